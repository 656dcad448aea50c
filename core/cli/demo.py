"""``ease demo``: the default designs on the default body, through every stage.

Runs the same subcommands a user would (so the demo exercises the real CLI
paths), writes everything under one folder and ends by listing the files it
wrote. Stages: body sizes and poses -> cut -> pattern, transfer, adaptation
-> drape -> export -> a Cycles render of the scene through the add-on's
scripted run. The designs are the shipped templates (package data), so the
demo runs from an installed wheel too; the render needs the add-on of a
source checkout (``examples/scripted_run.py`` in the current directory) and
is skipped with a note elsewhere.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable

from .common import subcommand

SCRIPTED_RUN = Path("examples") / "scripted_run.py"


def _steps(out: Path, quick: bool):
    from ..design.templates import template_path

    shirt = template_path("shirt_long_sleeve")
    teaser = template_path("teaser_shirt_pants")
    yield "body: five sizes, five poses", ["body", "--all", "--out", str(out / "body")]
    yield "cut: long-sleeve shirt", ["cut", str(shirt), "--out", str(out / "cut")]
    yield "pattern: teaser shirt + pants", ["pattern", str(teaser), "--out", str(out / "pattern")]
    yield "transfer: teaser to size XL", ["transfer", str(teaser), "--size", "XL", "--out", str(out / "transfer_XL")]
    yield (
        "adapt: teaser to poses P1, P3",
        ["adapt", str(teaser), "--pose", "P1", "--pose", "P3", "--tolerance", "1.1", "--out", str(out / "adapt_P1_P3")],
    )
    # --quick: a shorter frame limit (the drape report then says it stopped at the limit)
    frames = ["--frames", "40"] if quick else []
    yield "drape: teaser shirt + pants", ["drape", str(out / "pattern"), "--out", str(out / "drape"), *frames]
    yield (
        "export: SVG, DXF, PDF, GLB, OBJ",
        [
            "export",
            str(out / "pattern"),
            "--format",
            "all",
            "--drape",
            str(out / "drape"),
            "--out",
            str(out / "export"),
        ],
    )


def _say(text: str) -> None:
    print(f"[ease demo] {text}", file=sys.stderr, flush=True)


def render_argv(out: Path, quick: bool) -> list:
    """The scripted run's arguments: the teaser design into ``out/render`` with the add-on's studio
    preset (1080 x 1440, 32 samples, denoised); --quick: half the size and 16 samples."""
    from ..design.templates import template_path

    return [
        str(template_path("teaser_shirt_pants")),
        str(out / "render"),
        *(["--resolution", "50", "--samples", "16"] if quick else []),
    ]


def _render(out: Path, quick: bool = False) -> int:
    """The add-on's scripted run (Cycles render, the studio preset) of the teaser design; 0 when skipped."""
    script = SCRIPTED_RUN.resolve()
    if not script.is_file():
        _say(f"render skipped: it runs the add-on from a source checkout ({SCRIPTED_RUN} not found under {Path.cwd()})")
        return 0
    t0 = time.perf_counter()
    rc = subprocess.call([sys.executable, str(script), *render_argv(out, quick)], env=dict(os.environ))
    if rc != 0:
        print(f"[ease demo] render failed with exit code {rc}", file=sys.stderr)
        return rc
    _say(f"  done in {time.perf_counter() - t0:.1f} s")
    return 0


def run_demo(out: Path, run: Callable, quick: bool = False, render: bool = True) -> int:
    """Every demo step through ``run(argv) -> exit code`` (the ``ease`` entry point)."""
    out = Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    started = time.time()
    steps = list(_steps(out, quick))
    total = len(steps) + (1 if render else 0)
    for i, (title, argv) in enumerate(steps, 1):
        _say(f"step {i}/{total}: {title}")
        t0 = time.perf_counter()
        rc = run(argv)
        if rc != 0:
            print(f"[ease demo] step {i} ({title}) failed with exit code {rc}", file=sys.stderr)
            return rc
        _say(f"  done in {time.perf_counter() - t0:.1f} s")
    if render:
        _say(f"step {total}/{total}: Cycles render through the add-on")
        rc = _render(out, quick)
        if rc != 0:
            return rc

    files = sorted(p for p in out.rglob("*") if p.is_file() and p.stat().st_mtime >= started - 1)
    print(f"\nEASE demo wrote {len(files)} files under {out}:")
    for p in files:
        print(f"  {p.relative_to(out)}  ({p.stat().st_size / 1024:.0f} KiB)")
    return 0


def add_parser(sub, run: Callable) -> None:
    """``run(argv) -> exit code`` runs one demo step as the ``ease`` command would."""
    p = subcommand(
        sub,
        "demo",
        lambda args: run_demo(Path(args.out), run, quick=args.quick, render=not args.no_render),
        help="run the default designs on the default body through every stage",
        description="Run the demo: body sizes/poses, cut, pattern, transfer, adaptation, drape, "
        "export and a Cycles render (from a source checkout); lists the files written at the end.",
    )
    p.add_argument("--out", default=str(Path("out") / "demo"), help="output folder (default: out/demo)")
    p.add_argument(
        "--quick",
        action="store_true",
        help="fewer drape frames (40 instead of settling), the render at half size with 16 samples",
    )
    p.add_argument("--no-render", action="store_true", help="skip the Cycles render step")
