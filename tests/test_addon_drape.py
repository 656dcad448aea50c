"""Drape operators (ease_addon.drape_ops): the garment and its fit maps; the modal drape's
progress, Esc, a failing core, a pattern changed meanwhile, disabling mid-drape."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from core.drape import DrapeOptions
from core.workflows._drape import pattern_body

DESIGN = "top_sleeveless.json"  # cheapest template: two panels


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """This module's starting scene."""
    return blender.reset(body=True, design=DESIGN, pattern=True)


def test_drape_garment_and_fit_map(bpy_session, blender):
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    s.drape_frames = 15
    s.drape_device = "cuda"
    r = blender.run(bpy.ops.ease.drape)
    if "ERROR" in r:  # no GPU here: the core's message, and no garment made
        assert "cuda" in r["ERROR"].lower()
        assert not [o for o in bpy.data.objects if o.get("ease_role") == "garment"]
    s.drape_device = "cpu"
    assert bpy.ops.ease.drape() == {"FINISHED"}
    garments = [o for o in bpy.data.objects if o.get("ease_role") == "garment"]
    assert len(garments) == 1
    g = garments[0]
    assert len(g.data.polygons) > 100
    assert g.data.materials[0].name == "EASE Fabric cotton"  # the design's fabric preset
    assert g.data.color_attributes.get("fit_strain") is not None
    rep = json.loads(s.drape_json)
    assert rep["frames"] >= 1
    assert bpy.ops.ease.fitmap(mode="STRAIN") == {"FINISHED"}
    assert g.data.materials[0].name == "EASE Fit Map fit_strain"
    assert g.data.color_attributes.active_color.name == "fit_strain"
    assert bpy.ops.ease.fitmap(mode="GAP") == {"FINISHED"}
    assert g.data.materials[0].name == "EASE Fit Map fit_gap"
    assert g.data.color_attributes.active_color.name == "fit_gap"
    gap = np.empty(len(g.data.vertices), dtype=np.float32)
    g.data.attributes["fit_gap_value"].data.foreach_get("value", gap)
    assert np.all(gap >= 0) and gap.max() > 0.0
    # the two maps colour differently: they show different fields
    cols = {}
    for layer in ("fit_strain", "fit_gap"):
        c = np.empty(len(g.data.vertices) * 4, dtype=np.float32)
        g.data.color_attributes[layer].data.foreach_get("color", c)
        cols[layer] = c
    assert not np.allclose(cols["fit_strain"], cols["fit_gap"])
    assert bpy.ops.ease.fitmap(mode="NONE") == {"FINISHED"}
    assert g.data.materials[0].name == "EASE Fabric cotton"  # the design's fabric preset


@pytest.fixture
def threaded(addon):
    """The add-on's jobs in worker threads, as in Blender's window (headless they run in line)."""
    jobs = addon("jobs")
    before, jobs.SYNCHRONOUS = jobs.SYNCHRONOUS, False
    try:
        yield jobs
    finally:
        jobs.cancel()
        jobs.SYNCHRONOUS = before


def _landed(jobs, job) -> None:
    """Wait for ``job``'s worker, then the main thread's poll (what Blender's timer does)."""
    job.thread.join(120)
    assert not job.thread.is_alive()
    jobs.poll()


