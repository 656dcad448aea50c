"""The GLB and OBJ of core.export.mesh read back by Blender's own importers (the session's bpy)."""

import numpy as np
import pytest
from export_synth import drape_positions, make_pattern

from core.export import export_pattern


def _mesh_arrays(obj):
    me = obj.data
    co = np.zeros(len(me.vertices) * 3)
    me.vertices.foreach_get("co", co)
    m = np.array(obj.matrix_world)
    co = co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3]
    uvl = me.uv_layers[0]
    uv = np.zeros(len(uvl.data) * 2)
    uvl.data.foreach_get("uv", uv)
    loops = np.zeros(len(me.loops), int)
    me.loops.foreach_get("vertex_index", loops)
    return co, uv.reshape(-1, 2), loops


def _body():
    """A small tetrahedron 'body' in the core frame (Z up), around the garment."""
    v = np.array([[0.0, 0.0, 0.5], [0.3, 0.0, 1.0], [-0.2, 0.25, 1.2], [0.0, -0.3, 1.6]])
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    return v, f


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    pat = make_pattern(rotate_back_deg=0.0)
    pos = drape_positions(pat)
    out = tmp_path_factory.mktemp("mesh")
    export_pattern(pat, out / "z", formats="glb,obj", drape_positions=pos, body=_body(), up="z", origin="root")
    export_pattern(pat, out / "y", formats="obj", drape_positions=pos, up="y", origin="root")
    export_pattern(pat, out / "default", formats="glb,obj", drape_positions=pos, body=_body())
    return pat, pos, out


@pytest.mark.parametrize("fmt,up", [("glb", "z"), ("obj", "z"), ("obj", "y"), ("glb", "default"), ("obj", "default")])
def test_blender_imports_positions_and_pattern_uvs(bpy_session, exported, fmt, up):
    """Every file comes back in Blender's Z-up frame at the draped positions: the GLB (always Y-up) and the
    Y-up OBJ (the default) through the importers' default axes, the Z-up OBJ with up Z, forward Y. By default
    (origin floor) the body stands on the floor: everything 0.5 m higher (the test body's lowest point)."""
    bpy = bpy_session["bpy"]
    pat, pos, out = exported
    out = out / up
    lift = np.array([0.0, 0.0, -_body()[0][:, 2].min()]) if up == "default" else np.zeros(3)
    bpy.ops.wm.read_homefile(use_empty=True)  # an empty scene; the session's preferences stay
    if fmt == "glb":
        bpy.ops.import_scene.gltf(filepath=str(out / "garment.glb"))
    elif up in ("y", "default"):
        bpy.ops.wm.obj_import(filepath=str(out / "garment.obj"))
    else:
        bpy.ops.wm.obj_import(filepath=str(out / "garment.obj"), up_axis="Z", forward_axis="Y")
    meshes = {o.name: o for o in bpy.data.objects if o.type == "MESH"}
    with_body = up in ("z", "default")
    assert sorted(meshes) == sorted([p.name for p in pat.panels] + (["body"] if with_body else []))
    if with_body:  # the body beside the garment, in the same frame
        me = meshes["body"].data
        co = np.zeros(len(me.vertices) * 3)
        me.vertices.foreach_get("co", co)
        m = np.array(meshes["body"].matrix_world)
        np.testing.assert_allclose(co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3], _body()[0] + lift, atol=1e-5)
    for panel in pat.panels:
        co, uv, loops = _mesh_arrays(meshes[panel.name])
        assert len(co) == len(panel.uv) and len(meshes[panel.name].data.polygons) == len(panel.faces)
        # back in Blender's Z-up frame at the draped positions, vertex order kept
        np.testing.assert_allclose(co, pos[panel.vertex_ids] + lift, atol=1e-5)
        # the UV map is the pattern uv (metres; grain along +v)
        np.testing.assert_allclose(uv, panel.uv[loops], atol=1e-5)
