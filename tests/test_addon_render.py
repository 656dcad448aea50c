"""Render operators (ease_addon.render_ops, render_studio, render_fabric): the studio preset
on a scene that still has Blender's startup cube and light, the garment in its fabric, and a
tiny Cycles render read back: body and garment cover the frame they project to, nothing stands
in front of them, the floor takes their shadow."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

DESIGN = "top_sleeveless.json"  # cheapest template: two panels
PCT = 6  # % of 1080 x 1440: a 64 x 86 frame
SAMPLES = 4


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """A draped garment on the body, and the startup file's cube (2 m, at the origin, where the
    body stands) and point light, as a user's scene has them."""
    blender.reset(body=True, design=DESIGN, pattern=True, drape_frames=15)
    bpy = blender.bpy
    me = bpy.data.meshes.new("Cube")
    h = 1.0
    me.from_pydata(
        [(x, y, z) for x in (-h, h) for y in (-h, h) for z in (-h, h)],
        [],
        [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)],
    )
    cube = bpy.data.objects.new("Cube", me)
    light = bpy.data.objects.new("Light", bpy.data.lights.new("Light", "POINT"))
    light.location = (4.0, 1.0, 6.0)
    for o in (cube, light):
        bpy.context.scene.collection.objects.link(o)
    s = bpy.context.scene.ease
    s.render_samples, s.render_resolution, s.render_view = SAMPLES, PCT, "FRONT"
    assert bpy.ops.ease.studio_setup() == {"FINISHED"}
    return blender


def _pixels(bpy, path) -> np.ndarray:
    """(h, w, 4) float pixels of a PNG, top row first."""
    img = bpy.data.images.load(str(path))
    w, h = img.size
    px = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    return px.reshape(h, w, 4)[::-1]


def _render(blender, name: str) -> np.ndarray:
    bpy = blender.bpy
    s = bpy.context.scene.ease
    s.render_path = str(blender.tmp / name)
    assert bpy.ops.ease.render() == {"FINISHED"}
    return _pixels(bpy, s.render_path)


def _projected_mask(blender, objects, shape) -> np.ndarray:
    """Pixels the meshes of ``objects`` project to through the scene camera (vertices and
    triangle centroids and edge midpoints: the triangles are smaller than a pixel here)."""
    bpy = blender.bpy
    sc = bpy.context.scene
    cam = sc.camera
    h, w = shape
    proj = np.array(cam.calc_matrix_camera(bpy.context.evaluated_depsgraph_get(), x=w, y=h))
    view = np.array(cam.matrix_world.inverted())
    mask = np.zeros(shape, dtype=bool)
    for o in objects:
        v = blender.verts(o).astype(np.float64)
        tri = np.array([list(p.vertices) for p in o.data.polygons])
        pts = np.vstack(
            [
                v,
                v[tri].mean(axis=1),
                0.5 * (v[tri[:, 0]] + v[tri[:, 1]]),
                0.5 * (v[tri[:, 1]] + v[tri[:, 2]]),
                0.5 * (v[tri[:, 2]] + v[tri[:, 0]]),
            ]
        )
        m = np.array(o.matrix_world)
        world = pts @ m[:3, :3].T + m[:3, 3]
        clip = np.hstack([world, np.ones((len(world), 1))]) @ (proj @ view).T
        ndc = clip[:, :2] / clip[:, 3:4]
        col = np.floor((ndc[:, 0] + 1) * 0.5 * w).astype(int)
        row = np.floor((1 - ndc[:, 1]) * 0.5 * h).astype(int)
        ok = (col >= 0) & (col < w) & (row >= 0) & (row < h)
        mask[row[ok], col[ok]] = True
    return mask


