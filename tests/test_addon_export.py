"""Export operators (ease_addon.export_ops): the core's exporters with the panel's allowance,
the garment read from its object; the export settings saved with the design file."""

from __future__ import annotations

import json

import numpy as np
import pytest

DESIGN = "top_sleeveless.json"  # cheapest template: two panels


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """This module's starting scene."""
    return blender.reset(body=True, design=DESIGN, pattern=True, drape_frames=6)


def _obj_vertices(path):
    return np.array([[float(x) for x in l.split()[1:4]] for l in path.read_text().splitlines() if l.startswith("v ")])


def test_export_pattern(bpy_session, blender, addon):
    """Export calls the core's exporters with the design's allowance; the garment comes from its object."""
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    out = bpy_session["tmp"] / "export"
    s.export_dir = str(out)
    s.export_svg, s.export_dxf, s.export_pdf, s.export_glb, s.export_obj = True, True, False, True, True
    s.export_allowance_cm, s.export_hem_cm, s.export_notch_cm = 1.5, 3.0, 8.0
    assert bpy.ops.ease.export_pattern() == {"FINISHED"}
    names = {p.name for p in out.iterdir()}
    assert {"pattern.svg", "pattern_astm.dxf", "pattern_plain.dxf", "garment.glb", "garment.obj"} <= names
    assert "pattern_a4.pdf" not in names
    # the panel's settings are in the design now, and the files were made with them
    exp = json.loads(s.design_json)["materials"]["export"]
    assert exp == {"allowance": {"default": 0.015, "hem": 0.03}, "notch_spacing": 0.08}
    summary = json.loads((out / "export.json").read_text())
    assert summary["allowance_mm"]["default"] == pytest.approx(15) and summary["allowance_mm"]["hem"] == pytest.approx(
        30
    )
    # every 8 cm from either end of a seam (or in its middle); export.json rounds to 0.01 mm
    off = [
        min(abs(n - 80.0 * round(n / 80.0)), abs(v[-1] - n - 80.0 * round((v[-1] - n) / 80.0)), abs(n - v[-1] / 2))
        for p in summary["pieces"]
        for v in p["notches_mm"].values()
        for n in v[1:-1]
    ]
    assert off and max(off) < 0.011
    # the draped garment written is the garment object's shape
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    from scipy.spatial import cKDTree

    got = _obj_vertices(out / "garment.obj")
    v = blender.verts(garment).astype(np.float64)
    # the pattern's own vertices (a refined drape mesh, the Drape panel's default, has more: the
    # export writes the pattern's triangles where they were draped, as `ease export --drape` does)
    ids = np.empty(len(v), dtype=np.int32)
    garment.data.attributes["ease_vertex_id"].data.foreach_get("value", ids)
    want = v[ids < garment["ease_pattern_vertices"]]  # garment.obj is Z-up by default, like the body OBJs
    assert cKDTree(want).query(got)[0].max() < 1e-5 and cKDTree(got).query(want)[0].max() < 1e-5

    # a garment draped from another pattern is not exported as this pattern's
    data = addon("data")
    digest = garment["ease_pattern"]
    garment["ease_pattern"] = "an earlier pattern"
    s.export_glb, s.export_obj = True, False
    out2 = bpy_session["tmp"] / "export2"
    s.export_dir = str(out2)
    assert bpy.ops.ease.export_pattern() == {"FINISHED"}  # the 2D files, GLB skipped with a warning
    assert "pattern.svg" in {p.name for p in out2.iterdir()} and not (out2 / "garment.glb").exists()
    s.export_svg, s.export_dxf = False, False
    out3 = bpy_session["tmp"] / "export3"
    s.export_dir = str(out3)
    r = blender.run(bpy.ops.ease.export_pattern)
    assert "ERROR" in r and "drape the current pattern again" in r["ERROR"] and not out3.exists()
    assert data.garment_positions(bpy.context.scene)[0] is None
    garment["ease_pattern"] = digest
    s.export_svg, s.export_dxf, s.export_glb = True, True, False
    # a folder that cannot be made: the error in the status bar, the design keeps its old settings
    blocker = bpy_session["tmp"] / "a_file"
    blocker.write_text("not a folder")
    s.export_dir = str(blocker / "export")
    design_before = s.design_json
    s.export_hem_cm = 4.0
    r = blender.run(bpy.ops.ease.export_pattern)
    assert "ERROR" in r and "a_file" in r["ERROR"], r
    assert s.design_json == design_before
    s.export_hem_cm = 3.0
    s.export_dir = str(out)


