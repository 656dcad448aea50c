"""Welding, rest matrices, colouring, bending stencils and tethers (core.drape.mesh)."""

import numpy as np
import pytest
from drape_synth import tube_skirt

from core.drape.mesh import (
    build_cloth,
    colour_order,
    dihedral_angles,
    grain_frame,
    greedy_colouring,
    interior_edges,
    rest_matrices,
    tethers,
    two_rings,
)
from core.errors import DrapeError


def test_grain_frame_weft_is_grain_turned_left():
    f = grain_frame([0.0, 2.0])
    assert np.allclose(f, [[-1.0, 0.0], [0.0, 1.0]])
    with pytest.raises(DrapeError):
        grain_frame([0.0, 0.0])


def test_rest_matrices_map_pattern_to_grain_frame():
    uv = np.array([[0.0, 0.0], [0.0, 0.1], [-0.2, 0.0]])  # warp edge 0.1, weft edge 0.2 (weft = -u)
    inv, area, bad = rest_matrices(uv, np.array([[0, 1, 2]]), [0.0, 1.0])
    assert not bad.any() and area[0] == pytest.approx(0.01)
    # a 3D copy stretched 10 % along the warp: F's warp column has length 1.1, weft 1
    x = np.array([[0, 0, 0], [0, 0, 0.11], [0.2, 0, 0]])
    f = np.stack([x[1] - x[0], x[2] - x[0]], axis=1) @ inv[0]
    assert np.linalg.norm(f[:, 0]) == pytest.approx(1.0)
    assert np.linalg.norm(f[:, 1]) == pytest.approx(1.1)
    _, _, bad = rest_matrices(np.zeros((3, 2)), np.array([[0, 1, 2]]), [0.0, 1.0])
    assert bad.all()


def test_colouring_has_no_shared_vertex_within_a_colour():
    cloth = build_cloth(tube_skirt(1.2, n_rows=6, n_cols=6))
    for elements in (cloth.faces, cloth.bends):
        colours = greedy_colouring(elements, cloth.n_particles)
        for c in np.unique(colours):
            verts = elements[colours == c].ravel()
            assert len(verts) == len(np.unique(verts))
        order, off = colour_order(elements, cloth.n_particles)
        assert off[-1] == len(elements) and np.array_equal(np.sort(order), np.arange(len(elements)))


def test_bending_stencils_and_dihedral():
    faces = np.array([[0, 1, 2], [2, 1, 3]])
    bends, pair = interior_edges(faces)
    assert len(bends) == 1 and set(bends[0, 2:]) == {1, 2} and set(bends[0, :2]) == {0, 3}
    flat = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]])
    assert abs(dihedral_angles(flat, bends)[0]) < 1e-12
    folded = flat.copy()
    folded[3] = [0.5, 0.5, 0.7]
    assert abs(dihedral_angles(folded, bends)[0]) > 0.5


def test_welding_merges_seam_ids_and_keeps_layout():
    p = tube_skirt(1.0, n_rows=4, n_cols=4)
    cloth = build_cloth(p)
    n_ids = int(max(q.vertex_ids.max() for q in p.panels)) + 1
    assert cloth.n_global == n_ids and cloth.n_particles == n_ids  # ids already shared on the seams
    assert np.array_equal(cloth.faces_global, cloth.particle_of[cloth.faces_global])
    assert cloth.pinned.sum() == len(p.pins["skirt"])


def test_tethers_are_never_shorter_than_the_straight_pattern_distance():
    p = tube_skirt(1.3, n_rows=8, n_cols=8)
    cloth = build_cloth(p)
    anchor, length = tethers(cloth.faces, cloth.rest_inv, cloth.pinned)
    assert np.all(anchor[cloth.pinned] == -1) and np.all(anchor[~cloth.pinned] >= 0)
    back = p.panel("back")
    uv = np.zeros((cloth.n_particles, 2))
    uv[cloth.particle_of[back.vertex_ids]] = back.uv
    inside = np.isin(np.arange(cloth.n_particles), cloth.particle_of[back.vertex_ids])
    free = inside & ~cloth.pinned & np.isin(anchor, cloth.particle_of[back.vertex_ids])
    straight = np.linalg.norm(uv[free] - uv[anchor[free]], axis=1)
    assert np.all(cloth.tether_length[free] >= straight - 1e-9)
    # straight down the grain from the waistband the fabric distance is exact: row k is k rows down
    column = cloth.particle_of[back.vertex_ids.reshape(9, 9)[1:, 4]]
    assert np.allclose(cloth.tether_length[column], np.arange(1, 9) * (0.95 - 0.62) / 8, atol=1e-9)


