"""The rerun stream shows the overlay image; loops and symmetry of every pattern kind."""

import pytest

from labkit.cli import main
from labkit.vision.laser.analyse import symmetry_of
from labkit.vision.shared.curves import a_for_k, k_for


def test_rerun_stream_logs_the_overlay_of_the_fit_on_the_accumulated_trace(tmp_path, capsys):
    from rerun.chunk import RrdReader

    from labkit.stream.readback import entity_paths

    clip = tmp_path / "epi.avi"
    assert main(["synth", "laser", str(clip), "--pattern", "epitrochoid", "--loops", "4", "--b", "0.4",
                 "--level", "easy", "--size", "320x240", "--frames", "45", "--codec", "MJPG",
                 "--seed", "3"]) == 0
    rrd, png = tmp_path / "laser.rrd", tmp_path / "overlay.png"
    assert main(["analyse", "laser", str(clip), "--rerun", f"save:{rrd}", "--overlay", str(png)]) == 0
    out = capsys.readouterr().out
    assert "/video/overlay" in entity_paths(rrd)
    chunks = list(RrdReader(str(rrd)).stream().filter(content="/video/overlay", is_static=True))
    blobs = [v for c in chunks for v in c.to_record_batch().column("EncodedImage:blob").to_pylist()]
    assert len(blobs) == 1
    logged = bytes(blobs[0][0] if isinstance(blobs[0], list) and isinstance(blobs[0][0], list) else blobs[0])
    assert logged[:8] == b"\x89PNG\r\n\x1a\n" and logged == png.read_bytes()  # the same picture
    assert "loops 4 (main loop + 3 small), 3-fold symmetry" in out and "quality: result ok" in out


@pytest.mark.parametrize(("kind", "loops", "symmetry"), [
    ("epitrochoid", 2, 1), ("epitrochoid", 5, 4), ("epitrochoid", 7, 6),
    ("hypotrochoid", 3, 3), ("hypotrochoid", 4, 4), ("hypotrochoid", 7, 7),
    ("ellipse", 1, 2), ("circle", 1, None),
])
def test_symmetry_is_the_rotational_order_round_one_over_abs_a(kind, loops, symmetry):
    k = k_for(kind, loops)
    assert symmetry_of(kind, k) == symmetry
    if symmetry is not None:
        assert symmetry == round(1 / abs(a_for_k(k))) == abs(k - 1)