def test_studio_replaces_the_startup_scene(scene, bpy_session):
    bpy = scene.bpy
    sc = bpy.context.scene
    # the startup objects stay in the file, out of the render
    assert bpy.data.objects["Cube"].hide_render and bpy.data.objects["Light"].hide_render
    assert sc.render.engine == "CYCLES" and sc.cycles.device == "CPU"
    assert sc.cycles.use_denoising and sc.cycles.use_adaptive_sampling
    assert (sc.render.resolution_x, sc.render.resolution_y) == (1080, 1440)
    assert sc.render.resolution_percentage == PCT
    studio = scene.mod("render_studio")
    body = scene.objects("body")[0]
    garment = scene.objects("garment")[0]
    # each view's camera sees the whole body and garment, which fill most of the frame's height
    from bpy_extras.object_utils import world_to_camera_view

    for view in ("FRONT", "THREE_QUARTER", "BACK"):
        cam = bpy.data.objects[studio.camera_name(view)]
        ndc = []
        for o in (body, garment):
            m = np.array(o.matrix_world)
            v = scene.verts(o)[::25] @ m[:3, :3].T + m[:3, 3]
            from mathutils import Vector

            ndc += [tuple(world_to_camera_view(sc, cam, Vector(p))) for p in v]
        ndc = np.array(ndc)
        assert ndc[:, :2].min() > 0.0 and ndc[:, :2].max() < 1.0 and ndc[:, 2].min() > 0, view
        assert ndc[:, 1].max() - ndc[:, 1].min() > 0.7, view
    # the back camera is behind the body, the front one in front of it (the body faces -Y)
    assert bpy.data.objects[studio.camera_name("FRONT")].location.y < body.location.y - 1
    assert bpy.data.objects[studio.camera_name("BACK")].location.y > body.location.y + 1
    # the floor is at the feet
    floor = bpy.data.objects[studio.SET]
    assert abs(floor.location.z - scene.world_box(body)[0][2]) < 0.01
    # running it again reuses the studio's objects
    n = len(bpy.data.objects)
    assert bpy.ops.ease.studio_setup() == {"FINISHED"}
    assert len(bpy.data.objects) == n


def test_garment_wears_its_fabric(scene, bpy_session):
    bpy = scene.bpy
    mats = scene.mod("materials")
    from importlib import import_module

    core = import_module(f"{scene.module}.core.drape.materials")
    g = scene.objects("garment")[0]
    assert g.data.materials[0].name == "EASE Fabric cotton"
    assert g.modifiers["EASE Thickness"].thickness == pytest.approx(core.PRESETS["cotton"].thickness)
    # the weave's UV map is the pattern in metres with V along the grain: each garment edge's UV
    # length is its pattern length (the weave's mm are the cloth's mm)
    # (on a refined drape mesh, the Drape panel's default, the pattern as draped: its triangles are the garment's)
    pattern = scene.mod("build").drape_pattern(g, scene.mod("data").stored_pattern(bpy.context.scene))
    uv = np.empty(len(g.data.loops) * 2, dtype=np.float32)
    g.data.uv_layers[mats.FABRIC_UV].data.foreach_get("uv", uv)
    uv = uv.reshape(-1, 3, 2)
    p0 = pattern.panels[0]
    f0 = p0.uv[p0.faces[: len(p0.faces)]]
    got = np.linalg.norm(uv[: len(p0.faces), 1] - uv[: len(p0.faces), 0], axis=1)
    want = np.linalg.norm(f0[:, 1] - f0[:, 0], axis=1)
    assert np.allclose(got, want, atol=1e-6)
    grain_dir = (f0[:, 1] - f0[:, 0]) @ p0.grain
    assert np.allclose(uv[: len(p0.faces), 1, 1] - uv[: len(p0.faces), 0, 1], grain_dir, atol=1e-6)
    # seam distance: 0 on the sewn edges' corners, growing inwards; hem distance 0 on the hems
    seam = np.empty(len(g.data.loops), dtype=np.float32)
    g.data.attributes[mats.SEAM_DIST].data.foreach_get("value", seam)
    hem = np.empty(len(g.data.loops), dtype=np.float32)
    g.data.attributes[mats.HEM_DIST].data.foreach_get("value", hem)
    corners = p0.faces.ravel()
    hem_verts = {int(i) for h in p0.hems for i in h}
    on_boundary = np.isin(corners, np.concatenate(p0.boundary))
    first = slice(0, corners.size)
    sewn_only = on_boundary & ~np.isin(corners, list(hem_verts))
    assert sewn_only.any() and np.all(seam[first][sewn_only] < 1e-6)
    assert np.all(hem[first][np.isin(corners, list(hem_verts))] < 1e-6)
    inner = seam[first][~on_boundary]
    assert inner.min() > 0 and np.median(inner) > 0.02 and seam.max() > 0.05
    # the weave is scaled in mm: the preset's thread repeat
    nodes = g.data.materials[0].node_tree.nodes
    assert mats.LOOKS["cotton"].weave == "plain"
    assert any(
        n.type == "BUMP" and abs(n.inputs["Distance"].default_value - 0.3e-3 * mats.LOOKS["cotton"].thread_mm) < 1e-9
        for n in nodes
    )
    bsdf = next(n for n in nodes if n.type == "BSDF_PRINCIPLED")
    assert bsdf.inputs["Sheen Weight"].default_value > 0 and bsdf.inputs["Normal"].is_linked


def _evaluated_verts(bpy, obj) -> np.ndarray:
    """(V, 3) object-space vertices of ``obj`` with its modifiers applied."""
    ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    co = np.empty(len(ev.data.vertices) * 3, dtype=np.float32)
    ev.data.vertices.foreach_get("co", co)
    return co.reshape(-1, 3).astype(np.float64)


