"""Graded nest (core.export.graded, `ease export DESIGN --sizes ...`): one AAMA block per piece per size
with the size in the block, the sizes of a piece stacked at its reference point, one colour per size."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from export_synth import make_pattern

from core.cli import main
from core.export.graded import SIZE_COLOURS, export_graded, graded_stacks, reference_point
from core.geom.polyline import polyline_length

SCALES = {"S": 0.95, "M": 1.0, "L": 1.06}


def _sizes():
    out = {}
    for size, f in SCALES.items():
        p = make_pattern()
        for panel in p.panels:
            panel.uv = panel.uv * f
        p.body = dict(p.body, size=size)
        out[size] = p
    return out


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    out = tmp_path_factory.mktemp("graded")
    return out, export_graded(_sizes(), out, title="test graded")


def test_stacks_aligned_at_the_reference_point():
    stacks = graded_stacks(_sizes())
    assert list(stacks) == ["front", "back"]
    for stack in stacks.values():
        assert list(stack) == list(SCALES)
        for d in stack.values():
            assert np.allclose(reference_point(d), 0.0, atol=1e-12)
            assert np.allclose(d.grain[:, 0], 0.0, atol=1e-9)  # grain lines on one line
        # the sizes really differ: the sew line grows with the scale
        lengths = [polyline_length(d.sew[0], closed=True) for d in stack.values()]
        assert np.allclose(np.array(lengths) / lengths[1], list(SCALES.values()), rtol=1e-9)


def test_one_block_per_piece_per_size(graded):
    import ezdxf

    out, files = graded
    assert sorted(f.name for f in files) == ["graded.json", "graded.pdf", "graded.svg", "graded_astm.dxf"]
    doc = ezdxf.readfile(out / "graded_astm.dxf")
    assert not doc.audit().has_errors
    blocks = {b.name: b for b in doc.blocks if not b.name.startswith("*")}
    assert sorted(blocks) == sorted(f"{p}_{s}" for p in ("front", "back") for s in SCALES)
    inserts = {}
    for ins in doc.modelspace().query("INSERT"):
        inserts[ins.dxf.name] = tuple(round(v, 6) for v in ins.dxf.insert)
    for piece in ("front", "back"):
        places = {inserts[f"{piece}_{s}"] for s in SCALES}
        assert len(places) == 1  # stacked: one insertion point
        mids = []
        for s in SCALES:
            texts = [e.dxf.text for e in blocks[f"{piece}_{s}"] if e.dxftype() == "TEXT"]
            assert f"Size: {s}" in texts and f"Piece Name: {piece}" in texts
            grain = [e for e in blocks[f"{piece}_{s}"] if e.dxftype() == "LINE" and e.dxf.layer == "7"][0]
            mids.append((np.array(grain.dxf.start)[:2] + np.array(grain.dxf.end)[:2]) / 2)
        assert np.allclose(mids, 0.0, atol=1e-6)  # aligned at the grain line's middle


def test_svg_colours_and_legend(graded):
    out, _ = graded
    root = ET.fromstring((out / "graded.svg").read_text())
    ns = {"svg": "http://www.w3.org/2000/svg"}
    legend = root.find("svg:g[@id='legend']", ns)
    assert [t.text for t in legend.findall("svg:text", ns)] == list(SCALES)
    for piece in ("front", "back"):
        g = root.find(f"svg:g[@id='piece-{piece}']", ns)
        groups = g.findall("svg:g[@class='size']", ns)
        assert [x.get("data-size") for x in groups] == list(SCALES)
        colours = [x.find("svg:path[@class='cut']", ns).get("stroke") for x in groups]
        assert colours == list(SIZE_COLOURS[: len(SCALES)])
    summary = json.loads((out / "graded.json").read_text())
    assert summary["sizes"] == list(SCALES) and set(summary["pieces"]) == {"front", "back"}
    assert (out / "graded.pdf").read_bytes().startswith(b"%PDF")


def test_graded_cli_errors(tmp_path, capsys):
    """Bad --sizes and a pattern folder instead of a design: exit 2 and one line, nothing written."""
    from core.design.templates import template_path

    design = template_path("top_sleeveless")
    for target, sizes, words in (
        (design, "XS,XXL", "--sizes"),
        (design, "M,M", "--sizes"),
        (design, "women:5XL", "XS, S, M, L, XL, XXL"),
        (tmp_path, "XS,M", "design JSON"),
    ):
        rc = main(["export", str(target), "--sizes", sizes, "--out", str(tmp_path / "g"), "--quiet"])
        err = capsys.readouterr().err
        assert rc == 2 and words in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "g").exists()


@pytest.mark.slow
def test_graded_cli_design(tmp_path):
    """The whole door: a shipped design transferred to two sizes, one block per piece per size."""
    import ezdxf

    from core.design.templates import template_path

    rc = main(["export", str(template_path("top_sleeveless")), "--sizes", "XS,XL", "--out", str(tmp_path), "--quiet"])
    assert rc == 0
    summary = json.loads((tmp_path / "graded.json").read_text())
    doc = ezdxf.readfile(tmp_path / "graded_astm.dxf")
    names = [b.name for b in doc.blocks if not b.name.startswith("*")]
    assert len(names) == 2 * len(summary["pieces"]) and all(n.endswith(("_XS", "_XL")) for n in names)
    for piece in summary["pieces"].values():
        assert piece["XL"]["sew_line_mm"] > piece["XS"]["sew_line_mm"]


def test_notches_graded_from_a_base_length():
    """A graded seam has the base length's notches, their distances from the ends scaled; at the base
    length itself the seam's own rule."""
    from core.export.notches import notch_positions

    own_a, own_b = notch_positions(0.83, 0.85, 0.10)
    same_a, same_b = notch_positions(0.83, 0.85, 0.10, base=0.83)
    assert np.allclose(own_a, same_a, atol=1e-15) and np.allclose(own_b, same_b, atol=1e-15)
    for short in (0.61, 0.70, 0.95, 1.20):  # fewer or more notches by their own rule
        a, b = notch_positions(short, short + 0.02, 0.10, base=0.83)
        assert len(a) == len(b) == len(own_a)
        f = short / 0.83
        head = len(own_a) // 2
        assert np.allclose(a[:head], own_a[:head] * f) and np.allclose(short - a[-head:], (0.83 - own_a[-head:]) * f)
    assert len(notch_positions(0.61, 0.63, 0.10)[0]) != len(own_a)  # the case the base rule is for


