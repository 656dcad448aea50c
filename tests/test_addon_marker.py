"""Marker operator (ease_addon.marker_ops): the panel's width and sizes nest the scene's pattern with the
core's marker; the files land in the export folder and the marker shows as an image on a flat object."""

from __future__ import annotations

import json

import pytest

pytest.importorskip("spyrrow")

DESIGN = "top_sleeveless.json"  # cheapest template: two panels


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    return blender.reset(body=True, design=DESIGN, pattern=True)


def test_marker_operator(bpy_session, blender):
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    s.export_dir = str(bpy_session["tmp"] / "marker_export")
    s.marker_width_mm, s.marker_sizes, s.marker_seconds, s.marker_one_way = 1400.0, "", 3, True
    assert bpy.ops.ease.marker() == {"FINISHED"}
    out = bpy_session["tmp"] / "marker_export" / "marker"
    rep = json.loads((out / "marker.json").read_text())
    assert rep["width_mm"] == pytest.approx(1400.0) and rep["orientations_deg"] == [0.0]
    assert rep["pieces"] == len(json.loads(bpy.context.scene["ease_pattern_json"])["panels"])
    assert all(p["angle_deg"] == 0.0 for p in rep["placements"])
    assert {"marker.dxf", "marker.svg", "marker.pdf", "marker.png"} <= {p.name for p in out.iterdir()}
    assert "efficiency" in s.marker_status and f"{rep['efficiency_pct']:.1f}" in s.marker_status
    # the export's allowance rule (core.workflows.marker): the panel's seam and hem allowances, the hem kept
    widths = {round(s.export_allowance_cm * 10, 2), round(s.export_hem_cm * 10, 2)}
    assert len(widths) == 2 and any(len(w) == 2 for w in rep["allowance_mm"].values())
    assert all(set(w) <= widths for w in rep["allowance_mm"].values())
    # shown: the picture as an image, on a flat object as long and wide as the marker
    img = bpy.data.images["EASE Marker"]
    assert img.size[0] > 0 and img.size[1] > 0
    obj = [o for o in bpy.context.scene.objects if o.get("ease_role") == "marker"]
    assert len(obj) == 1
    dims = obj[0].dimensions
    assert dims[0] == pytest.approx(rep["length_mm"] / 1000, abs=1e-4)
    assert dims[1] == pytest.approx(1.4, abs=1e-4) and dims[2] == pytest.approx(0.0)
    # again: one marker object, the image reloaded in place
    s.marker_sizes = "bad:size"
    r = blender.run(bpy.ops.ease.marker)
    assert "ERROR" in r and "Sizes" in r["ERROR"]
    assert len([o for o in bpy.context.scene.objects if o.get("ease_role") == "marker"]) == 1


def test_marker_spread_pairs_as_the_cli(bpy_session):
    """The panel's Spread: pairs lays two plies face to face, as `ease marker --spread pairs` (core.workflows.marker)."""
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    s.export_dir = str(bpy_session["tmp"] / "marker_pairs")
    s.marker_width_mm, s.marker_sizes, s.marker_seconds, s.marker_one_way = 1400.0, "", 2, False
    s.marker_spread = "PAIRS"
    try:
        assert bpy.ops.ease.marker() == {"FINISHED"}
    finally:
        s.marker_spread = "SINGLE"
    rep = json.loads((bpy_session["tmp"] / "marker_pairs" / "marker" / "marker.json").read_text())
    assert rep["spread"] == "pairs" and rep["plies"] == 2 and rep["face_to_face"]
    names = {p["name"] for p in json.loads(bpy.context.scene["ease_pattern_json"])["panels"]}
    # one piece of each mirrored pair nested, the pair's other piece cut by the second ply; a piece that is
    # its own mirror image once for two garments (one garment here: once)
    paired = set(rep["face_to_face"].values()) - {"itself"}
    assert paired <= names and rep["pieces"] == len(names) - len(paired)


def test_marker_runs_in_the_background(bpy_session, addon):
    """Marker pressed in Blender's UI (a job, as Drape's): the nesting and the files in a worker,
    the scene and the folder as they were until it lands, then the picture and the status; Esc
    (Cancel) while it nests leaves the marker folder all old (written at once) and says so."""
    bpy = bpy_session["bpy"]
    jobs, marker_ops = addon("jobs"), addon("marker_ops")
    s = bpy.context.scene.ease
    s.export_dir = str(bpy_session["tmp"] / "marker_threaded")
    out = bpy_session["tmp"] / "marker_threaded" / "marker"
    s.marker_width_mm, s.marker_sizes, s.marker_seconds, s.marker_one_way = 1400.0, "", 1, True
    s.marker_status = ""
    jobs.SYNCHRONOUS = False
    try:
        job, said = marker_ops.start_marker(bpy.context)
        assert jobs.running(marker_ops.JOB) is job and job.thread is not None and not said
        assert s.job_status.startswith("updating: Marker") and s.marker_status == "" and not out.exists()
        jobs.wait()
        assert said and "efficiency" in s.marker_status and s.job_status == said[0]
        before = {p.name: p.read_bytes() for p in out.iterdir()}
        assert "marker.json" in before
        # cancelled while it nests: the folder as it was, the status says so
        s.marker_width_mm, s.marker_seconds = 1300.0, 5
        status = s.marker_status
        job, said = marker_ops.start_marker(bpy.context)
        assert jobs.cancel() == 1
        job.thread.join(120)
        jobs.poll()
        assert not said and s.marker_status == status
        assert {p.name: p.read_bytes() for p in out.iterdir()} == before
        assert s.job_status == f"Marker cancelled: nothing written ({out} as it was)"
        assert not addon("state").BUGS
    finally:
        jobs.wait()
        jobs.SYNCHRONOUS = True