def _pressed_pleat(bpy, name: str):
    """A strip of cloth folded flat on itself (a pressed pleat: 5 cm long, each layer 1 cm wide,
    0.3 mm apart at the open side, its two triangle rows at 178 degrees along the fold), the
    shape a drape takes where a fold collapses (a gather, an elbow, a neckline)."""
    xs = np.linspace(0.0, 0.05, 6)
    fold = [(x, 0.0, 0.0) for x in xs]
    top = [(x, 0.01, 0.0003) for x in xs]
    bottom = [(x, 0.01, 0.0) for x in xs]
    verts = fold + top + bottom
    n = len(xs)
    faces = []
    for i in range(n - 1):  # one orientation across the fold: the layers' normals point apart
        faces += [(i, i + 1, n + i + 1), (i, n + i + 1, n + i)]
        faces += [(i, 2 * n + i, 2 * n + i + 1), (i, 2 * n + i + 1, i + 1)]
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    obj = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(obj)
    return obj, np.asarray(verts, dtype=np.float64)


def test_thickness_makes_no_spikes(scene, bpy_session):
    """The fabric's thickness (Solidify) moves no vertex farther than half of it, on the drape and
    where the cloth folds flat on itself: Even Thickness divided the offset by the cosine between
    the vertex normal and its faces' (~0 at a flat fold) and drew spikes several cm long out of
    the shoulder seams, the neckline and the gathered armholes."""
    bpy = scene.bpy
    fab = scene.mod("render_fabric")
    g = scene.objects("garment")[0]
    t = g.modifiers[fab.THICKNESS].thickness
    src, solid = scene.verts(g).astype(np.float64), _evaluated_verts(bpy, g)
    assert len(solid) == 2 * len(src)  # both faces of the cloth
    assert np.abs(np.linalg.norm(solid.reshape(2, -1, 3) - src, axis=2) - 0.5 * t).max() < 1e-5
    obj, verts = _pressed_pleat(bpy, "pleat")
    try:
        fab.thicken(obj, t)
        solid = _evaluated_verts(bpy, obj)
        assert len(solid) == 2 * len(verts)
        move = np.linalg.norm(solid.reshape(2, -1, 3) - verts, axis=2)
        assert move.max() < 0.5 * t * 1.001, move.max()
    finally:
        bpy.data.objects.remove(obj)