@pytest.fixture(scope="module")
def teaser_graded(tmp_path_factory):
    """The teaser graded XS, M, XL as `ease export --sizes` makes it (workflows transfers, the design's own
    size as the sample), and the design's own pattern exported alone (DXF) as `ease pattern` + `ease export`
    make it; the graded drawings too."""
    from core import workflows as wf
    from core.design.templates import template_path
    from core.export.graded import graded_stacks

    out = tmp_path_factory.mktemp("teaser_graded")
    prep = wf.prepare(template_path("teaser_shirt_pants"))
    solver = wf.make_solver(prep)
    ref = wf.reference(prep, solver=solver).pattern
    patterns = {s: wf.transfer(prep, s, solver=solver, start=ref).pattern for s in ("XS", "M", "XL")}
    own = [s for s in patterns if wf.is_own_size(prep, s)]
    assert own == ["M"]
    export_graded(patterns, out / "graded", sample="M")
    wf.export(ref, out / "single", "dxf")
    return out, patterns, graded_stacks(patterns, sample="M")


def _block_parts(block):
    """Sew lines, cut lines, turn points and notch slits of one AAMA block (mm), moved so that the middle of
    its grain line is the origin."""
    grain = [e for e in block if e.dxftype() == "LINE" and e.dxf.layer == "7"][0]
    o = (np.array(grain.dxf.start)[:2] + np.array(grain.dxf.end)[:2]) / 2

    def poly(layer):
        return [
            np.array(list(e.get_points("xy"))) - o
            for e in block
            if e.dxftype() == "LWPOLYLINE" and e.dxf.layer == layer
        ]

    return {
        "cut": poly("1"),
        "sew": poly("14"),
        "turn": np.array([tuple(e.dxf.location)[:2] for e in block if e.dxftype() == "POINT" and e.dxf.layer == "2"])
        - o,
        "notch": np.array(
            [
                [*tuple(e.dxf.start)[:2], *tuple(e.dxf.end)[:2]]
                for e in block
                if e.dxftype() == "LINE" and e.dxf.layer == "4"
            ]
        )
        - np.tile(o, 2),
    }