def test_drape_in_the_background_progress_and_esc(bpy_session, blender, addon, threaded):
    """The interactive drape (one job mechanism, :mod:`ease_addon.jobs`): the core runs in a
    worker thread, its progress per frame is the status line, the result lands on the main
    thread's poll, and Esc (cancel) leaves the scene as it was; a failing core, a pattern
    changed meanwhile and disabling the add-on mid-drape too."""
    bpy = bpy_session["bpy"]
    jobs = threaded
    s = bpy.context.scene.ease
    drape_ops = addon("drape_ops")
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    g_name, g_verts = garment.data.name, blender.verts(garment).copy()
    pattern = addon("data").stored_pattern(bpy.context.scene)
    body_v, body_f = pattern_body(pattern, "the test")
    # the Drape button's job (headless bpy has no window to invoke in): back at once, the job running
    job = drape_ops.start_drape(pattern, body_v, body_f, frames=400)
    assert jobs.running(drape_ops.JOB) is job and job.thread.is_alive()
    jobs.poll()
    assert s.job_status.startswith("updating: drape")
    from test_addon_honest import _draw  # the Drape panel shows the line and its Cancel button

    log = _draw(blender, "EASE_PT_drape")
    assert any(t.startswith("updating: drape") for t in log["labels"]) and "ease.cancel_jobs" in log["operators"]
    assert "drape_refine_mm" in log["props"]
    # Esc (the watcher's cancel): the worker stops at its next progress report, nothing is applied
    assert jobs.cancel() == 1
    _landed(jobs, job)
    assert job.cancelled and job.result is None and "cancelled" in s.drape_status
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment.data.name == g_name and np.array_equal(blender.verts(garment), g_verts)
    assert jobs.running() is None
    # the core fails mid-drape: its message in the status, the garment as it was
    from core.errors import EaseError

    real = drape_ops._compute

    def failing(*a, **k):
        a[4](0.3, "frame 12")
        raise EaseError("drape diverged at frame 12 (time step too large?)")

    drape_ops._compute = failing
    try:
        job = drape_ops.start_drape(pattern, body_v, body_f, frames=400)
        _landed(jobs, job)
    finally:
        drape_ops._compute = real
    assert "diverged at frame 12" in s.drape_status and "stopped" in s.drape_status
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment.data.name == g_name and np.array_equal(blender.verts(garment), g_verts)
    # a run to the end: a progress report per frame, shown in the status line, applied on the poll
    data = addon("data")
    key = addon("data").PATTERN_KEY
    digest = data.pattern_digest(bpy.context.scene[key])
    seen = []  # every progress report of the worker, as the status line shows it

    def recording(*a, **k):
        shown = a[4]

        def progress(fraction, message):
            shown(fraction, message)
            seen.append(jobs.running(drape_ops.JOB).status())

        return real(*a[:4], progress, *a[5:], **k)

    drape_ops._compute = recording
    try:
        job = drape_ops.start_drape(pattern, body_v, body_f, frames=4, digest=digest)
        job.thread.join(120)
    finally:
        drape_ops._compute = real
    frames = [re.match(r"updating: drape (\d+) % \(drape: frame (\d+),", t) for t in seen]
    frames = [(int(m[1]), int(m[2])) for m in frames if m]
    assert [k for _, k in frames] == [1, 2, 3, 4] and [f for f, _ in frames] == sorted({f for f, _ in frames}), seen
    assert job.fraction >= 0.9 and job.error is None
    jobs.poll()
    assert json.loads(s.drape_json)["frames"] <= 4 and s.drape_status.startswith("draped")
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment["ease_pattern"] == digest and data.garment_positions(bpy.context.scene)[0] is not None
    # the pattern changed while a drape ran: the garment says which pattern it fits, and
    # is not exported as the new one's
    job = drape_ops.start_drape(pattern, body_v, body_f, frames=2, digest=digest)
    text = bpy.context.scene[key]
    bpy.context.scene[key] = json.dumps(dict(json.loads(text), style="re-optimized meanwhile"))
    _landed(jobs, job)
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment["ease_pattern"] == digest
    pos, why = data.garment_positions(bpy.context.scene)
    assert pos is None and "another pattern" in why
    bpy.context.scene[key] = text
    assert data.garment_positions(bpy.context.scene)[0] is not None
    # disabling the add-on while a drape runs stops the worker (no thread left behind)
    module = bpy_session["module"]
    job = drape_ops.start_drape(pattern, body_v, body_f, frames=5000)
    assert job.thread.is_alive()
    bpy.ops.preferences.addon_disable(module=module)
    assert job.cancelled and not job.thread.is_alive() and job.result is None
    assert bpy.ops.preferences.addon_enable(module=module) == {"FINISHED"}
    assert bpy.context.scene.ease.drape_json  # the scene's EASE data is still there


