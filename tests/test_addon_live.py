"""Live mode (ease_addon.live): a painted change of the ease layer re-solves the pattern with the kept
factorisation and updates the pattern objects in place; the loop converges to the cold solve of the
painted field; a topology change rebuilds once; undo after a live update restores the previous pattern.

Headless, strokes are written as attribute data (a paint stroke segfaults without a window) and the
timer's tick (:func:`ease_addon.live.step`) is called directly, as the timer would call it.
"""
from __future__ import annotations

import numpy as np
import pytest

DESIGN = "top_sleeveless.json"     # cheapest template: two panels


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """This module's starting scene: a body, the design with piecewise ease, its pattern, Live on."""
    blender.reset(body=True, design=DESIGN, piecewise_ease=True, pattern=True)
    blender.scene.ease.live = True
    yield blender
    blender.scene.ease.live = False


def _stroke(blender, ease: float, seed: int):
    """Paint ``ease`` on a brush-sized patch (6 cm) around a random vertex of the garment."""
    bpy = blender.bpy
    ease_ops, data = blender.mod("ease_ops"), blender.mod("data")
    obj = bpy.context.scene.ease.body
    cut = data.current_cut(bpy.context)
    on = np.unique(cut.embedding.tocsr().indices)
    verts = blender.verts(obj).astype(np.float64)
    c = verts[np.random.default_rng(seed).choice(on)]
    mask = np.linalg.norm(verts - c, axis=1) < 0.06
    ease_ops.write_vertex_ease(obj, bpy.context.scene, ease, mask)
    return mask


def _converge(blender, limit=500):
    live = blender.mod("live")
    for _ in range(limit):
        if live.step(blender.bpy.context)["converged"]:
            return
    raise AssertionError("live mode did not converge")


def _pieces(blender):
    return {o.name: blender.verts(o).copy() for o in blender.objects("pattern_panel")}


def _names(bpy):
    return (sorted(o.name for o in bpy.data.objects), sorted(m.name for m in bpy.data.meshes),
            sorted(c.name for c in bpy.data.curves))


def _stored_uv(blender):
    p = blender.mod("data").stored_pattern(blender.bpy.context.scene)
    return {q.name: np.asarray(q.uv) for q in p.panels}


def test_live_update_in_place_and_convergence_to_the_cold_solve(blender):
    bpy = blender.bpy
    live = blender.mod("live")
    _converge(blender)                       # adopt the layer as it is
    before, names = _pieces(blender), _names(bpy)
    _stroke(blender, 1.75, seed=3)
    out = live.step(bpy.context)
    assert out["changed"] and out["iterations"] >= 1 and not out["converged"]
    after = _pieces(blender)
    assert _names(bpy) == names                              # no new object, mesh or curve, no new name
    assert sorted(after) == sorted(before)
    assert any(not np.array_equal(before[k], after[k]) for k in before)   # the pieces moved
    _converge(blender)
    assert _names(bpy) == names
    # converged: the stored pattern is the cold solve of the painted field (bitwise: the same solver
    # with the same targets from the same start) and the piece objects show it
    session = live.session_for(bpy.context)
    cold = session.cold_pattern(live._field(bpy.context.scene.ease.body, bpy.context.scene))
    stored = _stored_uv(blender)
    for p in cold.panels:
        assert np.allclose(stored[p.name], p.uv, rtol=0, atol=1e-12)
        o = next(o for o in blender.objects("pattern_panel") if o["ease_panel"] == p.name)
        assert np.allclose(blender.verts(o)[:, [0, 2]], p.uv, atol=1e-6)      # float32 mesh
    import json
    figures = json.loads(bpy.context.scene.ease.pattern_json)
    assert figures["ease compliance mean %"] == pytest.approx(cold.report["metrics"]["compliance"]["mean"], abs=1e-3)
    # the fit overlay: per face on its corners, finite colours, grey off the garment
    me = bpy.context.scene.ease.body.data
    fit = me.color_attributes.get(live.FIT_LAYER)
    assert fit is not None and fit.domain == "CORNER"
    assert me.color_attributes.active_color_name == "ease"    # painting still paints the ease layer
    rgba = np.empty(len(fit.data) * 4, dtype=np.float32)
    fit.data.foreach_get("color", rgba)
    rgba = rgba.reshape(-1, 3, 4)[:, 0]
    tri = np.unique(session.triangles)
    assert not np.allclose(rgba[tri, :3], 0.5) and np.allclose(np.delete(rgba, tri, axis=0)[:, :3], 0.5)
    assert len(bpy.context.scene.ease.live_legend) == 5
    # converged: a tick without a change does no work
    assert live.step(bpy.context)["iterations"] == 0


def test_topology_change_rebuilds_once(blender):
    bpy = blender.bpy
    live = blender.mod("live")
    _converge(blender)
    builds = live._LIVE["builds"]
    s = bpy.context.scene.ease
    name = s.design_params[0].name
    p = s.design_params[0]
    assert bpy.ops.ease.set_parameter(name=name, value=0.5 * (p.value + p.max)) == {"FINISHED"}
    live.step(bpy.context)
    assert live._LIVE["builds"] == builds + 1
    _converge(blender)
    _stroke(blender, 1.3, seed=5)
    _converge(blender)
    assert live._LIVE["builds"] == builds + 1
    assert blender.objects("pattern_panel")


def test_undo_restores_the_previous_pattern(blender):
    bpy = blender.bpy
    live = blender.mod("live")
    _converge(blender)
    bpy.ops.ed.undo_push(message="before")
    _stroke(blender, 1.6, seed=7)
    _converge(blender)                      # pushes the stroke's step
    first, first_uv = bpy.context.scene["ease_pattern_json"], _stored_uv(blender)
    layer = live._colors(bpy.context.scene.ease.body)
    _stroke(blender, 1.05, seed=8)
    assert live.step(bpy.context)["changed"]      # a live update
    _converge(blender)
    second = _stored_uv(blender)
    assert any(not np.array_equal(second[k], first_uv[k]) for k in first_uv)
    assert bpy.ops.ed.undo() == {"FINISHED"}
    # one step back: the paint and the pattern before the last stroke
    assert bpy.context.scene["ease_pattern_json"] == first
    assert np.array_equal(live._colors(bpy.context.scene.ease.body), layer)
    # the loop picks up the restored paint and pattern and converges to the same pattern again
    _converge(blender)
    assert all(np.array_equal(_stored_uv(blender)[k], first_uv[k]) for k in first_uv)


def test_strokes_faster_than_convergence_keep_one_step_each(blender):
    """A stroke that comes before the previous one converged first pushes the previous one's step:
    undo still goes back one stroke (its paint), and the loop converges to its pattern."""
    bpy = blender.bpy
    live = blender.mod("live")
    _converge(blender)
    bpy.ops.ed.undo_push(message="before")
    _stroke(blender, 1.5, seed=11)
    assert live.step(bpy.context)["changed"]
    layer_a = live._colors(bpy.context.scene.ease.body)
    _stroke(blender, 1.15, seed=12)
    assert live.step(bpy.context)["changed"]      # pushes stroke A's step first
    _converge(blender)
    assert bpy.ops.ed.undo() == {"FINISHED"}
    assert np.array_equal(live._colors(bpy.context.scene.ease.body), layer_a)
    _converge(blender)
    session = live.session_for(bpy.context)
    cold = session.cold_pattern(live._field(bpy.context.scene.ease.body, bpy.context.scene))
    stored = _stored_uv(blender)
    assert all(np.allclose(stored[p.name], p.uv, rtol=0, atol=1e-12) for p in cold.panels)
