"""Plausibility of a rig file's numbers (issue 27): unit slips refused by ``labkit rig check``
and by ``labkit run`` before anything opens, each as ``file:key: reason`` naming the slip; a
FIFO, a 60 000-part key, tachometer rates and control periods that would hang a run."""

from __future__ import annotations

import math
import os
import time
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.cli import main
from labkit.emulators.plant import reset_plants
from labkit.errors import RigFileError
from labkit.rig import load_rig, parse_rig
from labkit.rig.checks import MAX_KEY_PARTS, check_toml_shape, rate_problem

REPO = Path(__file__).resolve().parents[2]
FIG525 = REPO / "rigs" / "emulated-fig525.toml"
SHIPPED = sorted([*(REPO / "rigs").glob("*.toml"), *(REPO / "labkit" / "data" / "rigs").glob("*.toml"),
                  *(REPO / "labkit" / "data" / "templates").glob("*.toml"),
                  *(REPO / "recordings").rglob("rig.toml")])


@pytest.fixture(autouse=True)
def fresh_plants():
    reset_plants()
    yield
    reset_plants()


def rig_with(tmp_path: Path, old: str, new: str) -> Path:
    text = FIG525.read_text()
    assert old in text, old
    path = tmp_path / "rig.toml"
    path.write_text(text.replace(old, new, 1))
    return path


def cli(argv: list, capsys) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("path", SHIPPED, ids=[str(p.relative_to(REPO)) for p in SHIPPED])
def test_every_shipped_rig_template_and_recorded_rig_is_plausible(path, capsys):
    code, out, err = cli(["rig", "check", path], capsys)
    assert code == 0, err
    assert "is valid" in out


# (line of the shipped rig, its replacement, key in the error, words of the reason)
SLIPS = [
    ("gap_mm = 25", "gap_mm = 0.025", "geometry.gap_mm",
     ["looks like metres: 0.025 mm is smaller than the magnets", "12.5 mm", "did you mean gap_mm = 25?"]),
    ("gap_mm = 25", "gap_m = 25", "geometry.gap_m", ["no force", "did you mean gap_mm = 25?"]),
    ("gap_mm = 25", "gap_mm = 5", "geometry.gap_mm", ["5 mm is smaller than the magnets"]),
    ("full_speed_rpm = 23873", "full_speed_rpm = 400", "control.full_speed_rpm",
     ["below limits.max_speed_rpm (24000 RPM)", "looks like Hz", "400 Hz is 24000 RPM"]),
    ("full_speed_rpm = 23873", "full_speed_rpm = 2500", "control.full_speed_rpm",
     ["looks like rad/s: 2500 rad/s is 23873 RPM"]),
    ("mass_g = 5.9", "mass_g = 0.0059", "bodies.rotator.mass_g",
     ["density of 7.5", "looks like kilograms: did you mean mass_g = 5.9?"]),
    ("mass_g = 13.36", "mass_kg = 13.36", "bodies.floator.mass_kg",
     ["looks like grams: did you mean mass_kg = 0.01336?"]),
    ("dipole_moment_a_m2 = 0.93", "dipole_moment_a_m2 = 930", "bodies.rotator.dipole_moment_a_m2",
     ["B_r = m mu0 / V = 1488 T", "sintered NdFeB 1.17-1.49 T"]),
    ("dipole_moment_a_m2 = 2.0", "dipole_moment_a_m2 = 0.002", "bodies.floator.dipole_moment_a_m2",
     ["B_r = m mu0 / V = 0.001422 T"]),
    ("inertia_axial_kg_m2 = 3e-7", "inertia_axial_kg_m2 = 300", "bodies.floator.inertia_axial_kg_m2",
     ["times that of a uniform 15 mm sphere"]),
    ("dipole_moment_a_m2 = 0.93", 'dipole_moment_a_m2 = 0.5\ngrade = "N52"',
     "bodies.rotator.dipole_moment_a_m2",
     ["0.554 times B_r V / mu0 = 0.9031 A m^2", "grade N52"]),
    ("mass_g = 13.36", 'mass_g = 9\ngrade = "N42"', "bodies.floator.mass_g",
     ["9 g is 0.679 times the 13.25 g", "sintered NdFeB"]),
    ("tilt_deg = 5", "tilt_deg = 85", "bodies.rotator.tilt_deg",
     ["from the plane the dipole turns in, not from the spin axis", "did you mean 5 deg?"]),
    ("rate_hz=20", "rate_hz=-5", "devices.rotor_tach.port", ["rate_hz=-5: a rate must be in (0, 1000] Hz"]),
    ("rate_hz=20", "rate_hz=1e9", "devices.rotor_tach.port", ["rate_hz=1e9: a rate must be in"]),
    ("period_s = 0.05", "period_s = 1e-9", "control.period_s", ["below the floor of 1 ms"]),
    ("tach_timeout_s = 0.5", "tach_timeout_s = 0.5\nstatus_period_s = 0", "control.status_period_s",
     ["must be > 0"]),
    ('role=rotor_tach&rate_hz=20"', 'role=rotor_tach&rate_hz=20"\noptions = { rate_hz = 1e9 }',
     "devices.rotor_tach.options.rate_hz", ["a rate must be in (0, 1000] Hz, got 1000000000.0"]),
]


@pytest.mark.parametrize("old, new, key, words", SLIPS, ids=[s[1].split("\n")[-1] for s in SLIPS])
def test_rig_check_refuses_a_unit_slip_naming_key_and_slip(tmp_path, capsys, old, new, key, words):
    path = rig_with(tmp_path, old, new)
    code, out, err = cli(["rig", "check", path], capsys)
    assert code == 2 and out == "", (code, out, err)
    assert err.startswith(f"labkit rig: {path}:{key}: "), err
    assert err.count("\n") == 1 and "Traceback" not in err
    for word in words:
        assert word in err, (word, err)


