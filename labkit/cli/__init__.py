"""The ``labkit`` command. Each sub-command lives in its own module ``labkit.cli.<name>``
exposing ``register(subparsers)``, which adds its parser and sets ``func(args) -> int``.

Expected faults (:class:`labkit.errors.LabkitError`) end as one line on stderr and exit 2.
Ctrl-C ends as one line naming what the command stops (motors only for commands that drive
them, :data:`MOTOR_COMMANDS`), exit 130. A reader that closes the pipe (``labkit ... | head``)
ends the command quietly with exit 141, as a shell reports SIGPIPE, not a BrokenPipeError traceback.
``--json -`` (labkit.cli.output) keeps stdout for the JSON document alone.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from labkit import __version__
from labkit.cli.summaries import COMMAND_SUMMARIES
from labkit.errors import LabkitError

COMMANDS = list(COMMAND_SUMMARIES)  # the order of `labkit --help`


def build_parser(only: str | None = None, summaries_only: bool = False) -> argparse.ArgumentParser:
    """The full parser, or (``only``) one with just that command: importing every command
    module costs seconds (numba, matplotlib, rerun), so a run imports only its own.
    ``summaries_only``: every command as a name and its one line (:mod:`labkit.cli.summaries`)
    without its options, what ``labkit`` and ``labkit --help`` print; no command module is
    imported."""
    parser = argparse.ArgumentParser(
        prog="labkit", description="labkit: measure, replay and model PFR / MBS rigs"
    )
    parser.add_argument("--version", action="version", version=f"labkit {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS if only is None else [only]:
        if summaries_only:
            sub.add_parser(name, help=COMMAND_SUMMARIES[name])
            continue
        module_name = f"labkit.cli.{name}"
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name == module_name:  # command not built yet
                continue
            raise
        module.register(sub)
    return parser


#: commands that open a rig and drive its motors: only their Ctrl-C line speaks of motors
MOTOR_COMMANDS = frozenset({"run", "demo", "bench", "twin", "replay"})
#: exit status after the reader closed stdout (128 + SIGPIPE, what a shell shows)
EXIT_BROKEN_PIPE = 141


def main(argv: list[str] | None = None) -> int:
    """Run one command; ``argv`` None means the program's own (``labkit ...``, ``python -m labkit``),
    which then also ends quickly (:func:`end_quickly`) and quietly when its reader goes away."""
    if argv is None:
        _escape_unencodable()
        try:
            code = _run(sys.argv[1:])
            sys.stdout.flush()  # a closed pipe shows here, not in the interpreter's exit
            return code
        except BrokenPipeError:
            _silence_stdout()
            return EXIT_BROKEN_PIPE
        finally:
            end_quickly()
    return _run(list(argv))


def _escape_unencodable() -> None:
    """Print a character the terminal cannot take (a lone surrogate: a Latin-1 byte in a
    folder name or ``--notes``) as an escape such as ``\\udce9``, not a UnicodeEncodeError."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.reconfigure(errors="backslashreplace")  # type: ignore[union-attr]
        except (AttributeError, ValueError):  # replaced by a caller, or closed
            pass


def _silence_stdout() -> None:
    """After a BrokenPipeError: point stdout at /dev/null so the interpreter's final flush of
    what is still buffered raises nothing (the recipe of the Python docs, "Note on SIGPIPE")."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # stdout replaced or closed: nothing to flush
        pass


def end_quickly() -> None:
    """Let the interpreter's exit skip its garbage-collector passes over every object loaded
    (with numpy, OpenCV and scipy about 50 ms of one core, measured with
    analysis/whole_command_bench.py): :func:`gc.freeze`. Objects are still freed by reference
    counting as the modules are cleared, atexit handlers and thread joins run as before; only a
    reference cycle left alive at exit is not collected (Python never promises that anyway).
    Called only for the program itself, never when ``main(argv)`` runs inside another process."""
    import gc

    gc.freeze()


def _run(argv: list[str]) -> int:
    only = argv[0] if argv and argv[0] in COMMANDS else None
    parser = build_parser(only, summaries_only=only is None)
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 1
    from labkit.cli.output import stdout_reserved_for_json, wants_json_stdout

    try:
        with stdout_reserved_for_json(wants_json_stdout(args)):
            return int(args.func(args) or 0)
    except LabkitError as exc:
        print(f"labkit {args.command}: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        stopped = "; motors commanded to zero" if args.command in MOTOR_COMMANDS else ""
        print(f"labkit {args.command}: interrupted{stopped}", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
