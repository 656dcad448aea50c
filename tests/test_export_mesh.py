"""core.export.mesh: GLB (header, chunks, accessors, UVs = pattern uv) and OBJ with vt."""

import numpy as np
import pytest
from export_synth import drape_positions, make_pattern

from core.export import mesh
from core.export.pieces import build_pieces


@pytest.fixture(scope="module")
def made():
    pat = make_pattern(rotate_back_deg=0.0)  # grain already +v: the exported uv is the pattern uv itself
    pieces = build_pieces(pat)
    pos = drape_positions(pat)
    return pat, pieces, pos, mesh.piece_meshes(pat, pos, [p.rotation for p in pieces])


def test_glb_parses_with_pattern_uvs(made):
    pat, pieces, pos, meshes = made
    data = mesh.glb_bytes(meshes)
    assert data[:4] == b"glTF" and int.from_bytes(data[4:8], "little") == 2
    assert int.from_bytes(data[8:12], "little") == len(data) and len(data) % 4 == 0
    doc, binary = mesh.read_glb(data)
    assert doc["asset"]["version"] == "2.0"
    assert [m["name"] for m in doc["meshes"]] == [p.name for p in pat.panels]
    for m, panel in zip(doc["meshes"], pat.panels):
        prim = m["primitives"][0]
        n, f = len(panel.uv), len(panel.faces)
        acc = {k: doc["accessors"][i] for k, i in prim["attributes"].items()}
        assert acc["POSITION"]["count"] == acc["NORMAL"]["count"] == acc["TEXCOORD_0"]["count"] == n
        assert doc["accessors"][prim["indices"]]["count"] == 3 * f
        uv = mesh.glb_accessor(doc, binary, prim["attributes"]["TEXCOORD_0"])
        # glTF v runs down the image: importers map (u, 1 - v) back to the pattern uv
        np.testing.assert_allclose(np.column_stack([uv[:, 0], 1 - uv[:, 1]]), panel.uv, atol=1e-6)
        p = mesh.glb_accessor(doc, binary, prim["attributes"]["POSITION"])
        xyz = pos[panel.vertex_ids]
        np.testing.assert_allclose(p, np.column_stack([xyz[:, 0], xyz[:, 2], -xyz[:, 1]]), atol=1e-6)
        np.testing.assert_allclose(acc["POSITION"]["min"], p.min(0), atol=1e-6)
        nrm = mesh.glb_accessor(doc, binary, prim["attributes"]["NORMAL"])
        np.testing.assert_allclose(np.linalg.norm(nrm, axis=1), 1.0, atol=1e-5)
        idx = mesh.glb_accessor(doc, binary, prim["indices"]).reshape(-1, 3)
        np.testing.assert_array_equal(idx, panel.faces)
    # every piece node sits under its garment node of the scene
    roots = doc["scenes"][0]["nodes"]
    assert [doc["nodes"][r]["name"] for r in roots] == ["shirt"]
    assert sorted(doc["nodes"][roots[0]]["children"]) == list(range(len(pat.panels)))


def test_uv_follows_the_grain_when_the_piece_is_turned(made):
    pat = make_pattern(rotate_back_deg=40.0)
    pieces = build_pieces(pat)
    meshes = mesh.piece_meshes(pat, drape_positions(pat), [p.rotation for p in pieces])
    back = pat.panel("back")
    uv = meshes[1][4]
    # the warp (grain) direction of the piece maps onto +v of the texture
    e = back.uv[1] - back.uv[0]
    d = uv[1] - uv[0]
    along = np.dot(e, back.grain)
    assert d[1] == pytest.approx(along, abs=1e-12)
    assert np.linalg.norm(d) == pytest.approx(np.linalg.norm(e), abs=1e-12)


def test_normals_point_outward_on_a_cylinder(made):
    pat, pieces, pos, meshes = made
    for name, garment, xyz, nrm, uv, faces in meshes:
        radial = xyz[:, :2] / np.linalg.norm(xyz[:, :2], axis=1)[:, None]
        dots = np.sum(nrm[:, :2] * radial, axis=1)
        assert np.all(np.abs(dots) > 0.9)  # normal is radial (consistently oriented per piece)
        assert len(set(np.sign(dots))) == 1


def test_vertices_in_no_face_get_a_unit_normal():
    xyz = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [3, 3, 3]], float)
    nrm = mesh.smooth_normals(xyz, np.array([[0, 1, 2]]))
    np.testing.assert_allclose(nrm, [[0, 0, 1]] * 4)