def test_graded_own_size_is_the_single_size_pattern(teaser_graded):
    """The graded nest's M is `ease export` of the design's own M: the same sew and cut lines, turn points and
    notches (the graded M used to be a re-solve on M, its sew lines 5-14 mm shorter)."""
    import ezdxf

    out = teaser_graded[0]
    graded = ezdxf.readfile(out / "graded" / "graded_astm.dxf")
    single = ezdxf.readfile(out / "single" / "pattern_astm.dxf")
    summary = json.loads((out / "graded" / "graded.json").read_text())
    assert summary["sample_size"] == "M"
    texts = [e.dxf.text for e in graded.modelspace() if e.dxftype() == "TEXT"]
    assert "Sample Size: M" in texts
    pieces = [b.name for b in single.blocks if not b.name.startswith("*")]
    assert len(pieces) == 10
    for name in pieces:
        a, b = _block_parts(single.blocks.get(name)), _block_parts(graded.blocks.get(f"{name}_M"))
        for key in ("cut", "sew"):
            assert len(a[key]) == len(b[key])
            for x, y in zip(a[key], b[key]):
                assert x.shape == y.shape and np.allclose(x, y, atol=1e-6)
        for key in ("turn", "notch"):
            assert a[key].shape == b[key].shape and np.allclose(a[key], b[key], atol=1e-6), (name, key)


def test_graded_sizes_share_grade_points(teaser_graded):
    """Every size of a piece has the same notches and turn points (AAMA layers 4 and 2), in the same order:
    the k-th notch is on the same seam side, the k-th turn point on the same sew-line vertex or by the same
    corner of the cut line. Without the shared points shirt.front had 18 notches at XS and 20 at M, and 18
    turn points at XL against 24."""
    import dataclasses

    import ezdxf

    from core.export.dxf import piece_turn_points
    from core.export.pieces import build_pieces

    out, patterns, stacks = teaser_graded
    doc = ezdxf.readfile(out / "graded" / "graded_astm.dxf")
    sizes = ("XS", "M", "XL")
    pieces = sorted({b.name.rsplit("_", 1)[0] for b in doc.blocks if not b.name.startswith("*")})
    assert len(pieces) == 10
    for name in pieces:
        parts = [_block_parts(doc.blocks.get(f"{name}_{s}")) for s in sizes]
        assert len({p["turn"].shape for p in parts}) == 1 and len({p["notch"].shape for p in parts}) == 1, name
    # the order, from the drawings the files are written from
    front = stacks["shirt.front"]
    # what the shared points are for: by its own rule XL's front has other corners, XS's other notches
    assert len(piece_turn_points(dataclasses.replace(front["XL"], turn_points=None))) != len(front["XL"].turn_points)
    alone = {p.name: p for p in build_pieces(patterns["XS"])}
    assert len(alone["shirt.front"].notches) != len(front["XS"].notches)
    for name, stack in stacks.items():
        keys = {s: [(n.seam, n.side) for n in d.notches] for s, d in stack.items()}
        assert keys["XS"] == keys["M"] == keys["XL"], name
        for seam, side in set(keys["M"]):  # each notch at about the same fraction of its seam side
            frac = {s: np.array([n.s for n in d.notches if (n.seam, n.side) == (seam, side)]) for s, d in stack.items()}
            frac = {s: f / max(f[-1], 1e-12) for s, f in frac.items()}
            assert np.allclose(frac["XS"], frac["M"], atol=0.05) and np.allclose(frac["XL"], frac["M"], atol=0.05)
        where = {}
        for s, d in stack.items():
            sew = np.concatenate(d.sew)
            ids = np.concatenate(d.sew_ids)
            dist = np.linalg.norm(d.turn_points[:, None] - sew[None], axis=2)
            on = dist.min(axis=1) < 1e-9
            where[s] = [int(ids[j]) if o else -1 for j, o in zip(dist.argmin(axis=1), on)]
            cut = np.concatenate(d.cut)
            assert np.all(np.min(np.linalg.norm(d.turn_points[~on][:, None] - cut[None], axis=2), axis=1) < 1e-12)
        assert where["XS"] == where["M"] == where["XL"], name
