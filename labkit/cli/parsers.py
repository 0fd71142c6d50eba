"""The one way a ``labkit`` sub-command makes its parser (light: argparse only)."""

from __future__ import annotations

import argparse


def command_parser(sub: argparse._SubParsersAction, name: str, help: str, doc: str | None
                   ) -> argparse.ArgumentParser:
    """``sub.add_parser(name)`` with the one-line ``help`` and the module docstring ``doc`` as
    its description, printed as written (paragraphs and tables of the docstring kept)."""
    return sub.add_parser(name, help=help, description=doc,
                          formatter_class=argparse.RawDescriptionHelpFormatter)