def test_bad_patterns():
    p = tube_skirt(1.0, n_rows=2, n_cols=2)
    p.panels[0].uv[:] = 0.0
    with pytest.raises(DrapeError, match="degenerate"):
        build_cloth(p)
    p = tube_skirt(1.0, n_rows=2, n_cols=2)
    p.pins = {"skirt": np.array([10_000])}
    with pytest.raises(DrapeError, match="pins"):
        build_cloth(p)
    p = tube_skirt(1.0, n_rows=2, n_cols=2)
    p.panels = []
    with pytest.raises(DrapeError, match="no panels"):
        build_cloth(p)


def test_two_rings_are_the_fabric_neighbours():
    # a strip of triangles 0-1-2-3-4-5 (each triangle (k, k+1, k+2))
    faces = np.array([[k, k + 1, k + 2] for k in range(4)])
    start, idx = two_rings(faces, 6)
    ring0 = set(idx[start[0] : start[1]].tolist())
    assert ring0 == {0, 1, 2, 3, 4}  # 1 and 2 share a triangle with 0; 3 and 4 are one more step away
    assert 5 not in ring0


@pytest.mark.parametrize("edge", [0.01, 0.005])
def test_bending_weight_stores_the_continuum_energy(edge):
    # rolled round a cylinder of radius R, a sheet's discrete bending energy sum(w theta^2) / 2 (per unit
    # bending stiffness) is the continuum kappa^2 / 2 per area, whatever the edge length (the
    # discrete-shell 3|e|^2/A stored 3.3 times it on this mesh)
    from core.drape import textile as T

    uv, faces = T.disc_mesh(0.15, edge, 0.09)
    cloth = build_cloth(T.sheet_pattern(uv, faces, 0.0, np.zeros(len(uv), bool), "cotton"))
    radius = 0.1
    for axis in (0, 1):
        x = cloth.x0.copy()
        u = x[:, axis].copy()
        x[:, axis], x[:, 2] = radius * np.sin(u / radius), radius * (1 - np.cos(u / radius))
        energy = 0.5 * np.sum(cloth.bend_weight * dihedral_angles(x, cloth.bends) ** 2)
        continuum = 0.5 * cloth.rest_area.sum() / radius**2
        assert energy / continuum == pytest.approx(1.0, abs=0.15)


def test_tethers_count_a_link_met_twice_once_at_its_shorter_length():
    # a fan of three triangles round vertex 0: the across-edge shortcut of edge 0-1 joins 2 and 3,
    # which are also an edge; the two links must not add up (a sparse matrix sums duplicates)
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 0.8], [0.5, -0.8]])
    faces = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 1]])
    inv, _, _ = rest_matrices(uv, faces, [0.0, 1.0])
    bends, bend_faces = interior_edges(faces)
    assert any(set(b[:2]) == {2, 3} for b in bends.tolist())
    anchor, length = tethers(faces, inv, np.array([False, False, False, True]), bends, bend_faces)
    assert anchor[2] == 3 and length[2] == pytest.approx(1.6)


def test_unique_pairs_is_numpys_unique_over_rows():
    from core.geom.mesh import unique_pairs

    pairs = np.random.default_rng(3).integers(0, 40, size=(500, 2))
    edges, inverse = unique_pairs(pairs)
    ref, ref_inv = np.unique(pairs, axis=0, return_inverse=True)
    assert np.array_equal(edges, ref) and np.array_equal(inverse, ref_inv.reshape(-1))
    assert np.array_equal(edges[inverse], pairs)
    assert unique_pairs(np.zeros((0, 2), int))[0].shape == (0, 2)
