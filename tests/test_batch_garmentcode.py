"""The GarmentCode specification (core.batch.garmentcode) against GarmentCode's own conventions, written here
from its code (pygarment): rotation ``Rz @ Ry @ Rx`` of the Euler angles in degrees
(``pattern/rotation.py: euler_xyz_to_R``, what its simulator's BoxMesh places panels with), centimetres, bodies
standing on y = 0 (Y up, facing +Z), edge loops starting at the vertex nearest to the lower-left corner of the
bounding box and running counter-clockwise (``pattern/core.py: _normalize_edge_loop``).

GarmentCode itself is not installed here: the ``pygarment`` 2.0.2 wheel installs its modules as top-level
``pattern``, ``meshgen`` and ``garmentcode`` (its own imports say ``pygarment.…``, and ``pygarment.data_config``
is missing), and its mesher needs the CGAL Python bindings and libigl (docs/batch.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.batch.garmentcode import MIN_EDGE, TO_GARMENTCODE, TOLERANCE, simplified_outlines, specification


def _rx(a):
    return np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])


def _ry(a):
    return np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])


def _rz(a):
    return np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])


def garmentcode_R(euler_deg):
    """GarmentCode's euler_xyz_to_R: Rz(z) Ry(y) Rx(x), degrees."""
    x, y, z = np.radians(euler_deg)
    return _rz(z) @ _ry(y) @ _rx(x)


def garmentcode_origin(vertices):
    """GarmentCode's _vert_at_left_corner."""
    v = np.asarray(vertices, float)
    return int(np.argmin(np.linalg.norm(v - v.min(axis=0), axis=1)))


@pytest.fixture(scope="module")
def teaser():
    from core import workflows as wf
    from core.body.instance import spec_instance
    from core.design.templates import template_path

    prep = wf.prepare(template_path("teaser_shirt_pants"))
    pattern = wf.reference(prep).pattern
    body, _ = spec_instance(pattern.body)
    return pattern, specification(pattern), float(body[:, 2].min())


def _written(pattern, name):
    """The pattern's vertex ids of a written panel, in the file's order."""
    ids = simplified_outlines(pattern)[name]
    uv = np.asarray(pattern.panel(name).uv, float)
    return np.roll(ids, -garmentcode_origin(uv[ids]))


def test_panels_placed_as_garmentcode_places_them(teaser):
    """Each panel's vertices, placed by GarmentCode's rotation and translation, land where the piece lies on the
    body (in GarmentCode's frame: cm, Y up, facing +Z, the floor at y = 0): the placement is the best rigid fit.
    Read in scipy's intrinsic XYZ (what the file used to mean), the back sleeves land ~60 cm off."""
    pattern, spec, floor = teaser
    worst_wrong = 0.0
    for name, panel in spec["pattern"]["panels"].items():
        V = np.column_stack([np.array(panel["vertices"]), np.zeros(len(panel["vertices"]))])
        placed = V @ garmentcode_R(panel["rotation"]).T + np.array(panel["translation"])
        true = (np.asarray(pattern.panel(name).xyz, float)[_written(pattern, name)] - [0, 0, floor]) * 100
        true = true @ TO_GARMENTCODE.T
        assert np.allclose(placed.mean(axis=0), true.mean(axis=0), atol=0.01), name
        # the best rigid fit: no rotation about the centroid brings the panel closer
        P, Q = V - V.mean(axis=0), true - true.mean(axis=0)
        U, _, Vt = np.linalg.svd(P.T @ Q)
        d = np.sign(np.linalg.det(Vt.T @ U.T))
        best = Vt.T @ np.diag([1, 1, d]) @ U.T
        assert np.allclose(garmentcode_R(panel["rotation"]), best, atol=1e-4), name
        assert np.median(np.linalg.norm(placed - true, axis=1)) < 12.0, name
        x, y, z = np.radians(panel["rotation"])
        wrong = V @ (_rx(x) @ _ry(y) @ _rz(z)).T + np.array(panel["translation"])
        worst_wrong = max(worst_wrong, float(np.median(np.linalg.norm(wrong - true, axis=1))))
    assert worst_wrong > 20.0


def test_units_and_floor(teaser):
    """Centimetres, the body's lowest point at y = 0: the pants reach down to the ankles, the shirt up to the
    shoulders of a body about 1.7 m tall."""
    pattern, spec, floor = teaser
    assert spec["properties"]["units_in_meter"] == 100
    ys = {}
    for name, panel in spec["pattern"]["panels"].items():
        V = np.column_stack([np.array(panel["vertices"]), np.zeros(len(panel["vertices"]))])
        ys[name] = (V @ garmentcode_R(panel["rotation"]).T + np.array(panel["translation"]))[:, 1]
    low = min(v.min() for n, v in ys.items() if n.startswith("pants"))
    high = max(v.max() for n, v in ys.items() if n.startswith("shirt"))
    assert 0.0 <= low < 30.0 and 130.0 < high < 175.0
    width = np.ptp(np.asarray(pattern.panel("shirt.front").uv, float)[:, 0]) * 100
    assert np.ptp(np.array(spec["pattern"]["panels"]["shirt.front"]["vertices"])[:, 0]) == pytest.approx(width, abs=0.1)


