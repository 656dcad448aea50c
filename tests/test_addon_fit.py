"""Fit operators (ease_addon.fit_ops): transfer to a size and adaptation to poses show their
figures; the add-on and the command line give the same pattern.json."""

from __future__ import annotations

import json

import pytest

DESIGN = "top_sleeveless.json"  # cheapest template: two panels


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """This module's starting scene."""
    return blender.reset(body=True, design=DESIGN)


def test_transfer_and_adapt_show_figures(bpy_session):
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    s.fit_size = "L"
    assert bpy.ops.ease.transfer_size() == {"FINISHED"}
    fig = json.loads(s.fit_json)
    assert fig["size"] == "L" and fig["transfer deviation mean %"] >= 0
    s.adapt_P1, s.adapt_P2, s.adapt_P3, s.adapt_T = True, False, False, False
    s.tolerance = 1.1
    assert bpy.ops.ease.adapt_poses() == {"FINISHED"}
    fig = json.loads(s.fit_json)
    keys = [k for k in fig if k.startswith("P1")]
    assert keys
    for k in keys:
        before, after = (float(x) for x in fig[k].split("/"))
        assert after <= before + 1e-6


def _canonical(text: str) -> str:
    """The add-on's stored pattern as ``save_pattern`` writes it (its number format, wall-clock
    seconds out of the report): reading is exact, so equal patterns give equal bytes."""
    from core.pattern.io import pattern_from_json, pattern_text

    return pattern_text(pattern_from_json(json.loads(text)))


@pytest.mark.parametrize(
    "mode, cli_args, panel",
    [
        ("pattern", [], {}),
        ("transfer", ["--size", "L"], {"fit_size": "L"}),
        ("adapt", ["--pose", "P1"], {"adapt_T": False, "adapt_P1": True, "adapt_P2": False, "adapt_P3": False}),
    ],
)
def test_addon_and_command_line_write_the_same_pattern(bpy_session, addon, tmp_path, mode, cli_args, panel):
    """One design through `ease pattern|transfer|adapt` and through the add-on's operators: the
    same pattern.json, byte for byte (the file keeps no wall-clock seconds)."""
    from core.cli import main
    from core.design.templates import template_path

    bpy = bpy_session["bpy"]
    assert main([mode, str(template_path("top_sleeveless")), "--out", str(tmp_path), "--quiet"] + cli_args) == 0
    s = bpy.context.scene.ease
    for key, value in panel.items():
        setattr(s, key, value)
    op = {
        "pattern": bpy.ops.ease.optimize_pattern,
        "transfer": bpy.ops.ease.transfer_size,
        "adapt": bpy.ops.ease.adapt_poses,
    }[mode]
    assert op() == {"FINISHED"}
    text = bpy.context.scene[addon("data").PATTERN_KEY]
    assert _canonical(text) == (tmp_path / "pattern.json").read_text()


@pytest.mark.parametrize("mode", ["transfer", "adapt"])
def test_transfer_and_adapt_run_in_the_background(bpy_session, addon, mode):
    """Transfer to Size and Adapt to Poses pressed in Blender's UI (their job, as Optimize's): the
    cut and the solve run in a worker, the operator returns with the scene as it was and the
    status "updating"; the pattern and the Fit panel's figures land in one pass, the same as in
    line; Esc (Cancel) leaves the scene as it was."""
    import numpy as np

    bpy = bpy_session["bpy"]
    jobs, data, pattern_job, fit_ops = addon("jobs"), addon("data"), addon("pattern_job"), addon("fit_ops")
    scene = bpy.context.scene
    s = scene.ease
    s.fit_size = "L"
    s.adapt_P1, s.adapt_P2, s.adapt_P3, s.adapt_T = True, False, False, False
    s.tolerance = 1.1
    op, start, label = {
        "transfer": (bpy.ops.ease.transfer_size, fit_ops.start_transfer, "Transfer to Size"),
        "adapt": (bpy.ops.ease.adapt_poses, fit_ops.start_adapt, "Adapt to Poses"),
    }[mode]
    assert op() == {"FINISHED"} and jobs.running() is None  # a script's call: in line
    want, want_fig = data.stored_pattern(scene), json.loads(s.fit_json)
    assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}  # another pattern stored meanwhile
    s.fit_json = ""
    text = scene[data.PATTERN_KEY]
    jobs.SYNCHRONOUS = False
    try:
        # the button's job (headless bpy has no window to invoke in): back at once, the job running
        job = start(bpy.context)
        assert jobs.running(pattern_job.PATTERN_JOB) is job and job.thread is not None
        assert s.job_status.startswith(f"updating: {label}")
        assert s.fit_json == "" and scene[data.PATTERN_KEY] == text  # nothing applied yet
        jobs.wait()
        got = data.stored_pattern(scene)
        assert json.loads(s.fit_json) == want_fig and s.job_status == ""
        assert [p.name for p in got.panels] == [p.name for p in want.panels]
        assert all(np.array_equal(a.uv, b.uv) for a, b in zip(got.panels, want.panels))
        # Esc: nothing applied
        assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
        s.fit_json = ""
        text = scene[data.PATTERN_KEY]
        job = start(bpy.context)
        assert jobs.cancel() == 1
        job.thread.join(120)
        jobs.poll()
        assert s.fit_json == "" and scene[data.PATTERN_KEY] == text and "cancelled" in s.job_status
        assert not addon("state").BUGS
    finally:
        jobs.wait()
        jobs.SYNCHRONOUS = True
