"""The `rayvr` command: subcommands live in modules of this package, each with
`register(subparsers)` adding its parser and setting `func(args) -> int`.

Exit codes: 0 done, 1 a check found a problem (`rayvr check`), 2 bad input (a RayvrError,
printed on one line: the file, option or field and the fix), 130 interrupted (Ctrl-C; outputs
are written all at once at the end, so an interrupted command leaves none).
"""
from __future__ import annotations

import argparse
import importlib
import re
import sys
import warnings

from ..errors import OptionError, RayvrError, SceneWarning

# Subcommand modules, in the order `rayvr --help` lists them.
COMMAND_MODULES = ["info", "render", "graph", "converge", "tune", "check", "view"]
INTERRUPTED = 130   # 128 + SIGINT, as shells report it


class Parser(argparse.ArgumentParser):
    """argparse whose usage errors are OptionErrors: one line naming the option, exit code 2."""

    def error(self, message: str):
        wanted = re.match(r"argument (\S+): expected one argument$", message)
        if wanted:   # argparse took a value such as -1,1,1 for an option
            option = wanted.group(1).split("/")[-1]
            message += f"; a value that starts with '-' goes after '=' ({option}=-1,...)"
        raise OptionError(f"{self.prog}: {message} (see '{self.prog} --help')")


def build_parser() -> argparse.ArgumentParser:
    """The `rayvr` parser with every subcommand of COMMAND_MODULES."""
    parser = Parser(prog="rayvr", description="Hybrid raster/ray-traced rendering for VR headsets.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(f"rayvr.cli.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the `rayvr` command; a RayvrError is printed to stderr (on one line unless it has
    several, as shader compile logs do) and gives exit code 2; Ctrl-C prints one line and gives 130."""
    try:
        warnings.simplefilter("ignore", SceneWarning)   # the CLI prints scene warnings as one line each
        parser = build_parser()
        args = parser.parse_args(argv)
        if not getattr(args, "func", None):
            parser.print_help()
            return 2
        return int(args.func(args) or 0)
    except RayvrError as exc:
        msg = " ".join(str(exc).split()) if "\n" not in str(exc).strip() else str(exc).strip()
        print(f"rayvr: error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("rayvr: interrupted", file=sys.stderr)
        return INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
