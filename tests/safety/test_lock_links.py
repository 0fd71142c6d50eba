"""The shared lock folder (issue 27): a lock file planted as a symbolic link is not followed, and
a LABKIT_LOCK_DIR the user chose keeps its mode."""

from __future__ import annotations

import os
import stat

import pytest

from labkit.errors import LabkitError
from labkit.io.port_lock import _lock_file, device_path, lock_device, unlock

pytestmark = pytest.mark.skipif(not hasattr(os, "O_NOFOLLOW"), reason="POSIX only")


@pytest.fixture
def pty_path():
    master, slave = os.openpty()
    try:
        yield os.ttyname(slave)
    finally:
        os.close(master)
        os.close(slave)


def test_a_planted_symlink_is_refused_and_its_target_untouched(tmp_path, monkeypatch, pty_path):
    locks = tmp_path / "locks"
    locks.mkdir(mode=0o700)
    monkeypatch.setenv("LABKIT_LOCK_DIR", str(locks))
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    _lock_file(device_path(pty_path)).symlink_to(victim)
    with pytest.raises(LabkitError, match="symbolic link there is refused"):
        lock_device(pty_path)
    assert victim.read_text() == "precious\n"


def test_a_chosen_lock_folder_keeps_its_mode(tmp_path, monkeypatch, pty_path):
    locks = tmp_path / "private"
    locks.mkdir(mode=0o700)
    monkeypatch.setenv("LABKIT_LOCK_DIR", str(locks))
    fd = lock_device(pty_path)
    try:
        assert fd is not None
        assert stat.S_IMODE(locks.stat().st_mode) == 0o700
    finally:
        unlock(fd)