def test_obj_has_vertices_uvs_normals_and_faces(made):
    pat, pieces, pos, meshes = made
    text = mesh.obj_text(meshes, pat.style)
    lines = text.splitlines()
    n = sum(len(p.uv) for p in pat.panels)
    assert sum(l.startswith("v ") for l in lines) == n
    assert sum(l.startswith("vt ") for l in lines) == n
    assert sum(l.startswith("vn ") for l in lines) == n
    assert sum(l.startswith("f ") for l in lines) == sum(len(p.faces) for p in pat.panels)
    assert [l[2:] for l in lines if l.startswith("o ")] == [p.name for p in pat.panels]
    vt = np.array([[float(x) for x in l.split()[1:]] for l in lines if l.startswith("vt ")])
    np.testing.assert_allclose(vt, np.vstack([p.uv for p in pat.panels]), atol=1e-6)
    faces = [l.split()[1:] for l in lines if l.startswith("f ")]
    last = faces[-1]
    assert max(int(c.split("/")[0]) for c in last) <= n  # 1-based, within range


def test_one_frame_helper_for_every_mesh_file():
    """core.geom.frame: Y-up is (x, z, -y), a right-handed turn (no mirror) that from_frame undoes; the
    body's up (+Z) becomes +Y and its front (-Y) +Z, as glTF/OBJ readers expect; bad axes are refused."""
    from core.geom import frame

    rng = np.random.default_rng(3)
    v = rng.normal(size=(20, 3))
    y = frame.to_frame(v, "y")
    assert np.allclose(y[:, 1], v[:, 2]) and np.allclose(y[:, 2], -v[:, 1]) and np.allclose(y[:, 0], v[:, 0])
    assert np.allclose(frame.from_frame(y, "y"), v) and np.allclose(frame.to_frame(v, "z"), v)
    turn = frame.to_frame(np.eye(3), "y")  # rows: the images of +X, +Y, +Z
    assert np.isclose(np.linalg.det(turn), 1.0) and np.allclose(turn[2], [0, 1, 0]) and np.allclose(turn[1], [0, 0, -1])
    # (K, V, 3) point caches too, frame by frame
    k = rng.normal(size=(3, 5, 3))
    assert np.allclose(frame.to_frame(k, "y")[1], frame.to_y_up(k[1]))
    assert "+Y up" in frame.frame_text("y") and "+Z up" in frame.frame_text("z", "root", "the body")
    with pytest.raises(ValueError, match="up"):
        frame.to_frame(v, "x")
    # the export's names are the same helpers
    assert mesh.to_frame is frame.to_frame and mesh.frame_text is frame.frame_text


def test_outfit_files_are_the_mesh_writers_with_one_material_a_garment(made):
    from core.export.outfit import LAYER_COLOURS, OUTFIT_MTL, outfit_glb, outfit_obj

    _, _, _, meshes = made
    garments = [("shirt layer", "shirt layer", *m[2:]) for m in meshes[:1]] + [("coat", "coat", *meshes[1][2:])]
    doc, binary = mesh.read_glb(outfit_glb(garments, ["cotton", "wool"]))
    assert doc["scenes"][0]["name"] == "outfit" and "origin on the floor" in doc["asset"]["extras"]["frame"]
    assert [m["name"] for m in doc["materials"]] == ["shirt layer", "coat"]
    assert [m["extras"]["fabric"] for m in doc["materials"]] == ["cotton", "wool"]
    for k, m in enumerate(doc["materials"]):
        assert m["pbrMetallicRoughness"]["baseColorFactor"] == [*LAYER_COLOURS[k], 1.0]
    assert [m["primitives"][0]["material"] for m in doc["meshes"]] == [0, 1]
    plain, _ = mesh.read_glb(mesh.glb_bytes(garments, origin="floor"))
    # the same writer: only the materials and the scene's name differ
    for key in ("accessors", "bufferViews", "nodes"):
        assert doc[key] == plain[key]
    files = outfit_obj(garments, ["cotton", "wool"], "outfit")
    text, mtl = files["outfit.obj"].decode(), files[OUTFIT_MTL].decode()
    assert text.splitlines()[3] == f"mtllib {OUTFIT_MTL}"
    assert [ln for ln in text.splitlines() if ln.startswith("usemtl")] == ["usemtl shirt_layer", "usemtl coat"]
    assert text.replace("usemtl shirt_layer", "usemtl fabric").replace("usemtl coat", "usemtl fabric") == mesh.obj_text(
        garments, "outfit", origin="floor", mtllib=OUTFIT_MTL
    )
    assert "newmtl shirt_layer" in mtl and "# fabric: wool" in mtl
    assert "Kd {:.3f} {:.3f} {:.3f}".format(*LAYER_COLOURS[1]) in mtl
    with pytest.raises(ValueError, match="one material per mesh"):
        mesh.glb_bytes(garments, materials=[])
