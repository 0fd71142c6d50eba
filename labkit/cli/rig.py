"""``labkit rig new KIND FILE``: write a commented rig-file template for real hardware.

KIND is ``balance`` (Fig. 5.25: rotor over a balance, ``speed-sweep``) or ``spin-critical``
(Fig. 6.18: two tachometers and a balance, ``spin-critical``). The templates ship inside the
package (``labkit/data/templates``), so this works after a plain ``pip install``. An existing
FILE is never overwritten. ``labkit rig check FILE`` reads a rig file and reports the first
problem as ``file:key: reason``.
"""

from __future__ import annotations

import argparse
import sys
from importlib import resources
from pathlib import Path

from labkit.cli.summaries import COMMAND_SUMMARIES
from labkit.errors import LabkitError


def template_names() -> list[str]:
    folder = resources.files("labkit") / "data" / "templates"
    return sorted(f.name[:-5] for f in folder.iterdir() if f.name.endswith(".toml"))


def template_text(kind: str) -> str:
    """The template for ``kind``; LabkitError naming the known kinds otherwise."""
    if kind not in template_names():
        raise LabkitError(f"no rig template {kind!r}; known: {', '.join(template_names())}")
    return (resources.files("labkit") / "data" / "templates" / f"{kind}.toml").read_text(encoding="utf-8")


def write_template(kind: str, out: str | Path) -> Path:
    """Write the ``kind`` template to ``out`` (never over an existing file) and return its path."""
    text = template_text(kind)
    path = Path(out)
    if path.suffix != ".toml":
        raise LabkitError(f"{path}: a rig file ends in .toml")
    try:
        with open(path, "x", encoding="utf-8") as f:  # "x": fails if the file exists
            f.write(text)
    except FileExistsError:
        raise LabkitError(f"{path} exists; not overwritten (choose another name or delete it)") from None
    except OSError as exc:
        raise LabkitError(f"{path}: cannot write ({exc.strerror or exc})") from None
    return path


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("rig", help=COMMAND_SUMMARIES["rig"],
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    actions = p.add_subparsers(dest="action", metavar="ACTION")
    new = actions.add_parser("new", help="write a commented template for real hardware")
    new.add_argument("kind", help="balance (Fig. 5.25) or spin-critical (Fig. 6.18)")
    new.add_argument("file", help="the rig file to write (.toml); never overwritten")
    new.set_defaults(func=run_new)
    check = actions.add_parser("check", help="read a rig file and report its first problem")
    check.add_argument("file", help="rig file or bundled rig name")
    check.set_defaults(func=run_check)
    p.set_defaults(func=lambda args: p.print_help() or 1)


def run_new(args: argparse.Namespace) -> int:
    path = write_template(args.kind, args.file)
    print(f"labkit rig: wrote {path} (template {args.kind})", file=sys.stderr)
    print(f"next: fill in its ports and magnets, then  labkit run {path} "
          f"{'speed-sweep' if args.kind == 'balance' else 'spin-critical'} --dry-run")
    return 0


def run_check(args: argparse.Namespace) -> int:
    from labkit.rig import load_rig

    rig = load_rig(args.file)
    print(f"{args.file}: rig {rig.name!r} is valid ({len(rig.devices)} devices: {', '.join(rig.devices)})")
    return 0
