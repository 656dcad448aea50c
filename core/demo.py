"""``ease demo``: the default designs on the default body, through every stage.

Runs the same subcommands a user would (so the demo exercises the real CLI
paths), writes everything under one folder and ends by listing the files it
wrote. Stages: body sizes and poses -> cut -> pattern, transfer, adaptation
-> drape -> export -> a Cycles render of the scene through the add-on's
scripted run.
"""
from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def _steps(out: Path, quick: bool):
    designs = REPO / "examples" / "designs"
    shirt = designs / "shirt_long_sleeve.json"
    teaser = designs / "teaser_shirt_pants.json"
    yield "body: five sizes, five poses", ["body", "--all", "--out", str(out / "body")]
    yield "cut: long-sleeve shirt", ["cut", str(shirt), "--out", str(out / "cut")]
    yield "pattern: teaser shirt + pants", ["pattern", str(teaser), "--out", str(out / "pattern")]
    yield "transfer: teaser to size XL", ["transfer", str(teaser), "--size", "XL", "--out", str(out / "transfer_XL")]
    yield "adapt: teaser to poses P1, P3", ["adapt", str(teaser), "--pose", "P1", "--pose", "P3",
                                            "--tolerance", "1.1", "--out", str(out / "adapt_P1_P3")]
    # --quick: a shorter frame limit (the drape report then says it stopped at the limit)
    frames = ["--frames", "40"] if quick else []
    yield "drape: teaser shirt + pants", ["drape", str(out / "pattern"), "--out", str(out / "drape"), *frames]
    yield "export: SVG, DXF, PDF, GLB, OBJ", ["export", str(out / "pattern"), "--format", "all",
                                             "--drape", str(out / "drape"), "--out", str(out / "export")]


def run_demo(out: Path, quick: bool = False, render: bool = True) -> int:
    from .cli import main as ease_main

    out = Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    started = time.time()
    steps = list(_steps(out, quick))
    total = len(steps) + (1 if render else 0)
    for i, (title, argv) in enumerate(steps, 1):
        print(f"[ease demo] step {i}/{total}: {title}", file=sys.stderr, flush=True)
        t0 = time.perf_counter()
        rc = ease_main(argv)
        if rc != 0:
            print(f"[ease demo] step {i} ({title}) failed with exit code {rc}", file=sys.stderr)
            return rc
        print(f"[ease demo]   done in {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)
    if render:
        i = total
        print(f"[ease demo] step {i}/{total}: Cycles render through the add-on", file=sys.stderr, flush=True)
        script = REPO / "examples" / "scripted_run.py"
        t0 = time.perf_counter()
        env = dict(os.environ)
        rc = subprocess.call([sys.executable, str(script),
                              str(REPO / "examples" / "designs" / "teaser_shirt_pants.json"),
                              str(out / "render")], env=env)
        if rc != 0:
            print(f"[ease demo] render failed with exit code {rc}", file=sys.stderr)
            return rc
        print(f"[ease demo]   done in {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)

    files = sorted(p for p in out.rglob("*") if p.is_file() and p.stat().st_mtime >= started - 1)
    print(f"\nEASE demo wrote {len(files)} files under {out}:")
    for p in files:
        print(f"  {p.relative_to(out)}  ({p.stat().st_size / 1024:.0f} KiB)")
    return 0


def _cmd(args) -> int:
    return run_demo(Path(args.out), quick=args.quick, render=not args.no_render)


def add_parser(sub) -> None:
    p = sub.add_parser(
        "demo",
        help="run the default designs on the default body through every stage",
        description="Run the demo: body sizes/poses, cut, pattern, transfer, adaptation, drape, "
                    "export and a Cycles render; lists the files written at the end.",
    )
    p.add_argument("--out", default=str(REPO / "out" / "demo"), help="output folder (default: out/demo)")
    p.add_argument("--quick", action="store_true", help="fewer drape frames (40 instead of settling)")
    p.add_argument("--no-render", action="store_true", help="skip the Cycles render step")
    p.set_defaults(func=_cmd)
