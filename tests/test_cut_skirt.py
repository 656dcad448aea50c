"""Skirt topology (core.cut.skirt) on Anny, and a two-panel skirt cut on it."""

import numpy as np
import pytest
import scipy.sparse as sp
from cut_anny_shirt import ray_point
from cut_synth import triangle_areas
from scipy.sparse.csgraph import connected_components

from core.cut.engine import cut_surface
from core.cut.skirt import inter_leg_faces, make_skirt
from core.cut.split import CutMesh
from core.design.spec import CutLine, CutSpec, GarmentSpec, PanelSpec


def section_loops(X, F, z0):
    """Number of closed curves in which the plane z = z0 cuts the mesh."""
    s = X[:, 2] - z0
    a = F.reshape(-1)
    b = np.roll(F, -1, 1).reshape(-1)
    crossed = np.sign(s[a]) != np.sign(s[b])
    fid = np.arange(len(a)) // 3
    n = len(X)
    key = np.minimum(a, b) * n + np.maximum(a, b)
    sel = np.nonzero(crossed)[0]
    order = np.argsort(key[sel], kind="stable")
    k = key[sel][order]
    same = k[1:] == k[:-1]
    i, j = fid[sel][order][:-1][same], fid[sel][order][1:][same]
    faces = np.unique(fid[sel])
    idx = {f: t for t, f in enumerate(faces.tolist())}
    A = sp.coo_matrix(
        (np.ones(len(i)), ([idx[x] for x in i.tolist()], [idx[x] for x in j.tolist()])), shape=(len(faces), len(faces))
    )
    return connected_components(A, directed=False)[0]


def test_skirt_topology_is_one_closed_tube(anny, anny_reference):
    body, (X, _) = anny, anny_reference
    F = np.asarray(body.faces)
    mesh = CutMesh(X, F)
    make_skirt(mesh, body, X)
    Fm = mesh.F
    nv = mesh.nv
    a = Fm.reshape(-1)
    b = np.roll(Fm, -1, 1).reshape(-1)
    key = a * nv + b
    assert len(np.unique(key)) == len(key)  # oriented manifold
    assert np.isin(key, b * nv + a).all()  # closed: no boundary edge
    used = np.unique(Fm)
    E = len(np.unique(np.minimum(a, b) * nv + np.maximum(a, b)))
    assert len(used) - E + len(Fm) == 2  # still a sphere
    crotch = body.landmarks["crotch"].position(X, F)[2]
    knee = body.landmarks["knee_left"].position(X, F)[2]
    for t in (0.3, 0.6):
        z0 = crotch + t * (knee - crotch)
        assert section_loops(X, np.asarray(F), z0) == 2  # two legs on the body
        assert section_loops(mesh.X, Fm, z0) == 1  # one tube around both legs
    # the bridge follows any shape and pose: its corners are body vertices or midpoints of a
    # body vertex and its mirror (on the midline)
    S = np.asarray(body.symmetry)
    added = range(len(X), mesh.nv)
    assert len(added) > 10
    for v in added:
        cols, vals = mesh.weights[v]
        assert len(cols) == 2 and S[cols[0]] == cols[1] and np.allclose(vals, 0.5)
        assert abs(mesh.X[v, 0]) < 1e-12


def _mirror_keys(mesh, S):
    """Sorted-corner keys of every face and of its mirror image (added midline vertices are
    their own mirror)."""
    m = np.arange(mesh.nv)
    m[: len(S)] = S
    key = lambda T: set(map(tuple, np.sort(T, axis=1).tolist()))
    return key(mesh.F), key(m[mesh.F])


