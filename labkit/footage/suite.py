"""The robustness suite: seeded, deterministic case specs over pattern kinds, loop counts, b,
arcs per frame, frame sizes, photos and videos, and stroboscope clips over body shape, rest
orientation, flashes per exposure, apparent frequency (both signs) and rolling shutter; each
labelled easy / medium / hard.

A :class:`CaseSpec` is small and frozen; :func:`labkit.footage.suite_build.build_shot` turns it
into a renderer shot (every other parameter drawn from its seed and difficulty), and
:func:`labkit.footage.suite_eval.render_case` renders it on demand into a cache folder.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import cycle

FAMILIES = ("circle", "ellipse", "epitrochoid", "hypotrochoid", "strobe")
DIFFICULTIES = ("easy", "medium", "hard")
SIZES = ((320, 240), (640, 480), (1280, 720), (1920, 1080))
ARCS = (0.1, 0.2, 0.35, 0.6, 1.0, 1.6, 3.0)


@dataclass(frozen=True)
class CaseSpec:
    """One case. Laser: ``family`` a pattern kind, ``loops``/``b`` for trochoids, ``arc_cycles``
    of the pattern per frame (a photo's exposure holds many cycles), ``source`` ``kinematic``
    (precession + nutation) or ``sim`` (the cone integrated by labkit.sim). Strobe: ``body``,
    ``rest_deg`` (0 vertical, 90 horizontal), ``flashes`` per exposure (0: the camera's short
    exposure is the strobe), ``apparent_cpf`` apparent cycles per frame (signed), ``harmonic``
    m, ``rolling`` shutter."""

    name: str
    family: str
    difficulty: str
    seed: int
    size: tuple[int, int]
    photo: bool = False
    loops: int | None = None
    b: float | None = None
    arc_cycles: float = 1.0
    source: str = "kinematic"
    body: str | None = None
    rest_deg: float = 0.0
    flashes: float = 1.0
    apparent_cpf: float = 0.0
    harmonic: int = 1
    rolling: bool = False

    @property
    def kind(self) -> str:
        return "photo" if self.photo else "video"


def _b_values(loops: int, kind: str) -> tuple[float, ...]:
    """From barely looped (loops appear for b > 1/|k|) to large."""
    k = loops if kind == "epitrochoid" else 1 - loops
    barely = 1.08 / abs(k)
    return (round(barely, 3), round(0.5 * (barely + 0.9), 3), 0.9)


def _laser_cases() -> list[CaseSpec]:
    cases: list[CaseSpec] = []
    diff = cycle(DIFFICULTIES)
    sizes = cycle(SIZES)
    arcs = cycle(ARCS)
    seed = 1000

    def add(family: str, n: int, **kw) -> None:
        nonlocal seed
        for i in range(n):
            seed += 1
            d, size = next(diff), next(sizes)
            photo = i % 4 == 3
            source = "sim" if family in ("circle", "ellipse") and i % 2 == 1 else "kinematic"
            extra = dict(kw)
            if "b_list" in extra:
                extra["b"] = extra.pop("b_list")[i % 3]
            name = f"{family}-{extra.get('loops', '')}{'-' if 'loops' in extra else ''}{i:02d}-{d}"
            arc = next(arcs) if d != "easy" else 1.0 + (i % 3) * 0.6
            cases.append(CaseSpec(name, family, d, seed, size, photo=photo, arc_cycles=arc,
                                  source=source, **extra))

    add("circle", 20)
    add("ellipse", 24)
    for loops in range(2, 8):
        add("epitrochoid", 8, loops=loops, b_list=_b_values(loops, "epitrochoid"))
    for loops in range(3, 8):
        add("hypotrochoid", 8, loops=loops, b_list=_b_values(loops, "hypotrochoid"))
    return cases


def _strobe_cases() -> list[CaseSpec]:
    cases = []
    bodies = ("cylinder", "cuboid")
    rests = (0.0, 90.0, 35.0, -60.0, 90.0, 0.0)
    flashes = (1.0, 2.0, 3.0, 0.0, 4.0, 6.0, 3.3, 1.0, 5.0)
    cpfs = (0.08, -0.06, 0.11, -0.13, 0.045, -0.09, 0.17)
    sizes = ((640, 480), (1280, 720), (320, 240), (1920, 1080))
    for i in range(72):
        d, j = DIFFICULTIES[i % 3], i // 3  # j counts within a difficulty: every level gets every value
        body, rest, fl = bodies[j % 2], rests[j % len(rests)], flashes[j % len(flashes)]
        cpf, size = cpfs[i % len(cpfs)], sizes[(j + j // 2) % len(sizes)]
        rolling = i % 4 in (1, 2)
        harmonic = 2 if i % 5 == 4 else 1
        if d == "easy":  # a lamp triggered by the camera: one flash per frame, upright, global shutter
            rest, fl, rolling, harmonic = 0.0, 1.0, False, 1
        cases.append(CaseSpec(f"strobe-{body}-{i:02d}-{d}", "strobe", d, 5000 + i, size, body=body,
                              rest_deg=rest, flashes=fl, apparent_cpf=cpf, harmonic=harmonic,
                              rolling=rolling))
    return cases + _simulated_strobe_cases()


def _simulated_strobe_cases() -> list[CaseSpec]:
    """Strobe clips whose body motion is integrated by labkit.sim (``source="sim"``): a cylinder or
    a square plate floator bound beneath a spinning rotator (footage.sim_swing)."""
    cases = []
    rests = (0.0, 90.0, -60.0, 35.0)
    flashes = (2.0, 0.0, 4.0, 3.3)
    cpfs = (0.07, -0.1, 0.12, -0.05)
    sizes = ((640, 480), (1280, 720), (1920, 1080), (320, 240))
    for i in range(12):
        d, j = DIFFICULTIES[i % 3], i // 3
        body, rest, fl = ("cylinder", "cuboid")[i % 2], rests[j], flashes[j]
        rolling, harmonic = i % 4 in (1, 2), 2 if i % 5 == 4 else 1
        if d == "easy":
            rest, fl, rolling, harmonic = 0.0, 1.0, False, 1
        cases.append(CaseSpec(f"strobe-sim-{body}-{i:02d}-{d}", "strobe", d, 6000 + i, sizes[(i + j) % 4],
                              source="sim", body=body, rest_deg=rest, flashes=fl, apparent_cpf=cpfs[j],
                              harmonic=harmonic, rolling=rolling))
    return cases


def suite_cases(only: str | None = None, difficulty: str | None = None,
                limit: int | None = None) -> list[CaseSpec]:
    """All cases (>= 200), interleaved across families so that a ``limit`` takes a mix; filter by
    family and difficulty."""
    groups: dict[str, list[CaseSpec]] = {f: [] for f in FAMILIES}
    for case in _laser_cases() + _strobe_cases():
        groups[case.family].append(case)
    order: list[CaseSpec] = []
    longest = max(len(g) for g in groups.values())
    for i in range(longest):
        for f in FAMILIES:
            if i < len(groups[f]):
                order.append(groups[f][i])
    if only:
        if only not in FAMILIES:
            raise ValueError(f"unknown family {only!r}; choose from {', '.join(FAMILIES)}")
        order = [c for c in order if c.family == only]
    if difficulty:
        if difficulty not in DIFFICULTIES:
            raise ValueError(f"unknown difficulty {difficulty!r}; choose from {', '.join(DIFFICULTIES)}")
        order = [c for c in order if c.difficulty == difficulty]
    return order[:limit] if limit else order
