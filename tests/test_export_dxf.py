"""core.export.dxf: ASTM D6673/AAMA blocks and layers, plain DXF, read back with ezdxf."""

import io

import numpy as np
import pytest
from export_synth import make_pattern

ezdxf = pytest.importorskip("ezdxf")

from core.export import dxf  # noqa: E402  (after the importorskip)
from core.export.pieces import build_pieces  # noqa: E402  (after the importorskip)
from core.geom.layout import layout_pieces  # noqa: E402  (after the importorskip)
from core.geom.polyline import polyline_length  # noqa: E402  (after the importorskip)


@pytest.fixture(scope="module")
def made():
    pat = make_pattern(rotate_back_deg=30.0)
    pat.panels[1].mirror_of = "front"
    pieces = build_pieces(pat, allowance={"default": 0.01, "hem": 0.02})
    lay = layout_pieces([p.bbox for p in pieces], 0.88, 0.02)
    return pat, pieces, lay


def _piece_blocks(doc):
    return [b for b in doc.blocks if not b.name.startswith("*")]


def _poly_points(e):
    if e.dxftype() == "LWPOLYLINE":
        return np.array([p[:2] for p in e.get_points()])
    return np.array([tuple(v.dxf.location)[:2] for v in e.vertices])


@pytest.mark.parametrize("writer", ["astm_text", "astm_r12_text"])
def test_astm_blocks_layers_and_sew_lengths(made, writer):
    pat, pieces, lay = made
    doc = ezdxf.read(io.StringIO(getattr(dxf, writer)(pieces, lay, pat.style, "M")))
    blocks = _piece_blocks(doc)
    assert [b.name for b in blocks] == [p.name for p in pat.panels]  # one block per piece
    if writer == "astm_text":
        assert doc.header["$INSUNITS"] == 4  # millimetres
    inserts = list(doc.modelspace().query("INSERT"))
    assert sorted(i.dxf.name for i in inserts) == sorted(b.name for b in blocks)
    style_text = [t.dxf.text for t in doc.modelspace().query("TEXT")]
    assert "Units: METRIC" in style_text and "Style Name: test shirt" in style_text
    for blk, piece in zip(blocks, pieces):
        panel = pat.panel(blk.name)
        layers = {e.dxf.layer for e in blk}
        assert layers >= {"1", "2", "4", "7", "14"}
        # turn points: the 4 corners of the sew line and of the cut line (mitred, so also 4)
        turns = [tuple(e.dxf.location)[:2] for e in blk if e.dxf.layer == "2"]
        assert len(turns) == 8 and all(e.dxftype() == "POINT" for e in blk if e.dxf.layer == "2")
        sew = [e for e in blk if e.dxf.layer == "14"]
        assert len(sew) == 1 and sew[0].is_closed
        pts = _poly_points(sew[0])
        want = polyline_length(panel.uv[panel.boundary[0]], closed=True) * 1000.0
        assert polyline_length(pts, closed=True) == pytest.approx(want, abs=1e-6)
        cut = [e for e in blk if e.dxf.layer == "1" and e.dxftype() in ("POLYLINE", "LWPOLYLINE")]
        assert len(cut) == 1 and polyline_length(_poly_points(cut[0]), closed=True) > want + 8 * 10
        assert len([e for e in blk if e.dxf.layer == "4"]) == len(piece.notches)
        grain = [e for e in blk if e.dxf.layer == "7"]
        assert len(grain) == 1 and grain[0].dxftype() == "LINE" and grain[0].dxf.end[1] > grain[0].dxf.start[1]
        # the arrow heads: two open barb-tip-barb polylines on the annotation layer, tips on the grain line's ends
        heads = [_poly_points(e) for e in blk if e.dxf.layer == "15" and e.dxftype() != "TEXT"]
        assert len(heads) == 2 and all(len(h) == 3 for h in heads)
        tips = sorted(tuple(np.round(h[1], 6)) for h in heads)
        ends = sorted(tuple(np.round(np.array(p)[:2], 6)) for p in (grain[0].dxf.start, grain[0].dxf.end))
        assert tips == ends
        assert abs(grain[0].dxf.end[0] - grain[0].dxf.start[0]) < 1e-9  # grain line along +y
        texts = [e.dxf.text for e in blk if e.dxftype() == "TEXT"]
        assert f"Piece Name: {panel.name}" in texts and "Size: M" in texts and "Quantity: 1" in texts
    back_texts = [e.dxf.text for e in blocks[1] if e.dxftype() == "TEXT" and e.dxf.layer == "15"]
    # the back is declared the front's mirror but is no mirror image: the label says so, with the figure
    gap = round(pieces[1].mirror_gaps["front"] * 1000, 1)
    assert gap > 0.5 and f"cut 1, not the mirror of front: {gap:g} mm off" in back_texts