def test_skirt_topology_is_its_own_mirror(anny, anny_reference):
    # the band, the curtains and their midline split are mirror images: every face's mirror is
    # a face, and every bridge face lies on one side of the midline (the sides returned)
    body, (X, _) = anny, anny_reference
    mesh = CutMesh(X, np.asarray(body.faces))
    sides = make_skirt(mesh, body, X)
    faces, mirrored = _mirror_keys(mesh, np.asarray(body.symmetry))
    assert faces == mirrored
    assert sides is not None and len(sides) == mesh._ptri_count() - len(body.faces)
    bridge = mesh.F[mesh.parent >= len(body.faces)]
    x = mesh.X[bridge][..., 0]
    on_mid = np.abs(x) < 1e-12
    assert len(bridge) == len(sides) and sides.sum() == len(sides) // 2
    got = np.where(np.where(on_mid, 0.0, x).sum(1) > 0, 1, 0)
    np.testing.assert_array_equal(got, sides[mesh.parent[mesh.parent >= len(body.faces)] - len(body.faces)])
    assert not np.any((x > 1e-12).any(1) & (x < -1e-12).any(1))  # none across the midline


def test_skirt_topology_without_a_symmetry_map(anny, anny_reference):
    # no symmetry map: the legs are zipped directly, as one closed tube, with no new vertices
    import copy

    body, (X, _) = anny, anny_reference
    plain = copy.copy(body)
    plain.symmetry = None
    mesh = CutMesh(X, np.asarray(body.faces))
    assert make_skirt(mesh, plain, X) is None
    assert mesh.nv == len(X)
    a = mesh.F.reshape(-1)
    b = np.roll(mesh.F, -1, 1).reshape(-1)
    assert np.isin(a * mesh.nv + b, b * mesh.nv + a).all()
    faces, mirrored = _mirror_keys(mesh, np.asarray(body.symmetry))
    assert faces != mirrored  # the zip is not a mirror image


def test_inter_leg_band_is_symmetric(anny, anny_reference):
    body, (X, _) = anny, anny_reference
    H = inter_leg_faces(body, X)
    assert 50 < H.sum() < 0.1 * len(H)
    F = np.asarray(body.faces)
    c = X[F[H]].mean(1)
    assert abs(c[:, 0].mean()) < 0.01


def skirt_spec(body, X, J, refine=0.01):
    lm = body.landmarks
    F = np.asarray(body.faces)
    jn = body.joint_names
    pos = {k: v.position(X, F) for k, v in lm.items()}
    hem = []
    for S, out in (("L", 1.0), ("R", -1.0)):
        k = J[jn.index(f"lowerleg01.{S}")] + [0, 0, 0.08]  # just above the knee
        hem.append([ray_point(body, X, k, d) for d in ([out, 0, 0], [0, -1, 0], [0, 1, 0])])
    (lo, lf, lb), (ro, rf, rb) = hem
    centre = np.array([0.0, 0.5 * (pos["waist_front"][1] + pos["waist_back"][1]), pos["hip_left"][2]])
    lines = [
        CutLine(
            "skirt.waist",
            [lm["waist_front"], lm["waist_left"], lm["waist_back"], lm["waist_right"]],
            closed=True,
            role="opening",
        ),
        CutLine("skirt.hem", [lo, lb, rb, ro, rf, lf], closed=True, role="opening"),
        CutLine("skirt.side_left", [lm["waist_left"], lo]),
        CutLine("skirt.side_right", [lm["waist_right"], ro]),
    ]
    panels = [
        PanelSpec("skirt.front", "skirt", ray_point(body, X, centre, [0, -1, 0])),
        PanelSpec("skirt.back", "skirt", ray_point(body, X, centre, [0, 1, 0])),
    ]
    return CutSpec(
        lines,
        panels,
        [GarmentSpec("skirt", "lower", pin_line="skirt.waist")],
        skirt=True,
        refine_edge_length=refine,
        body={"model": "anny"},
    )


