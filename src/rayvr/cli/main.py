"""The `rayvr` command: subcommands live in modules of this package, each with
`register(subparsers)` adding its parser and setting `func(args) -> int`."""
from __future__ import annotations

import argparse
import importlib
import sys

from ..errors import RayvrError

# Subcommand modules, in the order `rayvr --help` lists them.
COMMAND_MODULES = ["info", "render", "graph", "converge", "tune"]


def build_parser() -> argparse.ArgumentParser:
    """The `rayvr` parser with every subcommand of COMMAND_MODULES."""
    parser = argparse.ArgumentParser(prog="rayvr", description="Hybrid raster/ray-traced rendering for VR headsets.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(f"rayvr.cli.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the `rayvr` command; a RayvrError is printed to stderr (on one line unless it has
    several, as shader compile logs do) and gives exit code 2; Ctrl-C gives one line and 130
    (outputs are written atomically, so nothing half-written is left)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except RayvrError as exc:
        msg = " ".join(str(exc).split()) if "\n" not in str(exc).strip() else str(exc).strip()
        print(f"rayvr: error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"rayvr: interrupted; {args.command} wrote nothing", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
