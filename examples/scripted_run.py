"""EASE headless: design -> body -> pattern -> drape -> .blend + Cycles PNG + pattern files, through the add-on.

    blender -b --python examples/scripted_run.py -- DESIGN.json OUT_DIR [--frames N] [--solver pd] [--samples N] [--view ALL]
    python examples/scripted_run.py DESIGN.json OUT_DIR            # with the bpy module (the venv)

Writes into OUT_DIR: ``scene.blend`` (body, ease layer, design, pattern
pieces, draped garment, studio), ``render.png`` (Cycles, CPU, the add-on's
studio preset: 1080 x 1440, 32 samples, denoised; ``render_front.png``,
``render_three_quarter.png``, ``render_back.png`` with ``--view ALL``),
``pattern.json``, ``report.json`` (the key figures the panels show) and
``export/`` (the add-on's Export Pattern: SVG, DXF, PDF, and GLB/OBJ of the
draped garment).

This is an example script, not add-on code: it enables the add-on straight
from this checkout (a temporary extension repository pointing at it) and,
under a Blender binary whose Python lacks the core's dependencies, borrows
them from the checkout's ``.venv``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def _args(argv):
    if "--" in argv:
        argv = argv[argv.index("--") + 1 :]
    elif argv and argv[0].endswith(".py"):
        argv = argv[1:]
    ap = argparse.ArgumentParser(prog="scripted_run.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("design", help="design JSON (e.g. examples/designs/teaser_shirt_pants.json)")
    ap.add_argument("out", help="output folder")
    ap.add_argument("--frames", type=int, default=120, help="drape frame limit (default 120)")
    ap.add_argument(
        "--solver",
        default="default",
        choices=("default", "xpbd", "pd"),
        help="drape solver (the Drape panel's Solver; default: the core's default)",
    )
    ap.add_argument(
        "--samples",
        type=int,
        default=None,
        help="Cycles samples (default: the studio preset's, 32, adaptive and denoised)",
    )
    ap.add_argument(
        "--resolution", type=int, default=None, help="render size, %% of the studio's 1080 x 1440 frame (default 100)"
    )
    ap.add_argument(
        "--view",
        default="FRONT",
        choices=("FRONT", "THREE_QUARTER", "BACK", "PATTERN", "ALL"),
        help="studio camera (ALL: front, 3/4 and back, render_<view>.png each; default FRONT)",
    )
    ap.add_argument("--no-drape", action="store_true", help="skip the drape")
    ap.add_argument("--no-export", action="store_true", help="skip the pattern files (export/)")
    return ap.parse_args(argv)


def _bpy():
    if "bpy" not in sys.modules and "BLENDER_USER_RESOURCES" not in os.environ:
        # bpy module: keep the user's Blender configuration out of it
        os.environ["BLENDER_USER_RESOURCES"] = tempfile.mkdtemp(prefix="ease_blender_user_")
    os.environ.setdefault("WARP_CACHE_PATH", str(REPO / ".cache" / "warp"))
    import bpy

    try:
        import scipy  # noqa: F401
    except ImportError:  # a Blender binary: use the checkout's venv for the core's dependencies
        for sp in sorted((REPO / ".venv" / "lib").glob("python3*/site-packages")):
            sys.path.append(str(sp))
    return bpy


def enable_from_checkout(bpy) -> str:
    """Enable the add-on from this checkout; returns its module name."""
    repo_dir = tempfile.mkdtemp(prefix="ease_ext_repo_")
    link = os.path.join(repo_dir, "ease")
    try:
        os.symlink(REPO, link, target_is_directory=True)
    except OSError:  # no symlinks (Windows without rights): copy the package
        import shutil

        shutil.copytree(
            REPO,
            link,
            ignore=shutil.ignore_patterns(".venv", ".cache", ".git", "tests", "benchmarks", "build", "dist", "out"),
        )
    repo = bpy.context.preferences.extensions.repos.new(
        name="EASE checkout", module="ease_checkout", custom_directory=repo_dir, source="USER"
    )
    module = f"bl_ext.{repo.module}.ease"
    if bpy.ops.preferences.addon_enable(module=module) != {"FINISHED"}:
        raise SystemExit(f"could not enable {module}")
    return module


def _op(bpy, name, **kw):
    t0 = time.perf_counter()
    op = getattr(bpy.ops.ease, name)
    r = op(**kw)
    if r != {"FINISHED"}:
        raise SystemExit(f"ease.{name} failed: {r}")
    print(f"[scripted_run] {name}: {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)


def run(
    design: str,
    out: str,
    frames: int = 120,
    samples: int | None = None,
    resolution: int | None = None,
    drape: bool = True,
    export: bool = True,
    view: str = "FRONT",
    solver: str = "default",
) -> dict:
    bpy = _bpy()
    module = enable_from_checkout(bpy)
    out = Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    s = scene.ease
    _op(bpy, "add_body", source="DEFAULT")
    _op(bpy, "load_design_file", filepath=str(Path(design).resolve()))
    _op(bpy, "optimize_pattern")
    if drape:
        s.drape_frames, s.drape_solver = frames, solver
        _op(bpy, "drape")
    if samples is not None:
        s.render_samples = samples
    if resolution is not None:
        s.render_resolution = resolution
    s.render_view = view
    _op(bpy, "studio_setup")
    blend = out / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    s = bpy.context.scene.ease
    s.render_path = str(out / "render.png")
    _op(bpy, "render")
    core_io = sys.modules[module + ".core.pattern.io"]
    fileio = sys.modules[module + ".core.fileio"]
    addon_data = sys.modules[module + ".ease_addon.data"]
    core_io.save_pattern(addon_data.stored_pattern(bpy.context.scene), out)
    renders = [f"render_{v}.png" for v in ("front", "three_quarter", "back")] if view == "ALL" else ["render.png"]
    files = ["scene.blend", *renders, "pattern.json"]
    if export:
        s.export_dir = str(out / "export")
        s.export_svg = s.export_dxf = s.export_pdf = True
        s.export_glb = s.export_obj = drape
        _op(bpy, "export_pattern")
        files += sorted(f"export/{p.name}" for p in (out / "export").iterdir())
    report = {
        "design": str(design),
        "pattern": json.loads(s.pattern_json or "{}"),
        "drape": json.loads(s.drape_json or "{}"),
        "files": files,
    }
    fileio.write_json(out / "report.json", report)
    return report


def main(argv=None) -> int:
    args = _args(sys.argv if argv is None else argv)
    rep = run(
        args.design,
        args.out,
        args.frames,
        args.samples,
        args.resolution,
        not args.no_drape,
        not args.no_export,
        args.view,
        args.solver,
    )
    print(json.dumps(rep, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
