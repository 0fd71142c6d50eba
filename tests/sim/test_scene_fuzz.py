"""Fuzzing the scene reader: any mangled scene either loads or ends with a SceneError
(``file:key: reason``), never with another exception."""

from __future__ import annotations

import copy

from hypothesis import example, given, settings
from hypothesis import strategies as st

from labkit.sim import SceneError, scene_from_dict

from .conftest import bundled_dict

BASES = {name: bundled_dict(name) for name in ("conical_5_1", "fig5_13", "mbs_fig6_1", "pendulum_5_484")}

values = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-5, 5),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=5),
    st.lists(st.floats(-1e3, 1e3), max_size=4),
    st.lists(st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3), min_size=3, max_size=3),
    st.dictionaries(st.text(max_size=4), st.integers(), max_size=2),
)


def _paths(node, prefix=()):
    if isinstance(node, dict):
        for k, v in node.items():
            yield prefix + (k,)
            yield from _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield prefix + (i,)
            yield from _paths(v, prefix + (i,))


@settings(max_examples=150, deadline=None)
# found by CI: a drive of 1.34e154 rad/s overflowed omega**2 in the conical equilibrium (a traceback)
@example(base="fig5_13", pick=4096, value=1.3407807929942597e154, delete=False)
@given(base=st.sampled_from(sorted(BASES)), pick=st.integers(0, 10_000), value=values, delete=st.booleans())
def test_mangled_scenes_load_or_raise_scene_error(base, pick, value, delete):
    data = copy.deepcopy(BASES[base])
    paths = list(_paths(data))
    path = paths[pick % len(paths)]
    parent = data
    for key in path[:-1]:
        parent = parent[key]
    if delete and isinstance(parent, dict):
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    try:
        scene_from_dict(data, source="fuzz.toml")
    except SceneError as exc:
        assert str(exc).startswith("fuzz.toml")