@pytest.mark.parametrize("old, new, key", [
    ("gap_mm = 25", "gap_mm = 0.025", "geometry.gap_mm"),
    ("full_speed_rpm = 23873", "full_speed_rpm = 400", "control.full_speed_rpm"),
])
def test_run_refuses_before_anything_opens(tmp_path, capsys, old, new, key):
    # the ports are real device paths that do not exist: opening one would be another error
    path = rig_with(tmp_path, old, new)
    text = path.read_text()
    for dev in ("pololu_smc?seed=1", "labkit_tach?seed=2", "mtsics?seed=3"):
        start = text.index(f'"sim://{dev}')
        text = text[:start] + '"/dev/ttyLABKIT_NONE"' + text[text.index("\n", start):]
    path.write_text(text)
    sessions = tmp_path / "sessions"
    code, out, err = cli(["run", path, "speed-sweep", "--sessions", sessions, "--no-progress", "--yes"],
                         capsys)
    assert code == 2, err
    assert err.startswith(f"labkit run: {path}:{key}: "), err
    assert "ttyLABKIT_NONE" not in err and not sessions.exists()


def test_full_speed_just_under_the_limit_is_accepted_and_the_default_is_not_checked():
    text = FIG525.read_text()
    assert load_rig(FIG525).control.full_speed_rad_s < load_rig(FIG525).limits.max_speed_rad_s
    no_full_speed = "\n".join(ln for ln in text.splitlines() if not ln.startswith("full_speed_rpm"))
    rig = parse_rig(no_full_speed.replace("max_speed_rpm = 24000", "max_speed_rpm = 100000"), "r.toml")
    assert rig.control.full_speed_rad_s == pytest.approx(2500.0)


def test_a_fifo_is_refused_at_once(tmp_path, capsys):
    fifo = tmp_path / "rig.toml"
    os.mkfifo(fifo)
    start = time.monotonic()
    code, out, err = cli(["rig", "check", fifo], capsys)
    assert code == 2 and time.monotonic() - start < 5
    assert f"{fifo}:(file): is a FIFO (named pipe), not a regular file" in err


def test_a_key_of_60000_dotted_parts_is_refused_before_toml_reads_it(tmp_path, capsys):
    path = tmp_path / "rig.toml"
    path.write_text("[rig]\n" + "a" + ".b" * 59999 + " = 1\n")
    start = time.monotonic()
    code, out, err = cli(["rig", "check", path], capsys)
    assert code == 2 and time.monotonic() - start < 5
    assert f"{path}:(line 2): a key of 60000 dotted parts" in err


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet="ab.=[]# \"'\n", max_size=400))
def test_toml_shape_check_refuses_only_keys_of_many_parts(text):
    try:
        check_toml_shape(text, "f.toml")
    except RigFileError as exc:
        assert exc.key.startswith("(line ") and "dotted parts" in exc.reason
        line = text.splitlines()[int(exc.key[6:-1]) - 1]
        assert line.count(".") >= MAX_KEY_PARTS


@settings(max_examples=300, deadline=None)
@given(st.sampled_from(["rate_hz", "sample_hz", "rate", "timeout_s"]),
       st.one_of(st.floats(allow_nan=True), st.integers(-10**12, 10**12), st.text(max_size=8), st.booleans()))
def test_rate_problem_accepts_exactly_the_finite_rates_up_to_1_khz(name, value):
    problem = rate_problem(name, value)
    if not name.endswith("_hz"):
        assert problem is None
        return
    try:
        rate = float(value)
    except ValueError:
        assert problem is None
        return
    ok = not isinstance(value, bool) and math.isfinite(rate) and 0 < rate <= 1000
    assert (problem is None) == ok, (value, problem)


BODY_KEYS = st.fixed_dictionaries({}, optional={
    "diameter_mm": st.floats(0.01, 1e4), "length_mm": st.floats(0.01, 1e4),
    "mass_g": st.floats(1e-6, 1e6), "dipole_moment_a_m2": st.floats(1e-6, 1e4),
    "inertia_axial_kg_m2": st.floats(1e-15, 1.0), "tilt_deg": st.floats(-89, 89)})


@settings(max_examples=150, deadline=None)
@given(shape=st.sampled_from(["sphere", "cylinder", "cube", "block", "ring"]), body=BODY_KEYS,
       gap=st.one_of(st.none(), st.floats(1e-4, 1e5)))
def test_any_body_numbers_give_a_rig_or_a_file_key_reason(shape, body, gap):
    text = FIG525.read_text().split("[bodies.rotator]")[0]
    text += f'[bodies.rotator]\nshape = "{shape}"\n' + "".join(f"{k} = {v!r}\n" for k, v in body.items())
    text += "[limits]\nmax_speed_rpm = 24000\nmax_ramp_rpm_per_s = 6000\n"
    if gap is not None:
        text += f"[geometry]\ngap_mm = {gap!r}\n"
    try:
        parse_rig(text, "f.toml", check_protocols=False)
    except RigFileError as exc:
        assert exc.file == "f.toml" and exc.key.startswith(("bodies.rotator.", "geometry.gap")), exc
        assert exc.reason


def test_predict_reading_only_the_bodies_refuses_a_slip_in_them(tmp_path, capsys):
    path = rig_with(tmp_path, "mass_g = 5.9", "mass_g = 0.0059")
    code, out, err = cli(["predict", path, "--speed-rpm", "25000", "--no-verify"], capsys)
    assert code == 2 and out == ""
    assert err.startswith(f"labkit predict: {path}:bodies.rotator.mass_g: ") and "looks like kilograms" in err
