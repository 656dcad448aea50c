"""core.export.validate: invalid patterns and drapes are refused with errors naming the culprit."""

import numpy as np
import pytest
from export_synth import drape_positions, make_pattern

from core.errors import ExportError
from core.export.boundary import face_loops, piece_loops
from core.export.validate import validate_drape, validate_pattern


def _nan_uv(p):
    p.panel("back").uv[3] = np.nan


def _flat_piece(p):
    p.panel("front").uv[:, 1] = 0.0


def _tangled(p):
    uv = p.panel("front").uv
    loop = p.panel("front").boundary[0]
    uv[loop[2]], uv[loop[20]] = uv[loop[20]].copy(), uv[loop[2]].copy()


def _seam_piece(p):
    p.seams[0].panel_b = "sleeve"


def _seam_range(p):
    p.seams[1].verts_a = p.seams[1].verts_a.copy()
    p.seams[1].verts_a[-1] = 10_000


def _seam_inside(p):
    p.seams[0].verts_a = np.array([0, 10, 20])
    p.seams[0].verts_b = p.seams[0].verts_b[:3]


def _seam_lengths(p):
    p.seams[0].verts_b = p.seams[0].verts_b[:-1]


def _faces(p):
    p.panel("front").faces[0, 0] = 999


def _grain(p):
    p.panel("front").grain = np.zeros(2)


def _dup(p):
    p.panels[1].name = "front"


def _mirror(p):
    p.panels[1].mirror_of = "nobody"


def _hem(p):
    p.panel("front").hems = [np.array([-1, 0])]


@pytest.mark.parametrize(
    "breaker,words",
    [
        (_nan_uv, ["back", "uv", "not finite"]),
        (_flat_piece, ["front", "degenerate"]),
        (_tangled, ["front", "crosses itself"]),
        (_seam_piece, ["side_left", "panel_b", "sleeve"]),
        (_seam_range, ["side_right", "verts_a"]),
        (_seam_inside, ["side_left", "boundary"]),
        (_seam_lengths, ["side_left", "equally long"]),
        (_faces, ["front", "faces"]),
        (_grain, ["front", "grain"]),
        (_dup, ["duplicate", "front"]),
        (_mirror, ["mirror_of", "nobody"]),
        (_hem, ["front", "hems[0]"]),
    ],
)
def test_invalid_pattern_names_the_culprit(breaker, words):
    pat = make_pattern()
    validate_pattern(pat)  # fine before breaking it
    breaker(pat)
    with pytest.raises(ExportError) as err:
        validate_pattern(pat)
    for w in words:
        assert w in str(err.value)


def test_boundary_is_derived_from_faces_when_missing():
    pat = make_pattern()
    given = [piece_loops(p) for p in pat.panels]
    for p in pat.panels:
        p.boundary = []
    validate_pattern(pat)
    # the loops from the faces: the same cycle, started at the smallest vertex id, outline ccw
    for p, loops in zip(pat.panels, given):
        derived = face_loops(p.faces)
        assert [int(b[0]) for b in derived] == sorted(int(b.min()) for b in derived)
        (b,), (g,) = piece_loops(p), loops
        assert int(b[0]) == int(b.min()) and len(b) == len(g)
        k = int(np.flatnonzero(g == b[0])[0])
        np.testing.assert_array_equal(np.roll(g, -k), b)


def test_drape_checks():
    pat = make_pattern()
    pos = drape_positions(pat)
    assert validate_drape(pat, pos).shape == pos.shape
    with pytest.raises(ExportError, match="needs the draped garment"):
        validate_drape(pat, None)
    with pytest.raises(ExportError, match=r"\(N, 3\)"):
        validate_drape(pat, pos[:, :2])
    with pytest.raises(ExportError, match="vertex ids"):
        validate_drape(pat, pos[:10])
    bad = pos.copy()
    bad[5] = np.inf
    with pytest.raises(ExportError, match="NaN or infinite"):
        validate_drape(pat, bad)


def test_drape_of_another_pattern_is_refused():
    pat = make_pattern()
    pos = drape_positions(pat)
    faces = np.concatenate([p.vertex_ids[p.faces] for p in pat.panels])
    # the pattern's own triangles, in any order and rotation: accepted
    rolled = np.roll(faces[::-1], 1, axis=1)
    assert validate_drape(pat, pos, rolled).shape == pos.shape
    assert validate_drape(pat, pos, np.zeros((0, 3), int)).shape == pos.shape  # no faces: not checked
    # another pattern with as many vertices: other triangles (a flipped diagonal), one missing, one extra
    other = faces.copy()
    other[0] = [faces[0][0], faces[0][1], faces[1][2]]
    for wrong in (other, faces[1:], np.vstack([faces, faces[:1] + 1])):
        with pytest.raises(ExportError, match="another pattern"):
            validate_drape(pat, pos, wrong)
    with pytest.raises(ExportError, match="drape.faces"):
        validate_drape(pat, pos, faces.astype(float))


def test_lenient_validation_returns_geometry_warnings():
    pat = make_pattern()
    _tangled(pat)
    warnings = validate_pattern(pat, strict=False)
    assert len(warnings) == 1 and "crosses itself" in warnings[0]
    _nan_uv(pat)  # data errors stay errors
    with pytest.raises(ExportError, match="not finite"):
        validate_pattern(pat, strict=False)


def test_sliver_loops_are_refused_too():
    """Issue 30: no area threshold lets a loop through (it let 8.2 cm^2 pass on a men's XS blouse)."""
    pat = make_pattern()
    front = pat.panel("front")
    loop = front.boundary[0]  # starts along the bottom edge, 6.25 cm between vertices
    x1, x2 = front.uv[loop[1], 0], front.uv[loop[2], 0]
    # swap two bottom vertices a hair above the edge: a bow-tie of ~0.2 cm^2
    front.uv[loop[1]] = (x2, 0.001)
    front.uv[loop[2]] = (x1, 0.0008)
    with pytest.raises(ExportError, match=r"piece 'front'.uv: the sew line crosses itself .* enclosing 0.062 cm\^2"):
        validate_pattern(pat)
    warnings = validate_pattern(pat, strict=False)
    assert len(warnings) == 1 and "crosses itself" in warnings[0]
