"""One grammar for what a command writes: ``--json PATH|-`` and "wrote FILE" lines.

``--json -`` means the JSON document alone on stdout: :func:`labkit.cli.main` sends every other
line of the command to stderr (:func:`stdout_reserved_for_json`), so ``labkit fit S --json - | jq``
always parses. Any other value is a file path, named on stderr once written
(:func:`announce_written`). Non-finite floats are written as ``null`` (strict JSON).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Iterator
from contextlib import contextmanager, redirect_stdout
from pathlib import Path
from typing import Any, TextIO

from labkit.errors import LabkitError

_json_stdout: list[TextIO] = []


def add_json_argument(p: argparse.ArgumentParser, what: str) -> None:
    """``--json PATH|-`` with the same help text on every command."""
    p.add_argument("--json", metavar="PATH|-",
                   help=f"write {what} as JSON to PATH; '-' prints it alone on stdout "
                   "(all other output then goes to stderr)")


def wants_json_stdout(args: argparse.Namespace) -> bool:
    return getattr(args, "json", None) == "-"


@contextmanager
def stdout_reserved_for_json(active: bool) -> Iterator[None]:
    """While ``active``: ``print()`` goes to stderr; :func:`write_json` with ``-`` keeps stdout."""
    if not active:
        yield
        return
    _json_stdout.append(sys.stdout)
    try:
        with redirect_stdout(sys.stderr):
            yield
    finally:
        _json_stdout.pop()


def strict(obj: Any) -> Any:
    """``obj`` with non-finite floats as None and tuples as lists (valid strict JSON)."""
    if isinstance(obj, dict):
        return {str(k): strict(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [strict(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def _fallback(x: Any) -> Any:
    if isinstance(x, Path):
        return str(x)
    try:
        value = float(x)
    except (TypeError, ValueError):
        return str(x)
    return value if math.isfinite(value) else None


def write_json(doc: Any, dest: str | Path | None, command: str) -> None:
    """Write ``doc`` to ``dest`` (``-``: stdout, alone; a path: the file, named on stderr)."""
    if dest is None or dest == "":
        return
    text = json.dumps(strict(doc), indent=2, default=_fallback, allow_nan=False) + "\n"
    if str(dest) == "-":
        out = _json_stdout[-1] if _json_stdout else sys.stdout
        out.write(text)
        out.flush()
        return
    path = Path(dest)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    except OSError as exc:
        raise LabkitError(f"--json: cannot write {path} ({exc.strerror or exc})") from None
    announce_written(path, command, "JSON")


def announce_written(path: str | Path, command: str, what: str = "") -> None:
    """One ``labkit CMD: wrote PATH`` line on stderr for every file a command writes."""
    kind = f" ({what})" if what else ""
    print(f"labkit {command}: wrote {path}{kind}", file=sys.stderr)


def kernel_cache_present() -> bool:
    """Whether numba's on-disk cache holds the simulator kernels (``labkit.sim.integrators``):
    in ``NUMBA_CACHE_DIR`` when that is set, else in the package's ``__pycache__``."""
    import importlib.util
    import os

    custom = os.environ.get("NUMBA_CACHE_DIR")
    if custom:
        folders = [Path(custom)]
    else:
        spec = importlib.util.find_spec("labkit.sim.integrators.splitting")
        if spec is None or spec.origin is None:
            return False
        folders = [Path(spec.origin).parent / "__pycache__"]
    return any(folder.is_dir() and any(folder.rglob("splitting.*.nbi")) for folder in folders)


def note_first_compile(command: str) -> None:
    """One line on stderr before the simulator kernels are compiled for the first time (about
    7-10 s of CPU per kind of scene, measured; numba caches them on disk, docs/reference/simulator.md)."""
    if not kernel_cache_present():
        print(f"labkit {command}: compiling simulator kernels once; cached afterwards "
              "(about 10 s per kind of scene; later runs start at once)", file=sys.stderr, flush=True)


def announce_rerun_file(spec: Any, command: str) -> None:
    """Name the recording that ``--rerun save:FILE`` wrote (nothing for spawn/connect)."""
    if getattr(spec, "mode", None) == "save" and Path(spec.target).exists():
        announce_written(spec.target, command, f"rerun recording; open with: rerun {spec.target}")
