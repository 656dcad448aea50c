"""The Blender add-on, headless with the bpy module, on the default body.

One bpy session for the whole module (bpy is heavy): the extension is
linked into a temporary extension repository of a temporary user folder and
enabled with ``addon_enable``. Tests run in file order and build on each
other's scene (body -> design -> ease -> pattern -> drape -> render), as a
designer would. Paint strokes crash headless, so the ease layer is written as
data the way a brush leaves it (scene-linear colours, linear blends).
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
DESIGN = "top_sleeveless.json"     # cheapest template: two panels


def _import_bpy(user_dir: str):
    if "bpy" not in sys.modules:
        os.environ["BLENDER_USER_RESOURCES"] = user_dir
    os.environ.setdefault("WARP_CACHE_PATH", str(ROOT / ".cache" / "warp"))
    import bpy
    return bpy


@pytest.fixture(scope="module")
def bpy_session():
    tmp = tempfile.mkdtemp(prefix="ease_addon_test_")
    bpy = _import_bpy(os.path.join(tmp, "user"))
    repo_dir = os.path.join(tmp, "repo")
    os.makedirs(repo_dir)
    os.symlink(ROOT, os.path.join(repo_dir, "ease"))
    repo = bpy.context.preferences.extensions.repos.new(name="EASE test", module="ease_test",
                                                        custom_directory=repo_dir, source="USER")
    module = f"bl_ext.{repo.module}.ease"
    assert bpy.ops.preferences.addon_enable(module=module) == {"FINISHED"}
    bpy.ops.wm.read_homefile(use_empty=True)
    yield {"bpy": bpy, "module": module, "tmp": Path(tmp)}
    import addon_utils
    if addon_utils.check(module)[1]:
        bpy.ops.preferences.addon_disable(module=module)
    elif module in sys.modules:  # preferences reloaded with a file: unregister directly
        sys.modules[module].unregister()
    for r in list(bpy.context.preferences.extensions.repos):
        if r.module == "ease_test":
            bpy.context.preferences.extensions.repos.remove(r)


@pytest.fixture(scope="module")
def ramp(bpy_session):
    return sys.modules[bpy_session["module"] + ".ease_addon.ramp"]


def _addon(bpy_session, name):
    return sys.modules[f"{bpy_session['module']}.ease_addon.{name}"]


def _scene(bpy):
    return bpy.context.scene


def _verts(obj):
    co = np.empty(len(obj.data.vertices) * 3, dtype=np.float32)
    obj.data.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def _world_box(obj):
    """Min and max corner of an object's world-space bounding box."""
    m = np.array(obj.matrix_world)
    c = np.array([list(v) for v in obj.bound_box]) @ m[:3, :3].T + m[:3, 3]
    return c.min(0), c.max(0)


def _run(bpy, op, **kw):
    """Call an operator; return its result set (failures come back as CANCELLED + report)."""
    try:
        return op(**kw)
    except RuntimeError as exc:  # operator reported an error
        return {"ERROR": str(exc)}


# ----------------------------------------------------------------------------- extension