def test_edge_loops_normalised(teaser):
    """normalized_edge_loops: every loop starts at GarmentCode's origin vertex and runs counter-clockwise, edges
    chain i -> i + 1."""
    _, spec, _ = teaser
    assert spec["properties"]["normalized_edge_loops"] is True
    for name, panel in spec["pattern"]["panels"].items():
        V = np.array(panel["vertices"])
        assert garmentcode_origin(V) == 0, name
        x, y = V[:, 0], V[:, 1]
        assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0, name
        n = len(V)
        assert [e["endpoints"] for e in panel["edges"]] == [[i, (i + 1) % n] for i in range(n)]


def test_outlines_simplified_within_tolerance(teaser):
    """The outline within TOLERANCE of the solved one (within 1 mm next to a vertex left out for being closer than
    MIN_EDGE to its neighbour), with far fewer vertices and no edge under MIN_EDGE (GarmentCode's mesher made
    degenerate triangles at edges of a millimetre or less); each stitch pairs corresponding stretches (the seam's
    correspondence kept), so every seam is stitched end to end on both sides."""
    from core.export.boundary import piece_loops
    from core.geom.polygon import distance_to_polyline

    pattern, spec, _ = teaser
    shortest = np.inf
    for name, panel in spec["pattern"]["panels"].items():
        p = pattern.panel(name)
        loop = piece_loops(p)[0]
        V = np.array(panel["vertices"])
        assert len(V) < 0.5 * len(loop)
        uv = np.asarray(p.uv, float)
        local = (uv[loop] - uv[loop].min(axis=0)) * 100
        off = distance_to_polyline(local, V, closed=True)
        assert off.max() <= 0.1 and (off > TOLERANCE * 100 + 1e-3).sum() <= 3, name  # cm
        shortest = min(shortest, float(np.linalg.norm(np.diff(np.vstack([V, V[:1]]), axis=0), axis=1).min()))
    assert shortest >= MIN_EDGE * 100 - 1e-3  # cm: 2 mm (the solved outline's shortest edges: 0.04 mm)

    def length(side):
        V = np.array(spec["pattern"]["panels"][side["panel"]]["vertices"])
        i, j = spec["pattern"]["panels"][side["panel"]]["edges"][side["edge"]]["endpoints"]
        return float(np.linalg.norm(V[j] - V[i]))

    stitched = {}
    for a, b in spec["pattern"]["stitches"]:
        key = (a["panel"], b["panel"])
        sa, sb = stitched.get(key, (0.0, 0.0))
        stitched[key] = (sa + length(a), sb + length(b))
    seams = {}
    for s in pattern.seams:
        full = [
            float(
                np.sum(
                    np.linalg.norm(
                        np.diff(np.asarray(pattern.panel(panel).uv, float)[np.asarray(ids, int)], axis=0), axis=1
                    )
                )
            )
            * 100
            for panel, ids in ((s.panel_a, s.verts_a), (s.panel_b, s.verts_b))
        ]
        sa, sb = seams.get((s.panel_a, s.panel_b), (0.0, 0.0))
        seams[(s.panel_a, s.panel_b)] = (sa + full[0], sb + full[1])
    assert set(seams) == set(stitched)
    for key, full in seams.items():
        for k in (0, 1):
            # the chords of a simplified run are at most the run's length, and within the tolerance of it
            assert 0.99 * full[k] <= stitched[key][k] <= full[k] + 1e-6, key
    assert MIN_EDGE > TOLERANCE


BOXMESH = r"""
import json, sys
sys.path.insert(0, sys.argv[1])
from pygarment.meshgen.boxmeshgen import BoxMesh
m = BoxMesh(sys.argv[2], res=1.0)
m.load()
print("RESULT " + json.dumps({"panels": len(m.panels), "vertices": len(m.vertices), "stitches": len(m.stitches)}))
"""


def test_garmentcodes_own_mesher_meshes_every_panel(teaser, tmp_path):
    """GarmentCode's BoxMesh at its default 1 cm resolution meshes the file (it stopped with "panel contains
    degenerate triangles" on sub-millimetre edges). GarmentCode is no dependency and its 2.0.2 wheel cannot be
    imported (docs/batch.md): set EASE_GARMENTCODE to a GarmentCode checkout and EASE_GARMENTCODE_PYTHON to a
    Python with its mesher's packages (cgal, libigl, numpy<2, scipy, svgpathtools, svgwrite, matplotlib, pyyaml,
    cairosvg, psutil) to run it."""
    import json
    import os
    import subprocess

    root, python = os.environ.get("EASE_GARMENTCODE"), os.environ.get("EASE_GARMENTCODE_PYTHON")
    if not (root and python):
        pytest.skip("GarmentCode not configured (EASE_GARMENTCODE, EASE_GARMENTCODE_PYTHON)")
    _, spec, _ = teaser
    path = tmp_path / "specification.json"
    path.write_text(json.dumps(spec))
    env = dict(os.environ, MPLBACKEND="Agg")
    r = subprocess.run([python, "-c", BOXMESH, root, str(path)], capture_output=True, text=True, env=env, timeout=600)
    line = next((ln for ln in r.stdout.splitlines() if ln.startswith("RESULT ")), None)
    assert r.returncode == 0 and line, r.stdout[-2000:] + r.stderr[-2000:]
    got = json.loads(line[len("RESULT ") :])
    assert got["panels"] == len(spec["pattern"]["panels"]) and got["stitches"] == len(spec["pattern"]["stitches"])
    assert got["vertices"] > 1000
