"""examples/scripted_run.py with the bpy module: design -> pattern -> drape ->
.blend + Cycles PNG + pattern files, in a subprocess (its own Blender user folder)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
from export_synth import ALL_EXPORT_FILES

ROOT = Path(__file__).resolve().parent.parent


def test_scripted_run_writes_blend_render_and_pattern(tmp_path):
    out = tmp_path / "run"
    env = dict(os.environ, WARP_CACHE_PATH=str(ROOT / ".cache" / "warp"), BLENDER_USER_RESOURCES=str(tmp_path / "user"))
    r = subprocess.run(
        [
            sys.executable,
            str(ROOT / "examples" / "scripted_run.py"),
            str(ROOT / "examples" / "designs" / "top_sleeveless.json"),
            str(out),
            "--frames",
            "10",
            "--samples",
            "2",
            "--resolution",
            "10",
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    for name in ("scene.blend", "render.png", "pattern.json", "report.json"):
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    rep = json.loads((out / "report.json").read_text())
    assert rep["pattern"]["pieces"] == 2 and rep["drape"]["frames"] >= 1
    # the add-on's export: every format, the draped garment included
    want = set(ALL_EXPORT_FILES)
    assert {p.name for p in (out / "export").iterdir()} == want
    assert {f"export/{n}" for n in want} <= set(rep["files"])
    from core.pattern.io import load_pattern

    assert len(load_pattern(out / "pattern.json").panels) == 2
    # the PNG is a real picture (not one flat colour): decode it with matplotlib
    import matplotlib.image as mpimg

    img = mpimg.imread(out / "render.png")
    assert img.shape[0] > 50 and img.shape[1] > 50
    assert np.asarray(img)[..., :3].std() > 0.02


def test_arguments_under_blender_and_python():
    """`blender -b --python scripted_run.py -- DESIGN OUT` and `python scripted_run.py DESIGN OUT`
    give the script the same arguments (no Blender binary here to run the first for real)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("ease_scripted_run", ROOT / "examples" / "scripted_run.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    blender = mod._args(
        ["blender", "-b", "--python", "examples/scripted_run.py", "--", "d.json", "out", "--frames", "7", "--no-export"]
    )
    python = mod._args(["examples/scripted_run.py", "d.json", "out", "--frames", "7", "--no-export"])
    assert vars(blender) == vars(python)
    assert (blender.design, blender.out, blender.frames, blender.no_export, blender.no_drape) == (
        "d.json",
        "out",
        7,
        True,
        False,
    )