def test_manifest_validates():
    script = next(ROOT.glob(".venv/lib/python3.11/site-packages/bpy/*/scripts/addons_core/bl_pkg/cli/blender_ext.py"),
                  None)
    if script is None:
        import bpy  # noqa: F401  (the venv without the usual layout: find it from the module)
        script = next(Path(sys.modules["bpy"].__file__).parent.glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    r = subprocess.run([sys.executable, str(script), "validate", str(ROOT)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    text = (ROOT / "blender_manifest.toml").read_text()
    for key in ('id = "ease"', 'type = "add-on"', 'blender_version_min = "4.2.0"',
                '"SPDX:GPL-3.0-or-later"', "[permissions]", "files = "):
        assert key in text


def test_enable_disable_twice_leaves_nothing(bpy_session):
    bpy, module = bpy_session["bpy"], bpy_session["module"]
    base_ops = set(dir(bpy.ops.ease))
    assert "add_body" in base_ops and hasattr(bpy.types.Scene, "ease")
    handlers = {k: len(getattr(bpy.app.handlers, k)) for k in dir(bpy.app.handlers)
                if isinstance(getattr(bpy.app.handlers, k), list)}
    for _ in range(2):
        bpy.ops.preferences.addon_disable(module=module)
        assert not hasattr(bpy.types.Scene, "ease")
        assert not hasattr(bpy.types, "EASE_PT_body")
        assert not hasattr(bpy.types, "EASE_OT_add_body")
        assert not [c for c in dir(bpy.types) if c.startswith("EASE_")]
        assert bpy.ops.preferences.addon_enable(module=module) == {"FINISHED"}
        assert hasattr(bpy.types.Scene, "ease") and hasattr(bpy.types, "EASE_PT_ease")
    assert set(dir(bpy.ops.ease)) == base_ops
    # no handler added by enabling twice
    assert {k: len(getattr(bpy.app.handlers, k)) for k in handlers} == handlers
    panels = [c for c in dir(bpy.types) if c.startswith("EASE_PT_")]
    assert {getattr(bpy.types, p).bl_category for p in panels} == {"EASE"}


# ----------------------------------------------------------------------------- ramp (pure numpy)

def test_ramp_blends_decode_to_in_between_ease(ramp):
    lo, hi = 0.9, 2.0
    e = np.array([0.9, 1.0, 1.3, 1.75, 2.0])
    c = ramp.ease_to_color(e, lo, hi)
    assert np.allclose(ramp.color_to_ease(c, lo, hi), e, atol=1e-6)
    a = np.linspace(0, 1, 7)[:, None]
    c0, c1 = ramp.ease_to_color(1.1, lo, hi), ramp.ease_to_color(1.8, lo, hi)
    blend = (1 - a) * c0 + a * c1           # what a soft brush edge leaves in a float layer
    assert np.allclose(ramp.color_to_ease(blend, lo, hi), 1.1 + a[:, 0] * 0.7, atol=1e-6)
    # brush strength scaling the colour does not change the decoded ease
    assert np.allclose(ramp.color_to_ease(0.6 * c0, lo, hi), 1.1, atol=1e-6)
    with pytest.raises(ValueError):
        ramp.ease_to_color(1.0, 2.0, 1.0)
    assert np.allclose(ramp.srgb_to_linear(ramp.linear_to_srgb([0.0, 0.002, 0.3, 1.0])), [0.0, 0.002, 0.3, 1.0])


# ----------------------------------------------------------------------------- body

def test_add_body_and_shape_in_place(bpy_session):
    bpy = bpy_session["bpy"]
    from core.body import load_body
    model = load_body("anny")
    assert bpy.ops.ease.add_body(source="DEFAULT") == {"FINISHED"}
    s = _scene(bpy).ease
    obj = s.body
    assert obj is not None and len(obj.data.vertices) == model.n_vertices
    assert len(obj.data.polygons) == len(model.faces)
    layer = obj.data.color_attributes.get("ease")
    assert layer is not None and layer.domain == "POINT" and layer.data_type == "FLOAT_COLOR"
    assert {i.name for i in s.shape} == set(model.shape_parameters())
    assert np.allclose(_verts(obj), model.vertices(), atol=1e-5)
    # size preset: the vertices move in place, the ease layer stays
    assert bpy.ops.ease.set_size(size="XL") == {"FINISHED"}
    from core.body.sizes import size_shape
    assert np.allclose(_verts(obj), model.vertices(size_shape(model, "XL")), atol=1e-5)
    assert obj.data.color_attributes.get("ease") is not None
    assert "chest" in s.measurements_report
    # every pose preset, on the XL body
    for pose in ("T", "P1", "P2", "P3"):
        assert bpy.ops.ease.set_pose(pose=pose) == {"FINISHED"}
        assert np.allclose(_verts(obj), model.vertices(size_shape(model, "XL"), pose), atol=1e-5), pose
    assert bpy.ops.ease.set_pose(pose="A") == {"FINISHED"}
    # every size preset: girth grows from XS to XL
    girth = []
    for size in ("XS", "S", "M", "L", "XL"):
        assert bpy.ops.ease.set_size(size=size) == {"FINISHED"}
        assert np.allclose(_verts(obj), model.vertices(size_shape(model, size)), atol=1e-5), size
        girth.append(float(np.ptp(_verts(obj)[:, 1])))
    assert girth == sorted(girth)
    assert bpy.ops.ease.set_size(size="M") == {"FINISHED"}
    # sliders update the body live
    item = next(i for i in s.shape if i.name == "weight")
    v0 = _verts(obj).copy()
    item.value = 0.8
    assert np.abs(_verts(obj) - v0).max() > 1e-3
    item.value = 0.5
    assert np.allclose(_verts(obj), v0, atol=1e-5)


def test_bad_input_reports_and_leaves_scene(bpy_session):
    bpy = bpy_session["bpy"]
    obj = _scene(bpy).ease.body
    v0 = _verts(obj).copy()
    n_obj = len(bpy.data.objects)
    r = _run(bpy, bpy.ops.ease.set_size, size="XXL")
    assert "ERROR" in r and "XXL" in r["ERROR"] and "XS" in r["ERROR"]
    r = _run(bpy, bpy.ops.ease.set_pose, pose="Q9")
    assert "ERROR" in r
    r = _run(bpy, bpy.ops.ease.load_template, template="no_such_design.json")
    assert "ERROR" in r and "no_such_design" in r["ERROR"]
    # a design that fails to resolve on the body: the core's message, nothing changed
    bad = json.loads((ROOT / "examples" / "designs" / DESIGN).read_text())
    bad["body"]["shape"] = "XL"      # would reshape the body if it got that far
    bad["keypoints"]["chest_front"] = {"landmark": "nose_tip"}
    path = bpy_session["tmp"] / "bad_design.json"
    path.write_text(json.dumps(bad))
    r = _run(bpy, bpy.ops.ease.load_design_file, filepath=str(path))
    assert "ERROR" in r and "nose_tip" in r["ERROR"], r
    assert _scene(bpy).ease.design_json == ""
    assert np.array_equal(_verts(obj), v0) and len(bpy.data.objects) == n_obj
    # every later stage, asked too early, says what is missing and changes nothing
    s = _scene(bpy).ease
    s.export_dir = str(bpy_session["tmp"] / "too_early")
    for op, kw, words in ((bpy.ops.ease.optimize_pattern, {}, "design"),
                          (bpy.ops.ease.ease_to_design, {}, "design"),
                          (bpy.ops.ease.recut, {}, "design"),
                          (bpy.ops.ease.transfer_size, {}, "design"),
                          (bpy.ops.ease.adapt_poses, {}, "design"),
                          (bpy.ops.ease.drape, {}, "pattern"),
                          (bpy.ops.ease.export_pattern, {}, "pattern"),
                          (bpy.ops.ease.fitmap, dict(mode="STRAIN"), "drape")):
        r = _run(bpy, op, **kw)
        assert "ERROR" in r and words in r["ERROR"].lower(), (op.idname(), r)
        assert np.array_equal(_verts(obj), v0) and len(bpy.data.objects) == n_obj, op.idname()
        assert s.design_json == "" and not s.pattern_json and not s.fit_json and not s.drape_json, op.idname()
    assert not (bpy_session["tmp"] / "too_early").exists()


# ----------------------------------------------------------------------------- design

def test_load_template_draws_seamlines_and_keypoints(bpy_session):
    bpy = bpy_session["bpy"]
    from core.design import load_design
    assert bpy.ops.ease.load_template(template=DESIGN) == {"FINISHED"}
    s = _scene(bpy).ease
    design = load_design(json.loads(s.design_json))
    want = load_design(ROOT / "examples" / "designs" / DESIGN)
    assert design.panel_names() == want.panel_names()
    seams = [o for o in bpy.data.objects if o.get("ease_role") == "seamlines"]
    assert len(seams) == 1 and len(seams[0].data.edges) > 20
    convert = _addon(bpy_session, "convert")
    kps = convert.read_keypoints(s.body.data)
    assert kps, "the design's surface keypoints are stored on the body"
    # seamline vertices lie on the body surface (they are cut-embedded points)
    body_v = _verts(s.body)
    seam_v = _verts(seams[0])
    from scipy.spatial import cKDTree
    d, _ = cKDTree(body_v).query(seam_v)
    assert d.max() < 0.03
    # the seamlines stay attached when the body is posed (moved in place)
    assert bpy.ops.ease.set_pose(pose="P1") == {"FINISHED"}
    seams = [o for o in bpy.data.objects if o.get("ease_role") == "seamlines"]
    d, _ = cKDTree(_verts(s.body)).query(_verts(seams[0]))
    assert d.max() < 0.03 and np.abs(_verts(seams[0]) - seam_v).max() > 0.05
    assert bpy.ops.ease.set_pose(pose="A") == {"FINISHED"}
    # the cut panels match the design's panels
    design_ops = _addon(bpy_session, "design_ops")
    cut = design_ops.current_cut(bpy.context)
    assert sorted(p.name for p in cut.panels) == sorted(want.panel_names())


def test_keypoint_on_selected_vertex(bpy_session):
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
    obj = s.body
    from core.body import load_body
    model = load_body("anny")
    vid = int(model.faces[1234, 1])
    sel = np.zeros(len(obj.data.vertices), dtype=bool)
    sel[vid] = True
    obj.data.vertices.foreach_set("select", sel)
    assert bpy.ops.ease.assign_keypoint(name="test_point") == {"FINISHED"}
    design = json.loads(s.design_json)
    kp = design["keypoints"]["test_point"]
    tri, bary = kp["triangle"], kp["bary"]
    assert vid in model.faces[tri] and np.isclose(max(bary), 1.0)
    assert np.allclose(np.asarray(bary) @ model.vertices()[model.faces[tri]], model.vertices()[vid])
    convert = _addon(bpy_session, "convert")
    assert convert.read_keypoints(obj.data)["test_point"][0] == tri


def test_keypoint_on_a_vertex_selected_in_edit_mode(bpy_session):
    """The designer's way: Edit Mode, select one vertex, Keypoint at Selected Vertex; stays in Edit Mode."""
    bpy = bpy_session["bpy"]
    import bmesh
    s = _scene(bpy).ease
    obj = s.body
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    bm = bmesh.from_edit_mesh(obj.data)
    for v in bm.verts:
        v.select = False
    bm.verts.ensure_lookup_table()
    vid = 4321
    bm.verts[vid].select = True
    bmesh.update_edit_mesh(obj.data)
    assert bpy.ops.ease.assign_keypoint(name="edit_point") == {"FINISHED"}
    assert obj.mode == "EDIT"
    bpy.ops.object.mode_set(mode="OBJECT")
    kp = json.loads(s.design_json)["keypoints"]["edit_point"]
    faces = np.array([p.vertices[:] for p in obj.data.polygons])
    assert vid in faces[kp["triangle"]]
    assert np.allclose(np.asarray(kp["bary"]) @ _verts(obj)[faces[kp["triangle"]]], _verts(obj)[vid], atol=1e-6)
    # two selected: the add-on says what is wrong, the design unchanged
    before = s.design_json
    sel = np.zeros(len(obj.data.vertices), dtype=bool)
    sel[[10, 20]] = True
    obj.data.vertices.foreach_set("select", sel)
    r = _run(bpy, bpy.ops.ease.assign_keypoint, name="two_points")
    assert "ERROR" in r and "exactly one" in r["ERROR"] and s.design_json == before


def test_keypoint_clicked_on_the_surface(bpy_session):
    """Pick Keypoint: the ray under the mouse meets the body; the keypoint is that surface point.
    Headless there is no viewport to click in: the test casts the ray the click would."""
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
    design_ops = _addon(bpy_session, "design_ops")
    v = _verts(s.body).astype(np.float64)
    chest_z = v[:, 2].min() + 0.72 * np.ptp(v[:, 2])
    origin, direction = (0.03, -3.0, chest_z), (0.0, 1.0, 0.0)      # from in front (the body faces -Y)
    tri = design_ops.pick_on_surface(bpy.context, "clicked_point", origin, direction)
    kp = json.loads(s.design_json)["keypoints"]["clicked_point"]
    assert kp["triangle"] == tri and sum(kp["bary"]) == pytest.approx(1.0)
    faces = np.array([p.vertices[:] for p in s.body.data.polygons])
    hit = np.asarray(kp["bary"]) @ v[faces[tri]]
    # on the ray, and on the front of the body: nothing of the body lies between
    assert abs(hit[0] - 0.03) < 1e-5 and abs(hit[2] - chest_z) < 1e-5
    near = v[(np.abs(v[:, 0] - 0.03) < 0.01) & (np.abs(v[:, 2] - chest_z) < 0.01)]
    assert hit[1] <= near[:, 1].min() + 0.01
    convert = _addon(bpy_session, "convert")
    assert convert.read_keypoints(s.body.data)["clicked_point"][0] == tri
    # a click beside the body: the add-on's message, the design unchanged
    before = s.design_json
    with pytest.raises(Exception, match="no body under the mouse"):
        design_ops.pick_on_surface(bpy.context, "missed", (3.0, -3.0, chest_z), direction)
    with pytest.raises(Exception, match="name"):
        design_ops.pick_on_surface(bpy.context, "", origin, direction)
    assert s.design_json == before


def test_parameter_recut(bpy_session):
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
    if not len(s.design_params):
        pytest.skip("template has no parameters")
    item = max(s.design_params, key=lambda i: min(i.max, 10.0) - max(i.min, -10.0))
    seams = next(o for o in bpy.data.objects if o.get("ease_role") == "seamlines")
    v0 = _verts(seams).copy()
    old = item.value
    lo, hi = item.min, item.max
    new = old + 0.5 * (hi - old) if hi - old > old - lo else old - 0.5 * (old - lo)
    assert lo <= new <= hi
    assert bpy.ops.ease.set_parameter(name=item.name, value=new) == {"FINISHED"}
    assert json.loads(s.design_json)["parameters"][item.name]["value"] == pytest.approx(new)
    seams = next(o for o in bpy.data.objects if o.get("ease_role") == "seamlines")
    v1 = _verts(seams)
    assert v1.shape != v0.shape or np.abs(v1 - v0).max() > 1e-4
    assert bpy.ops.ease.set_parameter(name=item.name, value=old) == {"FINISHED"}
    # live re-cut from the slider itself
    s.live_recut = True
    item = next(i for i in s.design_params if i.name == item.name)
    item.value = new
    assert json.loads(s.design_json)["parameters"][item.name]["value"] == pytest.approx(new)
    seams = next(o for o in bpy.data.objects if o.get("ease_role") == "seamlines")
    assert np.abs(_verts(seams) - v1).max() < 1e-6 if _verts(seams).shape == v1.shape else False
    item.value = old
    assert json.loads(s.design_json)["parameters"][item.name]["value"] == pytest.approx(old)


# ----------------------------------------------------------------------------- ease

def test_brush_colour_and_painted_layer_read_back(bpy_session, ramp):
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
    s.ease_min, s.ease_max = 0.9, 2.0
    s.ease_value = 1.3
    assert bpy.ops.ease.brush_ease() == {"FINISHED"}
    ups = _scene(bpy).tool_settings.vertex_paint.unified_paint_settings
    want = ramp.ease_to_color(1.3, 0.9, 2.0)[:3]
    got = np.asarray(ups.color)
    if type(ups).bl_rna.properties["color"].subtype == "COLOR_GAMMA":
        got = ramp.srgb_to_linear(got)
    assert np.allclose(got, want, atol=1e-6)
    assert len(s.legend) == 5 and s.legend[0].ease == pytest.approx(0.9) and s.legend[-1].ease == pytest.approx(2.0)
    # "paint": the brush colour where the stroke was, a 50 % blend with 1.8 on its edge
    obj = s.body
    me = obj.data
    ease_ops = _addon(bpy_session, "ease_ops")
    c0, c1 = ramp.ease_to_color(1.3, 0.9, 2.0), ramp.ease_to_color(1.8, 0.9, 2.0)
    colors = np.tile(c1, (len(me.vertices), 1))
    faces = np.array([p.vertices[:] for p in me.polygons])
    stroke = faces[:500]
    colors[np.unique(stroke)] = np.asarray(got.tolist() + [1.0], dtype=np.float32)
    edge = faces[600:650]
    colors[np.unique(edge)] = 0.5 * c0 + 0.5 * c1
    me.color_attributes["ease"].data.foreach_set("color", colors.astype(np.float32).ravel())
    tri = ease_ops.triangle_ease(obj, _scene(bpy))
    inner = [i for i in range(500) if not np.isin(faces[i], np.unique(faces[500:])).any()]
    assert inner and np.allclose(tri[inner], 1.3, atol=1e-5)     # exact for the brush's value
    only_edge = [i for i in range(600, 650) if np.isin(faces[i], np.unique(edge)).all()
                 and not np.isin(faces[i], np.unique(stroke)).any()]
    assert only_edge and np.allclose(tri[only_edge], 1.55, atol=1e-5)   # in-between ease


def test_uniform_and_gradient_ease_per_panel(bpy_session):
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
    ease_ops = _addon(bpy_session, "ease_ops")
    design_ops = _addon(bpy_session, "design_ops")
    cut = design_ops.current_cut(bpy.context)
    names = [p.name for p in cut.panels]
    assert bpy.ops.ease.ease_uniform(whole_body=True, ease=1.2) == {"FINISHED"}
    assert bpy.ops.ease.ease_uniform(panel=names[0], ease=1.5) == {"FINISHED"}
    v = ease_ops.vertex_ease(s.body, _scene(bpy))
    mask = ease_ops.panel_vertex_mask(bpy.context, names[0])
    assert np.allclose(v[mask], 1.5, atol=1e-5) and np.allclose(v[~mask], 1.2, atol=1e-5)
    s.ease_from, s.ease_to, s.gradient_axis = 1.1, 1.7, "Z"
    assert bpy.ops.ease.ease_gradient(panel=names[-1]) == {"FINISHED"}
    v = ease_ops.vertex_ease(s.body, _scene(bpy))
    m2 = ease_ops.panel_vertex_mask(bpy.context, names[-1])
    z = _verts(s.body)[:, 2]
    top, bottom = m2 & (z >= np.percentile(z[m2], 95)), m2 & (z <= np.percentile(z[m2], 5))
    assert v[top].mean() < 1.2 < v[bottom].mean()
    assert v[m2].min() >= 1.1 - 1e-5 and v[m2].max() <= 1.7 + 1e-5
    # a value outside the ramp is refused, the layer unchanged
    r = _run(bpy, bpy.ops.ease.ease_uniform, panel=names[0], ease=3.5)
    assert "ERROR" in r
    assert np.allclose(ease_ops.vertex_ease(s.body, _scene(bpy)), v)
    # back to the piecewise field the pattern test uses
    assert bpy.ops.ease.ease_uniform(whole_body=True, ease=1.2) == {"FINISHED"}
    assert bpy.ops.ease.ease_uniform(panel=names[0], ease=1.4) == {"FINISHED"}


def test_ease_layer_to_design(bpy_session):
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
    design_ops = _addon(bpy_session, "design_ops")
    ease_ops = _addon(bpy_session, "ease_ops")
    assert bpy.ops.ease.ease_to_design() == {"FINISHED"}
    design = json.loads(s.design_json)
    fields = [p["ease"] for g in design["garments"] for p in g["panels"]]
    assert all("per_triangle" in f for f in fields)
    cut = design_ops.current_cut(bpy.context)
    names = [p.name for p in cut.panels]
    first, other = cut.panel(names[0]), cut.panel(names[-1])
    # the cut's per-triangle targets are the painted values (seam triangles may blend)
    assert np.median(first.ease) == pytest.approx(1.4, abs=1e-4)
    assert np.median(other.ease) == pytest.approx(1.2, abs=1e-4)
    # and back: the design's field written into the layer reads back the same
    v_before = ease_ops.vertex_ease(s.body, _scene(bpy))
    assert bpy.ops.ease.ease_from_design() == {"FINISHED"}
    v_after = ease_ops.vertex_ease(s.body, _scene(bpy))
    inside = ease_ops.panel_vertex_mask(bpy.context, names[0])
    assert np.median(np.abs(v_after[inside] - v_before[inside])) < 1e-4


# ----------------------------------------------------------------------------- pattern, fit, drape

def test_pattern_objects_match_pattern_json(bpy_session, tmp_path, ramp):
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
    assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
    pattern_ops = _addon(bpy_session, "pattern_ops")
    from core.pattern.io import load_pattern
    text = _scene(bpy)[pattern_ops.PATTERN_KEY]
    (tmp_path / "pattern.json").write_text(text)
    pattern = load_pattern(tmp_path / "pattern.json")
    pieces = {o["ease_panel"]: o for o in bpy.data.objects if o.get("ease_role") == "pattern_panel"}
    body_lo, body_hi = _world_box(s.body)
    assert sorted(pieces) == sorted(p.name for p in pattern.panels)
    for p in pattern.panels:
        o = pieces[p.name]
        ext = np.ptp(p.uv, axis=0)
        assert o.dimensions.x == pytest.approx(ext[0], abs=1e-4)
        assert o.dimensions.z == pytest.approx(ext[1], abs=1e-4)
        assert o.dimensions.y == pytest.approx(0.0, abs=1e-6)
        assert len(o.data.polygons) == len(p.faces)
        # coloured by achieved ease: the colours decode (ramp range on the mesh) to the pattern's weft scales
        col = o.data.color_attributes.get("achieved_ease")
        assert col is not None and col.domain == "CORNER"
        rgba = np.empty(len(col.data) * 4, dtype=np.float32)
        col.data.foreach_get("color", rgba)
        lo_r, hi_r = o.data["ease_ramp"]
        got = ramp.color_to_ease(rgba.reshape(-1, 4), lo_r, hi_r).reshape(-1, 3)[:, 0]
        assert np.allclose(got, np.clip(p.achieved_weft, lo_r, hi_r), atol=1e-4)
        assert np.mean((p.achieved_weft >= lo_r) & (p.achieved_weft <= hi_r)) > 0.95
        kids = {c.type for c in o.children}
        assert {"CURVE", "MESH", "FONT"} <= kids      # outline, grain arrow, name
        # laid out beside the body, not through it
        lo, hi = _world_box(o)
        assert hi[0] < body_lo[0] or lo[0] > body_hi[0] or hi[1] < body_lo[1] or lo[1] > body_hi[1], p.name
    figures = json.loads(s.pattern_json)
    assert figures["pieces"] == len(pattern.panels)
    assert figures["flipped triangles"] == 0
    assert figures["ease compliance mean %"] == pytest.approx(pattern.report["metrics"]["compliance"]["mean"], abs=1e-3)
    assert "seam mismatch max mm" in figures
    # piecewise ease realised: the 1.4 piece is wider per unit body than the 1.2 one
    first = pattern.panels[0] if pattern.panels[0].name == sorted(pieces)[0] else pattern.panel(sorted(pieces)[0])
    assert np.median(first.achieved_weft) > 1.0



def test_gathering_setting_reaches_the_design_and_the_pattern(bpy_session):
    """The Pattern panel's gathering threshold is kept in the design and decides which seams are gathered."""
    bpy = bpy_session["bpy"]
    scene = _scene(bpy)
    s = scene.ease
    pattern_ops = _addon(bpy_session, "pattern_ops")

    def gathered():
        return [x["name"] for x in json.loads(scene[pattern_ops.PATTERN_KEY])["seams"] if x.get("gathered")]

    try:
        s.gather_auto = False
        assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
        assert json.loads(s.design_json)["materials"]["gather_above"] is None
        assert gathered() == []
        # a 1 % threshold gathers seams whose sides differ a little (ease 1.2 against 1.4 across a seam)
        s.gather_auto, s.gather_above_pct = True, 1.0
        assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
        assert json.loads(s.design_json)["materials"]["gather_above"] == pytest.approx(0.01)
        assert gathered()
        assert json.loads(s.pattern_json)["gathered seams"] == len(gathered())
    finally:
        s.gather_auto, s.gather_above_pct = True, 20.0
        assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
    assert json.loads(s.design_json)["materials"]["gather_above"] == pytest.approx(0.2)
    assert "gathered seams" not in json.loads(s.pattern_json) or gathered()

def test_transfer_and_adapt_show_figures(bpy_session):
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
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
    # the drape below uses this adapted pattern (it fits the reference body in every chosen pose)


def test_drape_garment_and_fit_map(bpy_session):
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
    s.drape_frames = 15
    s.drape_device = "cuda"
    r = _run(bpy, bpy.ops.ease.drape)
    if "ERROR" in r:      # no GPU here: the core's message, and no garment made
        assert "cuda" in r["ERROR"].lower()
        assert not [o for o in bpy.data.objects if o.get("ease_role") == "garment"]
    s.drape_device = "cpu"
    assert bpy.ops.ease.drape() == {"FINISHED"}
    garments = [o for o in bpy.data.objects if o.get("ease_role") == "garment"]
    assert len(garments) == 1
    g = garments[0]
    assert len(g.data.polygons) > 100
    assert g.data.materials[0].name == "EASE Fabric"
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
    assert g.data.materials[0].name == "EASE Fabric"


def test_drape_modal_progress_and_esc(bpy_session):
    """The interactive drape: a worker thread runs the core; the modal step
    shows progress, applies the result on the main thread when done, and Esc
    cancels leaving the scene as it was. Headless there is no event loop (an
    INVOKE call falls back to execute), so the test drives the modal step."""
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
    drape_ops = _addon(bpy_session, "drape_ops")
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    g_name, g_verts = garment.data.name, _verts(garment).copy()
    pattern = _addon(bpy_session, "pattern_ops").stored_pattern(_scene(bpy))
    body_v, body_f = drape_ops._pattern_body(pattern)
    job = drape_ops.DrapeJob(pattern, body_v, body_f, frames=400).start()
    assert drape_ops.step_job(bpy.context, job, "ESC") == "RUNNING"
    job.join(120)
    assert drape_ops.step_job(bpy.context, job, "TIMER") == "CANCELLED"
    assert "cancelled" in s.drape_status
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment.data.name == g_name and np.array_equal(_verts(garment), g_verts)
    assert not drape_ops._JOBS
    # the core fails mid-drape: its message in the status, the garment as it was
    from core.errors import EaseError
    real = drape_ops._compute

    def failing(*a, **k):
        a[4](0.3, "frame 12")
        raise EaseError("drape diverged at frame 12 (time step too large?)")
    drape_ops._compute = failing
    try:
        job = drape_ops.DrapeJob(pattern, body_v, body_f, frames=400).start()
        job.join(60)
        assert drape_ops.step_job(bpy.context, job, "TIMER") == "CANCELLED"
    finally:
        drape_ops._compute = real
    assert "diverged at frame 12" in s.drape_status and "stopped" in s.drape_status
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment.data.name == g_name and np.array_equal(_verts(garment), g_verts)
    # a run to the end
    export_ops = _addon(bpy_session, "export_ops")
    key = _addon(bpy_session, "pattern_ops").PATTERN_KEY
    digest = export_ops.pattern_digest(_scene(bpy)[key])
    job = drape_ops.DrapeJob(pattern, body_v, body_f, frames=4, digest=digest).start()
    assert drape_ops.step_job(bpy.context, job, "MOUSEMOVE") == "RUNNING"
    job.join(120)
    assert job.fraction >= 0.9 and job.error is None
    assert drape_ops.step_job(bpy.context, job, "TIMER") == "FINISHED"
    assert json.loads(s.drape_json)["frames"] <= 4
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment["ease_pattern"] == digest and export_ops.garment_positions(_scene(bpy))[0] is not None
    # the pattern changed while a drape ran: the garment says which pattern it fits, and
    # is not exported as the new one's
    job = drape_ops.DrapeJob(pattern, body_v, body_f, frames=2, digest=digest).start()
    text = _scene(bpy)[key]
    _scene(bpy)[key] = json.dumps(dict(json.loads(text), style="re-optimized meanwhile"))
    job.join(120)
    assert drape_ops.step_job(bpy.context, job, "TIMER") == "FINISHED"
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment["ease_pattern"] == digest
    pos, why = export_ops.garment_positions(_scene(bpy))
    assert pos is None and "another pattern" in why
    _scene(bpy)[key] = text
    assert export_ops.garment_positions(_scene(bpy))[0] is not None
    # disabling the add-on while a drape runs stops the worker (no thread left behind)
    module = bpy_session["module"]
    job = drape_ops.DrapeJob(pattern, body_v, body_f, frames=5000).start()
    assert job._thread.is_alive()
    bpy.ops.preferences.addon_disable(module=module)
    assert job.cancelled and not job._thread.is_alive() and job.result is None
    assert bpy.ops.preferences.addon_enable(module=module) == {"FINISHED"}
    assert _scene(bpy).ease.drape_json       # the scene's EASE data is still there


def _obj_vertices(path):
    return np.array([[float(x) for x in l.split()[1:4]] for l in path.read_text().splitlines() if l.startswith("v ")])


def test_export_pattern(bpy_session):
    """Export calls the core's exporters with the design's allowance; the garment comes from its object."""
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
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
    assert summary["allowance_mm"]["default"] == pytest.approx(15) and summary["allowance_mm"]["hem"] == pytest.approx(30)
    interior = [n for p in summary["pieces"] for v in p["notches_mm"].values() for n in v[1:-1]]
    rest = np.mod(np.array(interior), 80.0)
    assert interior and np.all(np.minimum(rest, 80.0 - rest) < 1e-3)      # every 8 cm
    # the draped garment written is the garment object's shape
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    from scipy.spatial import cKDTree
    got = _obj_vertices(out / "garment.obj")
    v = _verts(garment).astype(np.float64)
    want = np.column_stack([v[:, 0], v[:, 2], -v[:, 1]])          # OBJ is Y-up
    assert cKDTree(want).query(got)[0].max() < 1e-5 and cKDTree(got).query(want)[0].max() < 1e-5

    # a garment draped from another pattern is not exported as this pattern's
    export_ops = _addon(bpy_session, "export_ops")
    digest = garment["ease_pattern"]
    garment["ease_pattern"] = "an earlier pattern"
    s.export_glb, s.export_obj = True, False
    out2 = bpy_session["tmp"] / "export2"
    s.export_dir = str(out2)
    assert bpy.ops.ease.export_pattern() == {"FINISHED"}          # the 2D files, GLB skipped with a warning
    assert "pattern.svg" in {p.name for p in out2.iterdir()} and not (out2 / "garment.glb").exists()
    s.export_svg, s.export_dxf = False, False
    out3 = bpy_session["tmp"] / "export3"
    s.export_dir = str(out3)
    r = _run(bpy, bpy.ops.ease.export_pattern)
    assert "ERROR" in r and "drape the current pattern again" in r["ERROR"] and not out3.exists()
    assert export_ops.garment_positions(_scene(bpy))[0] is None
    garment["ease_pattern"] = digest
    s.export_svg, s.export_dxf, s.export_glb = True, True, False
    # a folder that cannot be made: the error in the status bar, the design keeps its old settings
    blocker = bpy_session["tmp"] / "a_file"
    blocker.write_text("not a folder")
    s.export_dir = str(blocker / "export")
    design_before = s.design_json
    s.export_hem_cm = 4.0
    r = _run(bpy, bpy.ops.ease.export_pattern)
    assert "ERROR" in r and "a_file" in r["ERROR"], r
    assert s.design_json == design_before
    s.export_hem_cm = 3.0
    s.export_dir = str(out)


def test_cycles_render_is_not_empty(bpy_session):
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
    s.render_samples, s.render_resolution = 2, 8
    s.render_path = str(bpy_session["tmp"] / "render.png")
    assert bpy.ops.ease.studio_setup() == {"FINISHED"}
    assert _scene(bpy).render.engine == "CYCLES" and _scene(bpy).cycles.device == "CPU"
    assert bpy.ops.ease.render() == {"FINISHED"}
    img = bpy.data.images.load(s.render_path)
    px = np.empty(img.size[0] * img.size[1] * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    rgb = px.reshape(-1, 4)[:, :3]
    assert img.size[0] > 10 and rgb.std() > 0.01, "the render is a flat image"
    bpy.data.images.remove(img)


# ----------------------------------------------------------------------------- undo, save/reopen

def _fingerprint(bpy, ease_ops):
    """What an operator may change: objects, body vertices, ease layer, design, pattern, studio."""
    sc = _scene(bpy)
    s = sc.ease
    fp = {"objects": sorted(o.name for o in bpy.data.objects), "design": s.design_json,
          "pattern": sc.get("ease_pattern_json", ""), "engine": sc.render.engine,
          "camera": sc.camera.name if sc.camera else None,
          "reports": [s.pattern_json, s.fit_json, s.drape_json, s.measurements_report],
          "params": [(i.name, round(i.value, 6)) for i in s.design_params],
          "brush": [round(c, 6) for c in sc.tool_settings.vertex_paint.unified_paint_settings.color],
          "ramp": (round(s.ease_min, 6), round(s.ease_max, 6)),
          "mode": bpy.context.object.mode if bpy.context.object else None}
    for g in (o for o in bpy.data.objects if o.get("ease_role") == "garment"):
        fp["garment"] = (float(np.round(_verts(g).astype(np.float64).sum(), 5)),
                         g.data.materials[0].name if g.data.materials else None)
    if s.body is not None:
        fp["verts"] = float(np.round(_verts(s.body).astype(np.float64).sum(), 5))
        fp["ease"] = float(np.round(ease_ops.vertex_ease(s.body, sc).sum(), 5))
        fp["kp"] = json.dumps(_addon_convert.read_keypoints(s.body.data), sort_keys=True)
        layer = s.body.data.color_attributes.get("ease")
        raw = np.empty(len(layer.data) * 4, dtype=np.float32)
        layer.data.foreach_get("color", raw)
        fp["layer"] = (float(np.round(raw.astype(np.float64).sum(), 4)), list(s.body.data.get("ease_ramp", [])))
    return fp


_addon_convert = None


def test_undo_restores_the_scene(bpy_session):
    """Every operator's changes live in Blender data, so undo brings the scene back.

    Headless, operators called from Python push no undo step of their own; the
    test pushes the steps the UI would push around each call, then undoes.
    """
    global _addon_convert
    bpy = bpy_session["bpy"]
    ease_ops = _addon(bpy_session, "ease_ops")
    _addon_convert = _addon(bpy_session, "convert")
    names = [p.name for p in _addon(bpy_session, "design_ops").current_cut(bpy.context).panels]
    _scene(bpy).render.engine = "BLENDER_EEVEE" if "BLENDER_EEVEE" in \
        [i.identifier for i in _scene(bpy).render.bl_rna.properties["engine"].enum_items] else "BLENDER_WORKBENCH"
    # after an undo Blender rebuilds its data: Python references taken before it dangle,
    # so every step fetches the scene afresh (E() below)
    E = lambda: _scene(bpy).ease  # noqa: E731
    param_name = E().design_params[0].name
    design_file = bpy_session["tmp"] / "undo_design.json"
    other = json.loads((ROOT / "examples" / "designs" / DESIGN).read_text())
    other["materials"]["eps_weft"] = 1.2
    design_file.write_text(json.dumps(other))
    E().export_dir = str(bpy_session["tmp"] / "export_undo")
    E().export_svg, E().export_dxf, E().export_pdf, E().export_glb, E().export_obj = True, False, False, False, False

    def param():
        return E().design_params[param_name]

    def slider_without_live_update():
        body_ops = _addon(bpy_session, "body_ops")
        body_ops.SYNCING = True          # as if the slider moved with live update off
        try:
            E().shape["weight"].value = 0.7
        finally:
            body_ops.SYNCING = False

    def nudge_param():
        E().live_recut = False
        param().value = 0.5 * (param().value + param().max)

    ops = bpy.ops.ease
    # (operator, arguments, what to set first); every operator that changes the scene
    calls = [(ops.ease_uniform, lambda: dict(whole_body=True, ease=1.9), None),
             (ops.ease_gradient, lambda: dict(panel=names[0]), None),
             (ops.ease_to_design, dict, None),
             (ops.ease_from_design, dict, lambda: ops.ease_uniform(whole_body=True, ease=1.7)),
             # a new ramp range: the brush re-encodes the painted layer in it
             (ops.brush_ease, dict, lambda: setattr(E(), "ease_min", 0.8) or setattr(E(), "ease_value", 1.45)),
             (ops.set_size, lambda: dict(size="S"), None),
             (ops.set_pose, lambda: dict(pose="P3"), None),
             (ops.apply_shape, dict, slider_without_live_update),
             (ops.fit_measurements, dict, lambda: setattr(E(), "waist_cm", 90.0)),
             (ops.measure, dict, lambda: setattr(E(), "measurements_report", "")),
             (ops.assign_keypoint, lambda: dict(name="undo_point", vertex=100), None),
             (ops.set_parameter, lambda: dict(name=param_name, value=0.5 * (param().value + param().min)), None),
             (ops.recut, dict, nudge_param),
             (ops.load_design_file, lambda: dict(filepath=str(design_file)), None),
             (ops.load_template, lambda: dict(template=DESIGN), None),
             (ops.optimize_pattern, dict, None),
             (ops.transfer_size, dict, lambda: setattr(E(), "fit_size", "S")),
             (ops.adapt_poses, dict, None),
             (ops.drape, dict, lambda: setattr(E(), "drape_frames", 6)),
             (ops.fitmap, lambda: dict(mode="GAP"), None),
             (ops.export_pattern, dict, lambda: setattr(E(), "export_hem_cm", 2.5)),
             (ops.paint_ease, dict, None),
             (ops.add_body, lambda: dict(source="DEFAULT"), None),
             (ops.studio_setup, dict, None)]
    for op, kw, prepare in calls:
        if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
            bpy.ops.object.mode_set(mode="OBJECT")
        if prepare is not None:
            prepare()
        bpy.ops.ed.undo_push(message="before")
        before = _fingerprint(bpy, ease_ops)
        assert op(**kw()) == {"FINISHED"}, op
        bpy.ops.ed.undo_push(message=op.idname())
        assert _fingerprint(bpy, ease_ops) != before, f"{op.idname()} changed nothing"
        assert bpy.ops.ed.undo() == {"FINISHED"}
        after = _fingerprint(bpy, ease_ops)
        if op.idname() == "EASE_OT_brush_ease":
            # Blender keeps the paint colour out of its undo history (its own colour
            # picker is not undone either); the layer it re-encoded is restored
            assert after["brush"] != before["brush"]
            after["brush"] = before["brush"]
        assert after == before, (op.idname(), {k: (before.get(k), after.get(k)) for k in before
                                               if before.get(k) != after.get(k)})
        E().live_recut = True
    # the operators that change no Blender data (files only; the modal picker is a
    # click in the viewport): nothing to undo, and the scene stays as it was
    assert ops.export_pattern() == {"FINISHED"}     # the design takes the panel's export settings
    before = _fingerprint(bpy, ease_ops)
    assert ops.save_design(filepath=str(bpy_session["tmp"] / "undo_saved.json")) == {"FINISHED"}
    assert ops.export_pattern() == {"FINISHED"}
    assert _fingerprint(bpy, ease_ops) == before


def test_save_reopen_round_trip(bpy_session):
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
    ease_ops = _addon(bpy_session, "ease_ops")
    convert = _addon(bpy_session, "convert")
    design = s.design_json
    ease_v = ease_ops.vertex_ease(s.body, _scene(bpy)).copy()
    kps = convert.read_keypoints(s.body.data)
    path = str(bpy_session["tmp"] / "scene.blend")
    assert bpy.ops.wm.save_as_mainfile(filepath=path) == {"FINISHED"}
    bpy.ops.wm.read_homefile(use_empty=True)
    assert not _scene(bpy).ease.design_json
    assert bpy.ops.wm.open_mainfile(filepath=path) == {"FINISHED"}
    s = _scene(bpy).ease
    assert s.design_json == design
    assert np.allclose(ease_ops.vertex_ease(s.body, _scene(bpy)), ease_v, atol=1e-7)
    assert convert.read_keypoints(s.body.data) == kps
    pattern_ops = _addon(bpy_session, "pattern_ops")
    assert pattern_ops.stored_pattern(_scene(bpy)) is not None
    # the draped garment exports from the reopened file (nothing kept only in memory)
    s.export_dir = str(bpy_session["tmp"] / "export_reopened")
    s.export_svg, s.export_dxf, s.export_pdf, s.export_glb, s.export_obj = False, False, False, True, False
    assert bpy.ops.ease.export_pattern() == {"FINISHED"}
    assert (bpy_session["tmp"] / "export_reopened" / "garment.glb").stat().st_size > 1000
    s.export_svg, s.export_dxf = True, True
    # the scene keeps working after reopening: ease back into the design, re-cut from the JSON
    assert bpy.ops.ease.ease_to_design() == {"FINISHED"}


# ----------------------------------------------------------------------------- the rest of the operators, the panels

def test_measurements_fit_and_manual_shape(bpy_session):
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
    assert bpy.ops.ease.measure() == {"FINISHED"}
    assert "height" in s.measurements_report and "hip" in s.measurements_report
    s.height_cm, s.chest_cm, s.waist_cm, s.hip_cm = 175.0, 98.0, 84.0, 102.0
    assert bpy.ops.ease.fit_measurements() == {"FINISHED"}
    from core.body import load_body
    from core.body.measure import measure
    model = load_body("anny")
    got = measure(model, _verts(s.body).astype(np.float64))
    for k, want in (("height", 175.0), ("chest", 98.0), ("waist", 84.0), ("hip", 102.0)):
        if "not reachable" not in s.measurements_report.split(k, 1)[1].split(",", 1)[0]:
            assert abs(got[k] - want) <= 1.0 + 1e-6, (k, got[k])
    # sliders -> Apply Shape: the mesh is the model evaluated at the sliders
    for item in s.shape:
        if item.name == "muscle":
            item.value = 0.3
    assert bpy.ops.ease.apply_shape() == {"FINISHED"}
    shape = {i.name: i.value for i in s.shape}
    assert np.allclose(_verts(s.body), model.vertices(shape), atol=1e-5)


def test_paint_mode_design_file_save_and_recut(bpy_session):
    bpy = bpy_session["bpy"]
    s = _scene(bpy).ease
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
    assert (exp["allowance"]["default"], exp["allowance"]["hem"], exp["notch_spacing"]) == \
        pytest.approx(tuple(v / 100 for v in panel))
    assert panel != pytest.approx((1.0, 2.0, 10.0))
    s.design_json = ""
    s.export_allowance_cm, s.export_hem_cm, s.export_notch_cm = 1.0, 2.0, 10.0
    assert bpy.ops.ease.load_design_file(filepath=str(path)) == {"FINISHED"}
    assert json.loads(s.design_json)["name"] == saved["name"]
    assert (s.export_allowance_cm, s.export_hem_cm, s.export_notch_cm) == pytest.approx(panel)
    item = s.design_params[0]
    s.live_recut = False
    item.value = item.value            # no live re-cut while switched off
    assert bpy.ops.ease.recut() == {"FINISHED"}
    r = _run(bpy, bpy.ops.ease.load_design_file, filepath=str(bpy_session["tmp"] / "missing.json"))
    assert "ERROR" in r and "missing.json" in r["ERROR"]


class _Recorder:
    """A stand-in for ``UILayout`` that checks every property and operator the panels name."""

    def __init__(self, bpy, seen):
        self.bpy, self.seen = bpy, seen

    def _sub(self, *a, **k):
        return self

    row = column = box = split = _sub

    def label(self, **k):
        self.seen.append(("label", k.get("text")))

    def separator(self, **k):
        pass

    def prop(self, data, name, **k):
        assert name in data.bl_rna.properties, f"{type(data).__name__} has no property {name!r}"
        self.seen.append(("prop", name))

    def operator(self, idname, **k):
        mod, name = idname.split(".")
        assert hasattr(getattr(self.bpy.ops, mod), name), f"no operator {idname}"
        self.seen.append(("op", idname))

        class _Props:
            def __setattr__(s, key, value):
                pass
        return _Props()


def test_sidebar_panels_name_real_properties_and_operators(bpy_session):
    bpy = bpy_session["bpy"]
    seen = []
    for cls_name in [c for c in dir(bpy.types) if c.startswith("EASE_PT_")]:
        cls = getattr(bpy.types, cls_name)
        assert cls.bl_space_type == "VIEW_3D" and cls.bl_region_type == "UI" and cls.bl_category == "EASE"
        fake = type("P", (), {"layout": _Recorder(bpy, seen)})()
        cls.draw(fake, bpy.context)
    ops = {n for k, n in seen if k == "op"}
    for op in ("ease.add_body", "ease.set_size", "ease.fit_measurements", "ease.set_pose", "ease.load_template",
               "ease.assign_keypoint", "ease.paint_ease", "ease.brush_ease", "ease.ease_uniform",
               "ease.ease_gradient", "ease.ease_to_design", "ease.optimize_pattern", "ease.transfer_size",
               "ease.adapt_poses", "ease.drape", "ease.studio_setup", "ease.render", "ease.export_pattern"):
        assert op in ops, f"{op} is not in the sidebar"
    # every operator supports undo
    names = [n for n in dir(bpy.ops.ease) if not n.startswith("_")]
    assert len(names) >= 25
    for name in names:
        cls = getattr(bpy.types, "EASE_OT_" + name)
        assert {"REGISTER", "UNDO"} <= set(cls.bl_options), name


def test_body_from_a_file_the_user_owns(bpy_session):
    """From File: a template OBJ (no blend shapes) becomes the scene body, with its ease layer."""
    bpy = bpy_session["bpy"]
    from core.body import load_body
    model = load_body("anny")
    v = model.vertices()
    path = bpy_session["tmp"] / "my_body.obj"
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in v] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in model.faces]
    path.write_text("\n".join(lines) + "\n")
    s = _scene(bpy).ease
    s.body_file = str(path)
    assert bpy.ops.ease.add_body(source="FILE") == {"FINISHED"}
    obj = s.body
    assert obj["ease_model"] == str(path)
    assert len(obj.data.vertices) == len(v) and np.allclose(_verts(obj), v, atol=1e-5)
    assert obj.data.color_attributes.get("ease") is not None
    assert len([o for o in bpy.data.objects if o.get("ease_role") == "body"]) == 1
    s.body_file = str(bpy_session["tmp"] / "missing.npz")
    r = _run(bpy, bpy.ops.ease.add_body, source="FILE")
    assert "ERROR" in r and s.body == obj


def test_body_from_an_smpl_file(bpy_session):
    """From File with an SMPL-format .npz the user owns: its betas become the shape sliders, poses apply."""
    bpy = bpy_session["bpy"]
    sys.path.insert(0, str(ROOT / "tests"))
    from test_body_smpl import tube_model        # a small SMPL-format model (24 joints)
    from core.body import load_body
    path = bpy_session["tmp"] / "my_smpl.npz"
    np.savez(path, **tube_model(J=24, n_ring=12, n_rows=30))
    model = load_body(str(path))
    s = _scene(bpy).ease
    s.body_file = str(path)
    assert bpy.ops.ease.add_body(source="FILE") == {"FINISHED"}
    obj = s.body
    assert obj["ease_model"] == str(path) and len(obj.data.vertices) == model.n_vertices
    assert {i.name for i in s.shape} == set(model.shape_parameters())
    assert np.allclose(_verts(obj), model.vertices(), atol=1e-5)
    next(i for i in s.shape if i.name == "beta1").value = 2.0       # a slider: the body follows
    assert np.allclose(_verts(obj), model.vertices({"beta1": 2.0}), atol=1e-5)
    assert bpy.ops.ease.set_pose(pose="P1") == {"FINISHED"}
    assert np.allclose(_verts(obj), model.vertices({"beta1": 2.0}, "P1"), atol=1e-5)
    assert obj.data.color_attributes.get("ease") is not None
    assert bpy.ops.ease.add_body(source="DEFAULT") == {"FINISHED"}