def test_paint_mode_design_file_save_and_recut(bpy_session, blender):
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    assert bpy.ops.ease.paint_ease() == {"FINISHED"}
    assert bpy.context.object == s.body and bpy.context.object.mode == "VERTEX_PAINT"
    assert s.body.data.color_attributes.active_color.name == "ease"
    bpy.ops.object.mode_set(mode="OBJECT")
    path = bpy_session["tmp"] / "saved_design.json"
    assert bpy.ops.ease.save_design(filepath=str(path)) == {"FINISHED"}
    saved = json.loads(path.read_text())
    assert saved == json.loads(s.design_json)
    # the seam allowance set at export time is part of the design file, and comes back with it
    panel = (s.export_allowance_cm, s.export_hem_cm, s.export_notch_cm)
    exp = saved["materials"]["export"]
    assert (exp["allowance"]["default"], exp["allowance"]["hem"], exp["notch_spacing"]) == pytest.approx(
        tuple(v / 100 for v in panel)
    )
    assert panel != pytest.approx((1.0, 2.0, 10.0))
    s.design_json = ""
    s.export_allowance_cm, s.export_hem_cm, s.export_notch_cm = 1.0, 2.0, 10.0
    assert bpy.ops.ease.load_design_file(filepath=str(path)) == {"FINISHED"}
    assert json.loads(s.design_json)["name"] == saved["name"]
    assert (s.export_allowance_cm, s.export_hem_cm, s.export_notch_cm) == pytest.approx(panel)
    item = s.design_params[0]
    s.live_recut = False
    item.value = item.value  # no live re-cut while switched off
    assert bpy.ops.ease.recut() == {"FINISHED"}
    r = blender.run(bpy.ops.ease.load_design_file, filepath=str(bpy_session["tmp"] / "missing.json"))
    assert "ERROR" in r and "missing.json" in r["ERROR"]


def test_print_every_piece_reaches_the_tiled_pdf(bpy_session):
    """The panel's *Print every piece* decides whether the tiled PDFs print the top's symmetric front and
    back as halves on the fold (the default) or whole."""
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    saved = (s.export_svg, s.export_dxf, s.export_pdf, s.export_glb, s.export_obj, s.export_dir)
    plans = {}
    try:
        s.export_svg, s.export_dxf, s.export_pdf, s.export_glb, s.export_obj = False, False, True, False, False
        for every in (False, True):
            s.export_print_all = every
            out = bpy_session["tmp"] / f"export_print_all_{every}"
            s.export_dir = str(out)
            assert bpy.ops.ease.export_pattern() == {"FINISHED"}
            plans[every] = json.loads((out / "export.json").read_text())["pdf"]["a4"]
    finally:
        s.export_print_all = False
        s.export_svg, s.export_dxf, s.export_pdf, s.export_glb, s.export_obj, s.export_dir = saved
    assert {p["cut"] for p in plans[False]["pieces"]} == {"on fold (half printed)"}
    assert {p["cut"] for p in plans[True]["pieces"]} == {"as printed"}
    assert plans[True]["pages"] > plans[False]["pages"]


def test_export_runs_in_the_background(bpy_session, addon):
    """Export Pattern pressed in Blender's UI (a job, as Drape's): the files are rendered and written
    in a worker, the scene and the folder as they were until it lands; Esc (Cancel) before the
    files are written leaves the folder all old (the core writes it at once) and says so."""
    bpy = bpy_session["bpy"]
    jobs, export_ops = addon("jobs"), addon("export_ops")
    s = bpy.context.scene.ease
    out = bpy_session["tmp"] / "export_threaded"
    s.export_dir = str(out)
    s.export_svg, s.export_dxf, s.export_pdf, s.export_glb, s.export_obj = True, False, False, False, False
    s.export_allowance_cm = 1.0
    assert bpy.ops.ease.export_pattern() == {"FINISHED"}  # a script's call: in line
    old = (out / "pattern.svg").read_bytes()
    s.export_allowance_cm = 2.0  # another allowance: other files
    design = s.design_json
    jobs.SYNCHRONOUS = False
    try:
        job, said = export_ops.start_export(bpy.context)
        assert jobs.running(export_ops.JOB) is job and job.thread is not None and not said
        assert s.job_status.startswith("updating: Export Pattern") and s.design_json == design
        jobs.wait()
        assert said and said[0].startswith("exported") and s.job_status == said[0]
        new = (out / "pattern.svg").read_bytes()
        assert new != old and json.loads(s.design_json)["materials"]["export"]["allowance"]["default"] == 0.02
        # cancelled while it renders: nothing written, the scene as it was
        s.export_allowance_cm = 3.0
        design = s.design_json
        job, said = export_ops.start_export(bpy.context)
        assert jobs.cancel() == 1  # (the worker stops at its next report, long before the writing)
        job.thread.join(120)
        jobs.poll()
        assert not said and (out / "pattern.svg").read_bytes() == new and s.design_json == design
        assert s.job_status == f"Export Pattern cancelled: nothing written ({out} as it was)"
        assert not addon("state").BUGS
    finally:
        jobs.wait()
        jobs.SYNCHRONOUS = True
