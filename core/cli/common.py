"""What every ``ease`` subcommand shares: its parser header, progress line and file listing."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Callable, Iterable


def subcommand(sub, name: str, func: Callable, help: str, description: str, **kwargs) -> argparse.ArgumentParser:
    """Add the subcommand ``name`` to ``sub``; ``func(args) -> exit code`` runs it."""
    p = sub.add_parser(name, help=help, description=description, **kwargs)
    p.set_defaults(func=func)
    return p


def add_quiet(p: argparse.ArgumentParser, what: str = "no progress line") -> None:
    p.add_argument("--quiet", action="store_true", help=what)


def console_progress(args):
    """The stderr progress line, or None with ``--quiet``."""
    from ..progress import ConsoleProgress

    return None if args.quiet else ConsoleProgress()


def print_files(paths: Iterable, prefix: str = "") -> None:
    """One written file a line, sorted as given."""
    for p in paths:
        print(f"{prefix}{Path(p)}")