def test_refined_drape_mesh(bpy_session, blender, addon, tmp_path):
    """Refine (mm): the garment is the drape's refined mesh (more vertices than the pattern's);
    its fit maps, ``ease_vertex_id`` (the pattern's ids, then the refinement's), fabric UVs
    (the pattern as draped, laid corner by corner) are the refined mesh's; the export reads the
    pattern's vertices back from it. The default is ``ease drape``'s; a bad value is refused.
    *Solver* reaches the core (default: the core's own) and the report names it."""
    from core.cli.drape import REFINE_EDGE

    bpy = bpy_session["bpy"]
    sc = bpy.context.scene
    s = sc.ease
    build, fabric, data = addon("build"), addon("render_fabric"), addon("data")
    assert s.bl_rna.properties["drape_refine_mm"].default == pytest.approx(1000 * REFINE_EDGE)
    pattern = data.stored_pattern(sc)
    n_pattern = max(int(np.max(p.vertex_ids)) for p in pattern.panels) + 1
    s.drape_frames, s.drape_device = 3, "cpu"
    s.drape_refine_mm = 0.0
    assert s.drape_solver == "default"
    assert bpy.ops.ease.drape() == {"FINISHED"}
    assert json.loads(s.drape_json)["solver"] == DrapeOptions().solver  # the core's default
    s.drape_solver = "pd"
    try:
        assert bpy.ops.ease.drape() == {"FINISHED"}
    finally:
        s.drape_solver = "default"
    assert json.loads(s.drape_json)["solver"] == "pd"
    # *Hold Pins* reaches the core too (off by default: an upper garment's collar lets go once grown)
    assert json.loads(s.drape_json)["hold_pins"] is False
    s.drape_hold_pins = True
    try:
        assert bpy.ops.ease.drape() == {"FINISHED"}
    finally:
        s.drape_hold_pins = False
    assert json.loads(s.drape_json)["hold_pins"] is True
    coarse = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    n_coarse = len(coarse.data.vertices)
    assert coarse[build.REFINE_EDGE] == 0.0 and build.drape_pattern(coarse, pattern) is pattern
    s.drape_refine_mm = 8.0
    assert bpy.ops.ease.drape() == {"FINISHED"}
    g = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    me = g.data
    n = len(me.vertices)
    assert n > n_coarse and g[build.REFINE_EDGE] == pytest.approx(0.008) and g[build.PATTERN_VERTICES] == n_pattern
    assert "mesh refined to 8 mm" in s.drape_status and len(me.polygons) == int(
        s.drape_status.split("-> ")[1].split()[0]
    )
    ids = np.empty(n, dtype=np.int32)
    me.attributes[data.VERTEX_ID].data.foreach_get("value", ids)
    assert len(np.unique(ids)) == n and set(range(n_pattern)) <= set(ids.tolist())  # the pattern's, then new ones
    for layer in ("fit_strain", "fit_gap"):
        values = np.empty(n, dtype=np.float32)
        me.attributes[layer + "_value"].data.foreach_get("value", values)
        assert np.all(np.isfinite(values)) and len(me.color_attributes[layer].data) == n
    # the pattern as draped: its triangles are the garment's faces (corner by corner, by id)
    mesh = build.drape_pattern(g, pattern)
    corners = np.concatenate([np.asarray(p.vertex_ids)[np.asarray(p.faces).ravel()] for p in mesh.panels])
    loop_vertex = np.empty(len(me.loops), dtype=np.int32)
    me.loops.foreach_get("vertex_index", loop_vertex)
    assert np.array_equal(ids[loop_vertex], corners)
    # the fabric's UVs on the refined mesh: each edge's UV length is its length in the pattern
    build._MESH_PATTERNS.clear()  # as after reopening the file: the core refines the same way again
    assert fabric.dress_garment(sc, g) is True
    uv = np.empty(len(me.loops) * 2, dtype=np.float32)
    me.uv_layers[addon("materials").FABRIC_UV].data.foreach_get("uv", uv)
    uv = uv.reshape(-1, 3, 2)
    flat = np.concatenate([np.asarray(p.uv)[np.asarray(p.faces)] for p in mesh.panels])
    got = np.linalg.norm(uv[:, 1] - uv[:, 0], axis=1)
    assert np.allclose(got, np.linalg.norm(flat[:, 1] - flat[:, 0], axis=1), atol=1e-6)
    # the export reads the pattern's own vertices back from the refined garment
    pos, why = data.garment_positions(sc)
    assert why is None and np.all(np.isfinite(pos[:n_pattern]))
    s.export_dir = str(tmp_path)
    for f in ("svg", "dxf", "pdf", "glb"):
        setattr(s, f"export_{f}", False)
    s.export_obj = True
    assert bpy.ops.ease.export_pattern() == {"FINISHED"}
    assert list(tmp_path.glob("*.obj"))
    # a refinement the core cannot make: refused in one line naming the setting, nothing draped
    s.drape_refine_mm = 0.5
    r = blender.run(bpy.ops.ease.drape)
    assert "ERROR" in r and "Refine (mm)" in r["ERROR"], r
    s.drape_refine_mm = 10.0


