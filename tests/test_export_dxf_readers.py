"""Every DXF variant read by two independent readers (ezdxf with audit and recover, and tests/helpers/dxf_reader),
compared with export.json: piece count, sew-line lengths, notch counts; headers that open at the right size
(extents, units, the R12 layer table); AAMA grain lines alone on layer 7, their arrow heads on 15."""

import io
import json

import dxf_reader
import numpy as np
import pytest
from export_synth import make_pattern, wide_pattern

ezdxf = pytest.importorskip("ezdxf")
from ezdxf import recover  # noqa: E402

from core.export import export_pattern  # noqa: E402

VARIANTS = ("pattern_astm.dxf", "pattern_astm_r12.dxf", "pattern_plain.dxf")
CASES = {
    "tube 0 deg": lambda: make_pattern(rotate_back_deg=0.0),
    "tube 30 deg": lambda: make_pattern(rotate_back_deg=30.0),
    "tube 75 deg, fine": lambda: make_pattern(rotate_back_deg=75.0, nx=15, ny=21),
    "wide 1.6 m": lambda: wide_pattern(1.6),
}


@pytest.fixture(scope="module", params=sorted(CASES))
def exported(request, tmp_path_factory):
    out = tmp_path_factory.mktemp("dxf") / "out"
    export_pattern(CASES[request.param](), out, formats="dxf")
    summary = json.loads((out / "export.json").read_text())
    return out, summary


def _want(summary):
    pieces = summary["pieces"]
    return (
        [p["name"] for p in pieces],
        [p["sew_line_mm"] for p in pieces],
        [sum(len(v) for v in p["notches_mm"].values()) for p in pieces],
    )


def _ezdxf_pieces(doc, plain):
    """(name, sew length mm, notch count, grain LINEs, arrow polylines) per piece, read by ezdxf."""

    def pts(e):
        if e.dxftype() == "LWPOLYLINE":
            return np.array([p[:2] for p in e.get_points()])
        return np.array([tuple(v.dxf.location)[:2] for v in e.vertices])

    if plain:
        msp = doc.modelspace()
        sew = [dxf_reader.polyline_length(pts(e), True) for e in msp.query('LWPOLYLINE[layer=="SEW"]')]
        return sew, len(msp.query('LINE[layer=="NOTCH"]'))
    out = []
    for blk in [b for b in doc.blocks if not b.name.startswith("*")]:
        sew = [e for e in blk if e.dxf.layer == "14"]
        out.append(
            (
                blk.name,
                dxf_reader.polyline_length(pts(sew[0]), True),
                sum(1 for e in blk if e.dxf.layer == "4"),
                sum(1 for e in blk if e.dxf.layer == "7"),
                sum(1 for e in blk if e.dxf.layer == "15" and e.dxftype() in ("POLYLINE", "LWPOLYLINE")),
            )
        )
    return out


def _own_pieces(dwg, plain):
    if plain:
        sew = [
            dxf_reader.polyline_length(e.points, e.closed)
            for e in dwg.entities
            if e.kind == "LWPOLYLINE" and e.layer == "SEW"
        ]
        return sew, sum(1 for e in dwg.entities if e.kind == "LINE" and e.layer == "NOTCH")
    out = []
    inserted = [e.value(2) for e in dwg.entities if e.kind == "INSERT"]
    for name in inserted:
        ents = dwg.blocks[name]
        sew = [e for e in ents if e.layer == "14" and e.kind in ("POLYLINE", "LWPOLYLINE")]
        assert len(sew) == 1 and sew[0].closed
        out.append(
            (
                name,
                dxf_reader.polyline_length(sew[0].points, True),
                sum(1 for e in ents if e.layer == "4" and e.kind == "LINE"),
                sum(1 for e in ents if e.layer == "7"),
                sum(1 for e in ents if e.layer == "15" and e.kind in ("POLYLINE", "LWPOLYLINE")),
            )
        )
    return out


@pytest.mark.parametrize("variant", VARIANTS)
def test_both_readers_agree_with_export_json(exported, variant):
    out, summary = exported
    names, sew_mm, notches = _want(summary)
    text = (out / variant).read_text("ascii" if "astm" in variant else "utf-8")
    plain = variant == "pattern_plain.dxf"
    # reader 1: ezdxf, strict read with a clean audit, and the recover mode on the raw bytes
    doc = ezdxf.read(io.StringIO(text))
    audit = doc.audit()
    assert not audit.has_errors, [str(e) for e in audit.errors]
    rdoc, raudit = recover.read(io.BytesIO((out / variant).read_bytes()))
    assert not raudit.has_errors
    # reader 2: the independent group-code reader
    dwg = dxf_reader.read(text)
    for got in (_ezdxf_pieces(doc, plain), _ezdxf_pieces(rdoc, plain), _own_pieces(dwg, plain)):
        if plain:
            sew, n_notch = got
            np.testing.assert_allclose(sorted(sew), sorted(sew_mm), atol=0.006)
            assert n_notch == sum(notches)
        else:
            assert [g[0] for g in got] == names
            np.testing.assert_allclose([g[1] for g in got], sew_mm, atol=0.006)
            assert [g[2] for g in got] == notches
            assert all(g[3] == 1 and g[4] == 2 for g in got)  # the grain LINE alone on 7, two arrow heads on 15


@pytest.mark.parametrize("variant", VARIANTS)
def test_headers_open_at_the_right_size(exported, variant):
    out, summary = exported
    dwg = dxf_reader.read((out / variant).read_text("utf-8"))
    lo = np.array([dwg.header_number("$EXTMIN", 10), dwg.header_number("$EXTMIN", 20)])
    hi = np.array([dwg.header_number("$EXTMAX", 10), dwg.header_number("$EXTMAX", 20)])
    assert np.all(np.abs(np.concatenate([lo, hi])) < 1e5) and np.all(hi > lo)
    assert [dwg.header_number("$LIMMIN", 10), dwg.header_number("$LIMMIN", 20)] == lo.tolist()
    assert [dwg.header_number("$LIMMAX", 10), dwg.header_number("$LIMMAX", 20)] == hi.tolist()
    # every point drawn lies inside the extents, and the extents are tight (each side touched within 1 mm)
    pts = []
    inserts = {e.value(2): (e.number(10), e.number(20)) for e in dwg.entities if e.kind == "INSERT"}
    for name, ents in list(dwg.blocks.items()) + [(None, dwg.entities)]:
        if name is not None and name not in inserts:
            continue
        base = np.array(inserts.get(name, (0.0, 0.0)))
        for e in ents:
            if e.points is not None and len(e.points):
                pts.append(e.points + base)
            elif e.kind in ("LINE", "POINT", "TEXT"):
                pts.append(np.array([[e.number(10), e.number(20)]]) + base)
                if e.kind == "LINE":
                    pts.append(np.array([[e.number(11), e.number(21)]]) + base)
    pts = np.concatenate(pts)
    assert np.all(pts >= lo - 1e-6) and np.all(pts <= hi + 1e-6)
    assert np.all(pts.min(0) - lo < 1.0)
    if variant == "pattern_astm_r12.dxf":
        assert dwg.header["$ACADVER"] == [(1, "AC1009")]
        assert dwg.header_number("$MEASUREMENT", 70) == 1  # metric: Inkscape would read inches without it
        assert set(dwg.layers) >= {"1", "2", "4", "7", "14", "15"}
        assert not [b for b in dwg.blocks if b.startswith("$") or b.startswith("*")]  # Gerber: piece blocks only
    else:
        assert dwg.header_number("$INSUNITS", 70) == 4 and dwg.header_number("$MEASUREMENT", 70) == 1
