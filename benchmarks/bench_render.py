"""Render benchmark: the add-on's studio preset, the time of a Cycles render per view.

``run(out_dir, quick=False) -> dict`` writes ``render.md`` and ``render.json``.

The teaser (shirt and pants) draped on the default body through the add-on
(examples/scripted_run.py's steps, in a subprocess with bpy), then Studio Preset
and Render PNG for the front, three-quarter and back views at the preset's
defaults: 1080 x 1440, 32 samples, adaptive sampling, OpenImageDenoise
(``quick``: 34 %, 367 x 489). Cycles runs on the GPU that Blender's
preferences enable, else the CPU: the table says which device (and, on the
CPU, whether Cycles sees any GPU at all), the CPU's
thread count and the process's CPU seconds beside the wall seconds (on a
machine shared with other jobs the wall time grows, the CPU time much less).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
DESIGN = "teaser_shirt_pants"

SCRIPT = r"""
import json, os, resource, sys, time
sys.path.insert(0, os.path.join(sys.argv[1], "examples"))
import scripted_run as sr
bpy = sr._bpy()
sr.enable_from_checkout(bpy)
design, out, pct = sys.argv[2], sys.argv[3], int(sys.argv[4])
bpy.ops.wm.read_homefile(use_empty=True)
s = bpy.context.scene.ease
for op, kw in (("add_body", {"source": "DEFAULT"}), ("load_design_file", {"filepath": design}),
               ("optimize_pattern", {})):
    assert getattr(bpy.ops.ease, op)(**kw) == {"FINISHED"}, op
s.drape_frames = 120
assert bpy.ops.ease.drape() == {"FINISHED"}
s.render_resolution = pct
t = time.perf_counter(); bpy.ops.ease.studio_setup(); setup = time.perf_counter() - t
prefs = bpy.context.preferences.addons["cycles"].preferences
avail = []  # every GPU Cycles can see, enabled or not
for kind in ("OPTIX", "CUDA", "HIP", "ONEAPI", "METAL"):
    try:
        avail += [f"{d.name} ({kind})" for d in prefs.get_devices_for_type(kind) if d.type != "CPU"]
    except Exception:
        pass
rows = []
for view in ("FRONT", "THREE_QUARTER", "BACK"):
    s.render_view, s.render_path = view, os.path.join(out, f"{view.lower()}.png")
    c0 = resource.getrusage(resource.RUSAGE_SELF); t = time.perf_counter()
    assert bpy.ops.ease.render() == {"FINISHED"}
    wall = time.perf_counter() - t; c1 = resource.getrusage(resource.RUSAGE_SELF)
    rows.append({"view": view, "wall_s": round(wall, 1),
                 "cpu_s": round(c1.ru_utime + c1.ru_stime - c0.ru_utime - c0.ru_stime, 1)})
sc = bpy.context.scene
print("RESULT " + json.dumps({"setup_s": round(setup, 2), "views": rows, "device": sc.cycles.device,
      "gpu": [d.name for d in getattr(prefs, "devices", []) if d.use and d.type != "CPU"], "gpus_available": avail,
      "threads": sc.render.threads, "samples": sc.cycles.samples,
      "size": [sc.render.resolution_x * pct // 100, sc.render.resolution_y * pct // 100]}))
"""


def run(out_dir, quick: bool = False) -> dict:
    from core.design.templates import template_path
    from core.fileio import write_json, write_text

    pct = 34 if quick else 100
    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / "bench_render_run.py"
        script.write_text(SCRIPT)
        env = dict(os.environ, WARP_CACHE_PATH=os.environ.get("WARP_CACHE_PATH", str(REPO / ".cache" / "warp")))
        p = subprocess.run(
            [sys.executable, str(script), str(REPO), str(template_path(DESIGN)), tmp, str(pct)],
            capture_output=True,
            text=True,
            env=env,
            timeout=7200,
        )
        line = next((ln for ln in p.stdout.splitlines() if ln.startswith("RESULT ")), None)
    if line is None:
        why = p.stderr.strip()[-2000:] or str(p.returncode)
        raise RuntimeError("the render benchmark's Blender run failed: " + why)
    res = dict(json.loads(line[len("RESULT ") :]), design=DESIGN, quick=quick, load_avg=os.getloadavg())
    out = Path(out_dir)
    write_json(out / "render.json", res)
    device = "GPU " + ", ".join(res["gpu"]) if res["device"] == "GPU" else f"CPU, {os.cpu_count()} cores"
    if res["device"] != "GPU":
        seen = res.get("gpus_available") or []
        device += (
            f" (GPUs Cycles sees but Blender's preferences do not enable: {', '.join(seen)})"
            if seen
            else " (no GPU on this machine: Cycles sees no CUDA, OptiX, HIP, oneAPI or Metal device)"
        )
    md = [
        f"# Render: the studio preset on {DESIGN}",
        "",
        f"{res['size'][0]} x {res['size'][1]}, {res['samples']} samples (adaptive, denoised), {device}; "
        f"Studio Preset {res['setup_s']} s. Load average at the end {tuple(round(x, 1) for x in res['load_avg'])} "
        f"(wall time grows on a shared machine). Regenerate: `./ease.sh bench --only render`"
        f"{' (this run: --quick)' if quick else ''}.",
        "",
        "| view | wall s | CPU s |",
        "|---|---|---|",
    ]
    md += [f"| {r['view'].lower().replace('_', ' ')} | {r['wall_s']} | {r['cpu_s']} |" for r in res["views"]]
    write_text(out / "render.md", "\n".join(md + [""]))
    return res