def test_pressed_drapes_in_the_background_scripts_in_line(addon):
    """jobs.Background: an operator pressed in the interface (invoke) runs its job in the
    background (start's default: a worker with a window, in line headless); one run from a
    script (execute) always in line, its result there when the call returns."""
    jobs = addon("jobs")

    class Op(jobs.Background):
        def execute(self, context):
            return self.job_sync()

    assert Op().execute(None) is True
    assert Op().invoke(None, None) is None
    assert issubclass(addon("drape_ops").EASE_OT_drape, jobs.Background)
    assert issubclass(addon("motion_ops").EASE_OT_drape_animation, jobs.Background)


def test_the_body_takes_the_draped_patterns_size(bpy_session, addon, threaded):
    """A drape lands on the body of the pattern it draped (its record goes with the job), not of
    the scene's pattern by then: a Transfer landing meanwhile does not move the body under the
    old garment."""
    bpy = bpy_session["bpy"]
    sc, jobs = bpy.context.scene, threaded
    data, drape_ops, state = addon("data"), addon("drape_ops"), addon("state")
    pattern = data.stored_pattern(sc)
    body = data.body_object(bpy.context)
    from core.body.instance import instance_shape

    model = state.body_model(data.body_spec(body)["model"])
    draped = pattern.body.get("shape")  # None: the body stays as it is
    draped = data.full_shape(model, instance_shape(model, draped) if draped else data.body_spec(body)["shape"])
    assert draped != data.full_shape(model, instance_shape(model, "XL"))
    text = sc[data.PATTERN_KEY]
    job = drape_ops.start_drape(pattern, *pattern_body(pattern, "the test"), frames=2)
    other = json.loads(text)
    other["body"] = dict(other["body"], shape="XL", size="XL")  # a transfer to XL lands meanwhile
    sc[data.PATTERN_KEY] = json.dumps(other)
    try:
        _landed(jobs, job)
        assert job.error is None and sc.ease.drape_status.startswith("draped")
        assert data.full_shape(model, data.body_spec(body)["shape"]) == draped
        assert "XL" not in sc.ease.drape_status
    finally:
        sc[data.PATTERN_KEY] = text


def test_a_pattern_without_its_body_is_not_draped(bpy_session, blender, addon):
    """Drape refuses a pattern with no body record in one line (the core's
    :func:`core.workflows._drape.pattern_body`), as ``ease drape`` does: no default body is assumed."""
    bpy = bpy_session["bpy"]
    sc, data = bpy.context.scene, addon("data")
    text = sc[data.PATTERN_KEY]
    sc[data.PATTERN_KEY] = json.dumps({k: v for k, v in json.loads(text).items() if k != "body"})
    garments = [o.name for o in bpy.data.objects if o.get("ease_role") == "garment"]
    try:
        r = blender.run(bpy.ops.ease.drape)
    finally:
        sc[data.PATTERN_KEY] = text
    assert "ERROR" in r and "body: missing" in r["ERROR"] and "\n" not in r["ERROR"].strip(), r
    assert [o.name for o in bpy.data.objects if o.get("ease_role") == "garment"] == garments


def test_a_pleated_garment_gets_its_fabric(bpy_session, addon, anny):
    """A pleated pattern is draped opened (its pleats' cloth inserted): the garment's fabric UVs are
    laid on the pattern as draped, so Studio and Render dress it (they skipped it: the closed
    pattern's corners are not the garment's)."""
    from core import workflows as wf
    from core.design.pleated import skirt_knife_pleats

    bpy = bpy_session["bpy"]
    sc = bpy.context.scene
    build, fabric, materials = addon("build"), addon("render_fabric"), addon("materials")
    d = skirt_knife_pleats()
    for panel in d["garments"][0]["panels"]:  # one pleat a side of each panel
        panel["pleats"] = panel["pleats"][1:2]
    pattern = wf.reference(wf.prepare(d, body=anny)).pattern
    run = wf.drape(pattern, options={"max_frames": 1, "device": "cpu"})
    g = build.garment(sc, run.result, run.metrics["vertex_gap"], "pleated")
    closed = sum(len(p.faces) for p in pattern.panels)
    assert len(g.data.polygons) > closed
    assert fabric.dress_garment(sc, g, pattern) is True
    assert len(g.data.uv_layers[materials.FABRIC_UV].data) == 3 * len(g.data.polygons)