def test_plain_dxf(made):
    pat, pieces, lay = made
    doc = ezdxf.read(io.StringIO(dxf.plain_text(pieces, lay, pat.style)))
    assert doc.header["$INSUNITS"] == 4
    assert not _piece_blocks(doc)
    msp = doc.modelspace()
    sew = msp.query('LWPOLYLINE[layer=="SEW"]')
    assert len(sew) == len(pieces)
    got = sorted(polyline_length(_poly_points(e), closed=True) for e in sew)
    want = sorted(polyline_length(p.uv[p.boundary[0]], closed=True) * 1000 for p in pat.panels)
    np.testing.assert_allclose(got, want, atol=1e-6)
    assert len(msp.query('LINE[layer=="NOTCH"]')) == sum(len(p.notches) for p in pieces)
    assert len(msp.query('LWPOLYLINE[layer=="CUT"]')) == len(pieces)


def test_dxf_is_deterministic(made):
    pat, pieces, lay = made
    assert dxf.astm_text(pieces, lay, pat.style, "M") == dxf.astm_text(pieces, lay, pat.style, "M")


def _renamed(pattern, old, new):
    for p in pattern.panels:
        if p.name == old:
            p.name = new
        if getattr(p, "mirror_of", None) == old:
            p.mirror_of = new
    for s in pattern.seams:
        s.panel_a = new if s.panel_a == old else s.panel_a
        s.panel_b = new if s.panel_b == old else s.panel_b
    return pattern


def test_block_names_bounded_per_format(tmp_path):
    """A long piece name names an R12 block in at most 31 characters (R12's limit; two long names that share
    their start stay apart), an R2000 block whole; the label text keeps the whole name. A name over 100
    characters is refused in one line naming the field (it was accepted at 10,000 characters)."""
    import ezdxf

    from core.errors import ExportError
    from core.export import export_pattern

    long_a, long_b = "front_" + "x" * 60, "front_" + "x" * 59 + "y"
    pattern = _renamed(_renamed(make_pattern(), "front", long_a), "back", long_b)
    export_pattern(pattern, tmp_path / "e", formats=("dxf",))
    r12 = ezdxf.readfile(tmp_path / "e" / "pattern_astm_r12.dxf")
    names = sorted(b.name for b in r12.blocks if not b.name.startswith("*"))
    assert len(names) == 2 and len(set(names)) == 2 and all(len(n) <= 31 for n in names), names
    r2000 = ezdxf.readfile(tmp_path / "e" / "pattern_astm.dxf")
    assert sorted(b.name for b in r2000.blocks if not b.name.startswith("*")) == sorted([long_a, long_b])
    texts = [e.dxf.text for b in r12.blocks if not b.name.startswith("*") for e in b if e.dxftype() == "TEXT"]
    assert f"Piece Name: {long_a}" in texts and f"Piece Name: {long_b}" in texts
    with pytest.raises(ExportError, match=r"pattern.panels\[0\].name: expected at most 100 characters") as err:
        export_pattern(_renamed(make_pattern(), "front", "f" * 10000), tmp_path / "bad", formats=("dxf",))
    assert "\n" not in str(err.value) and len(str(err.value)) < 200
    assert not (tmp_path / "bad").exists()
