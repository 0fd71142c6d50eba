"""The twin rig file carries the user's bodies and geometry verbatim (fuzzed values)."""

import tomllib

from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.rig import load_rig
from labkit.twin.rigtext import twin_rig_text

VALUES = st.one_of(st.floats(allow_nan=False), st.integers(-10**6, 10**6), st.booleans(),
                   st.text(st.characters(blacklist_categories=("Cs",)), max_size=20))


def toml_value(v) -> str:
    """Independent of the code under test: TOML literals written by hand."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + "".join(c if c.isprintable() and c not in '"\\' else f"\\U{ord(c):08X}" for c in v) + '"'
    return repr(v)


@settings(max_examples=60, deadline=None)
@given(bodies=st.dictionaries(st.sampled_from(["rotator", "floator"]),
                              st.dictionaries(st.from_regex(r"[a-z_]{1,12}", fullmatch=True), VALUES,
                                              max_size=5), max_size=2),
       gap=st.floats(1, 100))
def test_bodies_and_geometry_round_trip_through_the_twin_rig_text(tmp_path_factory, bodies, gap):
    path = tmp_path_factory.mktemp("rig") / "user.toml"
    lines = []
    for name, table in bodies.items():
        lines.append(f"[bodies.{name}]")
        lines += [f"{k} = {toml_value(v)}" for k, v in table.items()]
    lines += ["[geometry]", f"gap_mm = {gap!r}"]
    path.write_text("\n".join(lines) + "\n")
    user = tomllib.loads(path.read_text())
    twin = tomllib.loads(twin_rig_text(path, "fig525"))
    assert twin.get("bodies", {}) == user.get("bodies", {})
    assert twin["geometry"] == {"gap_mm": gap, "balance_under": "rotator"}
    assert twin["devices"]["balance"]["port"].startswith("sim://")


def test_shipped_rig_twin_loads_with_the_same_magnets(tmp_path):
    from pathlib import Path
    rig = Path(__file__).resolve().parents[2] / "rigs" / "emulated-fig618.toml"
    out = tmp_path / "twin.toml"
    out.write_text(twin_rig_text(rig, "fig525"))
    assert load_rig(out).bodies == load_rig(rig).bodies
