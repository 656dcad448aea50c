"""The ``ease`` command line: one subcommand per pipeline stage.

Each stage module ``core.<stage>.cli`` defines ``add_parser(subparsers)``,
which adds its subcommand and sets ``func`` (taking the parsed args, returning
an exit code). Errors of the core (:class:`core.errors.EaseError`) print as one
clear line and exit with status 2; nothing half-written is left behind.
"""
from __future__ import annotations

import argparse
import importlib
import os
import sys
from pathlib import Path

from . import __version__
from .errors import Cancelled, EaseError

# Order = order in --help = order of the data flow.
STAGES = (
    "core.body.cli",
    "core.cut.cli",
    "core.pattern.cli",
    "core.drape.cli",
    "core.export.cli",
    "core.bench",
    "core.demo",
)


def _default_warp_cache() -> None:
    # Keep Warp's kernel cache in the project so only the first run compiles.
    if "WARP_CACHE_PATH" not in os.environ:
        root = Path(__file__).resolve().parent.parent
        os.environ["WARP_CACHE_PATH"] = str(root / ".cache" / "warp")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ease",
        description="EASE: parametric garment design with explicit, local ease control.",
    )
    parser.add_argument("--version", action="version", version=f"ease {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in STAGES:
        module = importlib.import_module(name)
        module.add_parser(sub)
    return parser


def main(argv=None) -> int:
    _default_warp_cache()
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 1
    try:
        return int(args.func(args) or 0)
    except EaseError as exc:
        print(f"ease {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except Cancelled:
        print(f"ease {args.command}: cancelled; nothing was written", file=sys.stderr)
        return 130
    except KeyboardInterrupt:
        print(f"ease {args.command}: interrupted; nothing was written", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
