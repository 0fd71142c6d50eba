"""The first simulator run says it compiles kernels (numba cache absent), later runs do not."""

from __future__ import annotations

from pathlib import Path

from labkit.cli.output import kernel_cache_present, note_first_compile


def test_an_empty_cache_gets_the_note_and_a_filled_one_does_not(tmp_path: Path, monkeypatch, capsys) -> None:
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert not kernel_cache_present()
    note_first_compile("simulate")
    assert capsys.readouterr().err.startswith(
        "labkit simulate: compiling simulator kernels once; cached afterwards")
    # numba mirrors the source path under NUMBA_CACHE_DIR and writes one index (.nbi) per kernel
    index = tmp_path / "work" / "labkit" / "sim" / "integrators" / "splitting.run_rigid-281.py311.nbi"
    index.parent.mkdir(parents=True)
    index.write_bytes(b"")
    assert kernel_cache_present()
    note_first_compile("simulate")
    assert capsys.readouterr().err == ""