def test_skirt_cut(anny, anny_reference):
    body, (X, J) = anny, anny_reference
    spec = skirt_spec(body, X, J)
    cut = cut_surface(body, X, spec)
    assert [p.name for p in cut.panels] == ["skirt.front", "skirt.back"]
    G = cut.positions(X)
    for p in cut.panels:
        assert len(p.boundary) == 1
        # front/back panels span both legs: their hem goes across the bridge
        P = G[p.vertex_ids]
        assert P[:, 0].min() < -0.1 and P[:, 0].max() > 0.1
        h = np.concatenate(cut.hems[p.name])
        assert np.ptp(P[h][:, 0]) > 0.2
    assert {s.name for s in cut.seams} == {"skirt.side_left", "skirt.side_right"}
    for s in cut.seams:
        a, b = cut.panel(s.panel_a), cut.panel(s.panel_b)
        np.testing.assert_array_equal(a.vertex_ids[s.verts_a], b.vertex_ids[s.verts_b])
    # the hem of front and back together is one closed loop around both legs
    hem = np.concatenate(
        [
            cut.panel(n).vertex_ids[h]
            for n in ("skirt.front", "skirt.back")
            for h in cut.hems[n]
            if G[cut.panel(n).vertex_ids[h]][:, 2].mean() < -0.2
        ]
    )
    ends, counts = np.unique(hem, return_counts=True)
    assert (counts <= 2).all()
    # transfers to poses with the same topology and non-degenerate triangles
    for pose in ("P1", "P3"):
        V = body.vertices(None, pose)
        Gp = cut.positions(V)
        for p in cut.panels:
            assert triangle_areas(Gp[p.vertex_ids], p.faces).min() > 0


def test_overlapping_garments_are_cut_separately(anny, anny_reference):
    """A shirt whose hem is below the skirt's waistband: each garment keeps its panels."""
    from cut_anny_shirt import shirt_spec

    body, (X, J) = anny, anny_reference
    shirt = shirt_spec(body, X, J, refine=None)
    skirt = skirt_spec(body, X, J, refine=None)
    both = CutSpec(
        shirt.lines + skirt.lines,
        shirt.panels + skirt.panels,
        shirt.garments + skirt.garments,
        skirt=True,
        refine_edge_length=None,
    )
    cut = cut_surface(body, X, both)
    # alone, each on the same surface as together: the skirt topology's, spanned over the cleft
    # (core.cut.span), which the shirt's back also reaches
    shirt_on_skirt = CutSpec(shirt.lines, shirt.panels, shirt.garments, skirt=True, refine_edge_length=None)
    alone = {"shirt": cut_surface(body, X, shirt_on_skirt), "skirt": cut_surface(body, X, skirt)}
    G = cut.positions(X)
    assert cut.garments == {"shirt": "upper", "skirt": "lower"}
    for name, ref in alone.items():
        Gr = ref.positions(X)
        for p in ref.panels:
            q = cut.panel(p.name)
            np.testing.assert_allclose(
                triangle_areas(G[q.vertex_ids], q.faces).sum(),
                triangle_areas(Gr[p.vertex_ids], p.faces).sum(),
                rtol=1e-9,
            )
    ids = {g: np.concatenate([p.vertex_ids for p in cut.panels if p.garment == g]) for g in ("shirt", "skirt")}
    assert not set(ids["shirt"].tolist()) & set(ids["skirt"].tolist())
    assert set(cut.pins) == {"shirt", "skirt"}


def test_points_on_the_removed_band(anny, anny_reference):
    """A keypoint on a removed triangle goes to the closest point of the bridged surface;
    a panel seed there is an error naming the panel."""
    from core.body.model import SurfacePoint
    from core.errors import CutError

    body, (X, J) = anny, anny_reference
    removed = np.nonzero(inter_leg_faces(body, X))[0]
    F = np.asarray(body.faces)
    c = X[F[removed]].mean(1)
    k = removed[np.argmin(np.abs(c[:, 2] - (c[:, 2].max() - 0.15)) + 10 * (c[:, 1] > c[:, 1].mean()))]
    sp_ = SurfacePoint(int(k), (1 / 3, 1 / 3, 1 / 3))
    spec = skirt_spec(body, X, J, refine=None)
    # hem through a point on the inner thigh band (front): still one loop, still cuts
    hem = spec.lines[1]
    hem.points = hem.points[:5] + [sp_] + hem.points[5:]
    cut = cut_surface(body, X, spec)
    assert [p.name for p in cut.panels] == ["skirt.front", "skirt.back"]
    spec.panels[0] = PanelSpec("skirt.front", "skirt", sp_)
    with pytest.raises(CutError, match="skirt.front.*removed"):
        cut_surface(body, X, spec)
