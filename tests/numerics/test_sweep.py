"""Sweeps: resume from partial results, identical verdicts on a Dask LocalCluster, bad scheduler."""

from __future__ import annotations

import pytest

from labkit.numerics import stability_map
from labkit.numerics.sweep import SweepError, load_store, run_sweep

CYCLES = 20


@pytest.fixture(scope="module")
def points():
    return stability_map.table5_3_rows()[10:22]  # rows 11-22: stable and unstable ones


@pytest.fixture(scope="module")
def complete(points, tmp_path_factory):
    store = tmp_path_factory.mktemp("sweep") / "all.jsonl"
    res = run_sweep(points, stability_map.Evaluator(CYCLES), store=store, chunk=4, progress=False)
    return res, store


def _verdicts(results):
    return [(r["row"], r["verdict"], r["max_deviation_rad"]) for r in results]


def test_a_sweep_gives_both_verdicts(complete):
    res, _ = complete
    assert res.computed == 12 and res.reused == 0
    assert {r["verdict"] for r in res.results} == {"stable", "unstable"}
    # row 12 (tau_S / tau_C = 0.55, far above Eq. 5.46's 0.221) keeps its cone
    assert next(r for r in res.results if r["row"] == 12)["verdict"] == "stable"


def test_interrupted_sweep_resumes_from_its_partial_results(points, complete, tmp_path):
    res_all, _ = complete
    store = tmp_path / "partial.jsonl"
    first = run_sweep(points, stability_map.Evaluator(CYCLES), store=store, chunk=4, progress=False, limit=5)
    assert first.computed == 5 and len(first.results) == 5
    with store.open("a") as fh:
        fh.write('{"key": "torn-wri')  # a write cut short by the interruption
    assert len(load_store(store)) == 5
    again = run_sweep(points, stability_map.Evaluator(CYCLES), store=store, chunk=4, progress=False)
    assert again.reused == 5 and again.computed == 7
    assert _verdicts(again.results) == _verdicts(res_all.results)


def test_local_cluster_gives_identical_verdicts(points, complete):
    distributed = pytest.importorskip("distributed")
    res_all, _ = complete
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    ) as cluster:
        res = run_sweep(
            points,
            stability_map.Evaluator(CYCLES),
            chunk=3,
            scheduler=cluster.scheduler_address,
            progress=False,
        )
    assert res.computed == len(points)
    assert _verdicts(res.results) == _verdicts(res_all.results)


def test_a_scheduler_that_does_not_answer_is_a_clear_error(points):
    pytest.importorskip("distributed")
    with pytest.raises(SweepError, match=r"tcp://127.0.0.1:9 did not answer within 1 s"):
        run_sweep(
            points[:1],
            stability_map.Evaluator(CYCLES),
            scheduler="tcp://127.0.0.1:9",
            timeout_s=1,
            progress=False,
        )


def test_fig5_12_map_without_spin_follows_eq5_46_and_the_papers_upper_line():
    """k = -1 (no spin): tau_S = 0 is unstable (Eq. 5.46 needs tau_S/tau_C >= 0.08 here), 2 is
    stable, and 5.5 lies beyond Fig. 5.12's upper line tau_S + k w^2 I < -1.6e-3 (ratio 4.7)."""
    points = stability_map.fig5_12_points([-1.0], [0.0, 2.0, 5.5])
    res = run_sweep(points, stability_map.Evaluator(100), progress=False)
    assert [r["verdict"] for r in res.results] == ["unstable", "stable", "unstable"]