def test_tiny_render_shows_body_garment_and_shadow(scene, bpy_session):
    """64 x 86 pixels, 4 samples: (1) the beauty render; (2) body and garment as holdouts on a
    transparent film: their pixels are those they project to, so nothing stands in front of
    them; (3) without their shadows the floor at their feet is lighter."""
    bpy = scene.bpy
    sc = bpy.context.scene
    body, garment = scene.objects("body")[0], scene.objects("garment")[0]
    beauty = _render(scene, "beauty.png")
    h, w = beauty.shape[:2]
    assert (w, h) == (64, 86)
    assert beauty[..., :3].std() > 0.03, "a flat image"
    expected = _projected_mask(scene, [body, garment], (h, w))
    expected_garment = _projected_mask(scene, [garment], (h, w))
    sc.render.film_transparent = True
    try:
        body.is_holdout = garment.is_holdout = True
        both = _render(scene, "holdout.png")[..., 3] < 0.5
        body.is_holdout = False
        only_garment = _render(scene, "holdout_garment.png")[..., 3] < 0.5
    finally:
        body.is_holdout = garment.is_holdout = False
        sc.render.film_transparent = False
    share = both.mean()
    assert 0.08 < share < 0.5, share  # a body framed, not a speck
    iou = (both & expected).sum() / (both | expected).sum()
    assert iou > 0.75, iou  # nothing in front, where expected
    assert only_garment.mean() > 0.6 * expected_garment.mean() > 0.01
    assert only_garment.sum() <= both.sum()
    # the floor's contact shadow: the floor pixels just around the feet, with and without it
    rows = np.flatnonzero(both.any(axis=1))
    low = rows.max() - max(2, (rows.max() - rows.min()) // 10)  # the lowest tenth: the feet
    cols = np.flatnonzero(both[low:].any(axis=0))
    region = np.zeros_like(both)
    region[low - 2 : min(rows.max() + 3, h), max(cols.min() - 3, 0) : cols.max() + 4] = True
    dilated = both.copy()
    for dr, dc in itertools.product((-1, 0, 1), repeat=2):
        dilated |= np.roll(np.roll(both, dr, 0), dc, 1)
    region &= ~dilated
    assert region.sum() >= 5
    lum = beauty[..., :3].mean(axis=2)
    try:
        body.visible_shadow = garment.visible_shadow = False
        lit = _render(scene, "no_shadow.png")[..., :3].mean(axis=2)
    finally:
        body.visible_shadow = garment.visible_shadow = True
    ratio = np.sort(lum[region] / lit[region])
    # the floor around the feet darker, and clearly so where the feet touch it (its darkest tenth)
    assert ratio.mean() < 0.97 and ratio[: max(1, len(ratio) // 10)].mean() < 0.9, ratio


def test_all_views_and_turntable(scene, bpy_session):
    bpy = scene.bpy
    s = bpy.context.scene.ease
    s.render_resolution, s.render_samples = 5, 1
    try:
        s.render_view = "ALL"
        s.render_path = str(scene.tmp / "views.png")
        assert bpy.ops.ease.render() == {"FINISHED"}
        for v in ("front", "three_quarter", "back"):
            assert (scene.tmp / f"views_{v}.png").is_file()
        s.render_view = "PATTERN"
        s.render_path = str(scene.tmp / "pattern.png")
        assert bpy.ops.ease.render() == {"FINISHED"}
        px = _pixels(bpy, s.render_path)
        assert px[..., :3].std() > 0.02
        s.render_turntable_frames = 3
        s.render_path = str(scene.tmp / "turn.png")
        assert bpy.ops.ease.render_turntable() == {"FINISHED"}
        assert sorted(p.name for p in scene.tmp.glob("turn_*.png")) == [f"turn_000{i}.png" for i in (1, 2, 3)]
    finally:
        s.render_view, s.render_resolution, s.render_samples = "FRONT", PCT, SAMPLES


def test_pattern_pieces_and_labels_do_not_overlap(scene, bpy_session):
    pieces = scene.objects("pattern_panel")
    labels = [o for o in scene.objects("pattern_panel_part") if o.type == "FONT"]
    assert len(labels) == len(pieces) >= 2

    def apart(a, b):
        (alo, ahi), (blo, bhi) = scene.world_box(a), scene.world_box(b)
        return any(ahi[i] <= blo[i] or bhi[i] <= alo[i] for i in (0, 2))

    for a, b in itertools.combinations(pieces, 2):
        assert apart(a, b), (a.name, b.name)
    for a, b in itertools.combinations(labels, 2):
        assert apart(a, b), (a.name, b.name)
    for lab in labels:  # inside its piece's width
        (llo, lhi), (plo, phi) = scene.world_box(lab), scene.world_box(lab.parent)
        assert plo[0] <= llo[0] and lhi[0] <= phi[0], lab.name


def test_design_colour_reaches_the_garment(scene, bpy_session):
    bpy = scene.bpy
    sc = bpy.context.scene
    mats, fab = scene.mod("materials"), scene.mod("render_fabric")
    pattern = scene.mod("data").stored_pattern(sc)
    garment = next(iter(pattern.garments))
    pattern.materials["color"] = {garment: "#ff8000"}
    try:
        assert fab.dress_garments(sc) == 1
        g = scene.objects("garment")[0]
        c = np.empty(len(g.data.loops) * 4, dtype=np.float32)
        g.data.attributes[mats.FABRIC_COLOR].data.foreach_get("color", c)
        assert np.allclose(c.reshape(-1, 4)[0], [1.0, fab.srgb_to_linear(128 / 255), 0.0, 1.0], atol=1e-5)
    finally:
        del pattern.materials["color"]
        fab.dress_garments(sc)
    # without one: the preset's colour
    c = np.empty(len(g.data.loops) * 4, dtype=np.float32)
    g.data.attributes[mats.FABRIC_COLOR].data.foreach_get("color", c)
    assert np.allclose(c.reshape(-1, 4)[0, :3], mats.LOOKS["cotton"].color, atol=1e-6)
    assert json.loads(sc.ease.design_json)["materials"]["fabric"] == "cotton"


def test_fabric_of_an_earlier_version_is_rebuilt_in_place(scene, bpy_session):
    """A saved file's fabric made by an earlier add-on (no look version): rebuilt, same datablock."""
    bpy = scene.bpy
    mats = scene.mod("materials")
    old = bpy.data.materials.new("EASE Fabric silk")
    try:
        assert "ease_look" not in old
        mat = mats.fabric("silk")
        assert mat == old and mat["ease_look"] == mats.LOOK_VERSION and mat["ease_fabric"] == "silk"
        bsdf = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
        assert bsdf.inputs["Roughness"].default_value == pytest.approx(mats.LOOKS["silk"].roughness)
        assert bsdf.inputs["Normal"].is_linked and len(mat.node_tree.nodes) > 30
        assert mats.fabric("silk") == mat  # current: kept as it is
    finally:
        bpy.data.materials.remove(old)
