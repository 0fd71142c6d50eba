"""labkit fit --rerun save:FILE logs data, model curve and residuals per series."""

import csv

import numpy as np

from labkit.cli import main
from labkit.stream.readback import column, entity_paths

PAPER_CSV = "labkit/data/paper/fig6_18_spin_critical.csv"


def test_fig618_fit_streams_each_series(tmp_path, capsys):
    rrd = tmp_path / "fit.rrd"
    assert main(["fit", PAPER_CSV, "--model", "spin-critical", "--rerun", f"save:{rrd}"]) == 0
    with open(PAPER_CSV) as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    names = sorted({r["series"] for r in rows})
    assert len(names) == 2
    entities = entity_paths(rrd)
    for name in names:
        assert {f"/fit/{name}/data", f"/fit/{name}/model", f"/fit/{name}/residual",
                f"/fit/{name}/summary"} <= entities
        ticks, values = column(rrd, f"/fit/{name}/data", "Scalars:scalars", "x:rotor_rad_s")
        mine = sorted((round(float(r["rotor_rad_s"])), float(r["spin_rad_s"])) for r in rows
                      if r["series"] == name)
        assert ticks == [m[0] for m in mine]
        assert np.allclose([v[0] for v in values], [m[1] for m in mine])
