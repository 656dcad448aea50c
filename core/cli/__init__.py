"""The ``ease`` command line: one subcommand per pipeline stage.

Each module here defines ``add_parser(subparsers)``, which adds its
subcommands and sets ``func`` (taking the parsed args, returning an exit
code). The modules parse and check options and print; the work is done by
:mod:`core.workflows` and the stage packages. Errors of the core
(:class:`core.errors.EaseError`) and of the system (:class:`OSError`: a file
that cannot be read or written) print as one clear line and exit with status
2. ``--out`` is checked before any work; an output folder is all-old or
all-new (:func:`core.fileio.output_dir`), and an interrupted command says
which output folders it did complete.
"""

from __future__ import annotations

import argparse
import sys

from .. import __version__
from ..errors import Cancelled, EaseError
from ..paths import default_warp_cache
from . import batch, bench, body, cut, demo, drape, export, marker, outfit, pattern, templates

# Order = order in --help = order of the data flow.
SUBCOMMANDS = (body, templates, cut, pattern, drape, outfit, export, marker, batch, bench)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ease",
        description="EASE: parametric garment design with explicit, local ease control.",
    )
    parser.add_argument("--version", action="version", version=f"ease {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in SUBCOMMANDS:
        module.add_parser(sub)
    demo.add_parser(sub, run=main)  # the demo runs every step as a user's `ease` would
    return parser


def main(argv=None) -> int:
    # before Warp is first imported: only the first run compiles the kernels
    default_warp_cache()
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 1
    from ..fileio import check_output, committed_outputs

    before = len(committed_outputs())
    try:
        if getattr(args, "out", None) is not None:
            # an output that cannot be written is refused before any work (`ease body` writes one file)
            check_output(args.out, folder=not (args.command == "body" and not getattr(args, "all", False)))
        return int(args.func(args) or 0)
    except EaseError as exc:
        print(f"ease {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a file the command reads or writes (disk full, permissions, ...)
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"ease {args.command}: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 2
    except (Cancelled, KeyboardInterrupt) as exc:
        # an output folder is all-old or all-new; say which ones this command completed
        done = committed_outputs()[before:]
        what = "cancelled" if isinstance(exc, Cancelled) else "interrupted"
        said = f"only {', '.join(map(str, done))} was written" if done else "nothing was written"
        print(f"ease {args.command}: {what}; {said}", file=sys.stderr)
        return 130


__all__ = ["build_parser", "main"]
