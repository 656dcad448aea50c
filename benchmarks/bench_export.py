"""Export benchmark: time per format and the geometric accuracy of the files.

Patterns: the pattern stage's synthetic front/back tube (solved by the real
optimizer) and, when the pipeline runs, the teaser shirt + pants design on the
default body. For each: milliseconds to build the pieces and to render each
format, and what the files say read back: SVG piece sizes vs the pattern (mm),
DXF sew-line lengths vs the pattern (mm), the PDF test square (mm), measured
allowance width vs requested (mm), notch arc-length mismatch across seams (mm).
The marker's efficiency is benchmarks/bench_marker.py's (``ease bench --only marker``).
Writes ``export.md`` and ``export.json`` into ``out_dir``.
"""

from __future__ import annotations

import importlib.util
import io
import re
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SYNTHETIC = HERE.parent / "tests" / "helpers" / "synthetic_pattern.py"
DXF_READER = HERE.parent / "tests" / "helpers" / "dxf_reader.py"  # the tests' second, ezdxf-independent reader


def _load(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up while the class is made
    spec.loader.exec_module(module)
    return module


def _two_panels():
    """The synthetic tube of the pattern tests, loaded by file path (test helpers are no package)."""
    return _load(SYNTHETIC, "ease_bench_synthetic_pattern").two_panels()


def _patterns():
    from core.design.templates import template_path
    from core.pattern.solve import solve_pattern
    from core.workflows import prepare

    cut, body = _two_panels()
    yield "synthetic front/back tube", solve_pattern(cut, body, style="synthetic tube"), None
    try:
        prep = prepare(template_path("teaser_shirt_pants"))
        yield "teaser shirt + pants (Anny)", solve_pattern(prep.cut, prep.reference, style=prep.design.name), None
    except Exception as exc:  # the benchmark reports what it could not run
        yield "teaser shirt + pants (Anny)", None, f"{type(exc).__name__}: {exc}"


def _accuracy(pattern, pieces, texts: dict) -> dict:
    import ezdxf

    from core.geom.polygon import distance_to_polyline
    from core.geom.polyline import polyline_length

    out = {}
    # allowance: distance from each sew edge midpoint to the cut line vs its width
    err = []
    for p in pieces:
        for sew, cut, w in zip(p.sew, p.cut, p.edge_allowance):
            mid = 0.5 * (sew + np.roll(sew, -1, axis=0))
            err.append(np.abs(distance_to_polyline(mid, cut) - w))
    out["allowance_err_mm_p95"] = float(np.percentile(np.concatenate(err), 95) * 1000)
    out["allowance_err_mm_max"] = float(np.concatenate(err).max() * 1000)
    # edges off by more than 0.1 mm are the sew edges next to corners, where the allowance is
    # squared or mitred so that sewn corners close, or where a 2 cm hem meets a 1 cm seam:
    # there the nearest cut line is the neighbour's
    out["allowance_edges_within_0.1mm_pct"] = float(100.0 * np.mean(np.concatenate(err) <= 1e-4))
    # notches: same count on both sides of every seam, at equal arc lengths from the nearer end (the first half
    # from the start, the second from the end, a middle one at half of each side; a gathered seam's at equal
    # fractions of each side): the mismatch in mm along the shorter side
    by = {p.name: p for p in pieces}
    worst, count_ok = 0.0, True
    for s in pattern.seams:
        a = np.array([n.s for n in by[s.panel_a].notches if n.seam == s.name and n.side == "a"])
        b = np.array([n.s for n in by[s.panel_b].notches if n.seam == s.name and n.side == "b"])
        count_ok &= len(a) == len(b)
        if len(a) == len(b) and len(a) > 2:
            la, lb = a[-1], b[-1]
            off = np.abs(a / la - b / lb) * min(la, lb)
            if not s.gathered:
                half = len(a) // 2
                off[:half] = np.abs(a[:half] - b[:half])
                off[len(a) - half :] = np.abs((la - a[len(a) - half :]) - (lb - b[len(a) - half :]))
            worst = max(worst, float(off.max()))
    out["notch_counts_match"] = bool(count_ok)
    out["notch_arclength_mismatch_mm"] = worst * 1000
    # SVG: piece sizes (mm) vs the pattern's
    root = ET.fromstring(texts["svg"])
    ns = {"svg": "http://www.w3.org/2000/svg"}
    size_err = 0.0
    for g, p in zip(root.findall("svg:g", ns), pieces):
        d = g.find("svg:path[@class='sew']", ns).get("d")
        pts = np.array([[float(x), float(y)] for x, y in re.findall(r"(-?[\d.]+),(-?[\d.]+)", d)])
        panel = pattern.panel(p.name)
        want = np.ptp(panel.uv[p.sew_ids[0]] @ p.rotation.T, axis=0) * 1000
        size_err = max(size_err, float(np.abs(np.ptp(pts, axis=0) - want).max()))
    out["svg_size_err_mm"] = size_err
    # DXF (ASTM): sew-line lengths read back vs the pattern's
    doc = ezdxf.read(io.StringIO(texts["dxf"]))
    len_err = 0.0
    for blk, p in zip([b for b in doc.blocks if not b.name.startswith("*")], pieces):
        sew = [e for e in blk if e.dxf.layer == "14"][0]
        pts = np.array([q[:2] for q in sew.get_points()])
        want = polyline_length(pattern.panel(p.name).uv[p.sew_ids[0]], closed=True) * 1000
        len_err = max(len_err, abs(polyline_length(pts, closed=True) - want))
    out["dxf_sew_length_err_mm"] = len_err
    return out


def run(out_dir, quick: bool = False) -> dict:
    from core.export import dxf, pdf, svg
    from core.export.pieces import build_pieces
    from core.export.print_set import print_set
    from core.export.validate import validate_pattern
    from core.fileio import write_json, write_text
    from core.geom.layout import layout_pieces

    out_dir = Path(out_dir)
    results = []
    for name, pattern, error in _patterns():
        if pattern is None:
            results.append({"pattern": name, "error": error})
            continue
        row = {
            "pattern": name,
            "pieces": len(pattern.panels),
            "boundary_vertices": int(sum(len(b) for p in pattern.panels for b in p.boundary)),
        }
        warnings = validate_pattern(pattern, strict=False)
        t = time.perf_counter()
        pieces = build_pieces(pattern, warnings=warnings)
        row["build_ms"] = (time.perf_counter() - t) * 1000
        row["warnings"] = len(warnings)
        lay = layout_pieces([p.bbox for p in pieces], 0.88, 0.02)
        lay_pdf = layout_pieces([p.bbox for p in pieces], 0.88, 0.02, reserve=pdf.TEST_RESERVE)
        # home-printer pages: each mirrored pair printed once (the export's default)
        printed, _ = print_set(pattern, pieces)
        row["printed_pieces"] = len(printed)
        t, c = time.perf_counter(), time.process_time()
        sheets = {paper: pdf.print_sheet(printed, paper) for paper in ("a4", "letter")}
        row["pdf_nest_ms"] = (time.perf_counter() - t) * 1000 / 2
        row["pdf_nest_cpu_ms"] = (time.process_time() - c) * 1000 / 2
        texts = {}
        for fmt, fn in (
            ("svg", lambda: svg.svg_document(pieces, lay, pattern.style)),
            ("dxf", lambda: dxf.astm_text(pieces, lay, pattern.style, "M")),
            ("dxf_r12", lambda: dxf.astm_r12_text(pieces, lay, pattern.style, "M")),
            ("dxf_plain", lambda: dxf.plain_text(pieces, lay, pattern.style)),
            ("pdf_a4", lambda: pdf.tiled_pdf(printed, sheets["a4"], "a4", pattern.style)),
            ("pdf_letter", lambda: pdf.tiled_pdf(printed, sheets["letter"], "letter", pattern.style)),
            ("pdf_plotter", lambda: pdf.plotter_pdf(pieces, lay_pdf, pattern.style)),
        ):
            t = time.perf_counter()
            texts[fmt] = fn()
            row[f"{fmt}_ms"] = (time.perf_counter() - t) * 1000
        for paper, lay_p in sheets.items():
            row[f"{paper}_pages"], row[f"{paper}_empty_pages"] = _page_counts(
                printed, lay_p, paper, texts[f"pdf_{paper}"]
            )
            # every piece printed (`--print-all`), for comparison
            every = pdf.print_sheet(pieces, paper)
            row[f"{paper}_pages_print_all"] = int(pdf.sheet_pages(pieces, every, paper)[1].sum())
        row.update(_two_readers(pattern, pieces, texts))
        rects = re.findall(rb"(-?[\d.]+) (-?[\d.]+) re", _page_one(texts["pdf_a4"]))
        squares = [float(w) for w, h in rects if abs(float(w) - float(h)) < 1e-3 and float(w) > 100]
        row["pdf_test_square_mm"] = squares[0] * 25.4 / 72 if squares else None
        row.update(_accuracy(pattern, pieces, texts))
        results.append(row)

    lines = [
        "# Export benchmark",
        "",
        "Time to build the pieces (sew/cut lines, notches, grain, labels) and to render each format; "
        "accuracy of the files read back (mm). Allowance error: distance from each sew-line edge's midpoint to "
        "the cut line minus the requested width; edges off by more than 0.1 mm are those next to "
        "corners (allowance squared or mitred so sewn corners close) or where a 2 cm hem meets a 1 cm seam: "
        "there the nearest cut line is the neighbour's. Tiled PDFs (a4, letter): each mirrored pair printed "
        "once, labelled cut 2 (the export's default; `printed_pieces` drawings), `*_pages_print_all` the same "
        "paper with every piece printed (`ease export --print-all`); empty pages: printed pages that no cut or "
        "sew line crosses; `pdf_nest_ms` / `pdf_nest_cpu_ms`: wall / CPU time of the print layout per paper.",
        "",
    ]
    keys = [
        "pieces",
        "boundary_vertices",
        "warnings",
        "build_ms",
        "svg_ms",
        "dxf_ms",
        "dxf_r12_ms",
        "pdf_a4_ms",
        "pdf_plotter_ms",
        "pdf_nest_ms",
        "pdf_nest_cpu_ms",
        "printed_pieces",
        "a4_pages",
        "a4_empty_pages",
        "a4_pages_print_all",
        "letter_pages",
        "letter_empty_pages",
        "letter_pages_print_all",
        "dxf_readers",
        "pdf_test_square_mm",
        "allowance_err_mm_p95",
        "allowance_err_mm_max",
        "allowance_edges_within_0.1mm_pct",
        "notch_counts_match",
        "notch_arclength_mismatch_mm",
        "svg_size_err_mm",
        "dxf_sew_length_err_mm",
    ]
    lines.append("| pattern | " + " | ".join(keys) + " |")
    lines.append("|---" * (len(keys) + 1) + "|")
    for r in results:
        if "error" in r:
            lines.append(f"| {r['pattern']} | not run: {r['error']} |")
            continue
        cells = [f"{r[k]:.3g}" if isinstance(r[k], float) else str(r[k]) for k in keys]
        lines.append(f"| {r['pattern']} | " + " | ".join(cells) + " |")
    lines += ["", "Marker efficiency: `ease bench --only marker` (benchmarks/bench_marker.py, marker.md)."]
    write_text(out_dir / "export.md", "\n".join(lines) + "\n")
    summary = {"results": results}
    write_json(out_dir / "export.json", summary)
    return summary


def _page_counts(pieces, layout, paper: str, data: bytes):
    """(pages in the PDF, pages of them with no cut or sew line), the line check by dense sampling of the lines
    against each printed window (independent of the tiler's clipping test); page 1 holds the test square."""
    from core.export import pdf

    n = len(re.findall(rb"/Type /Page\b", data))
    grid, ink = pdf.sheet_pages(pieces, layout, paper)
    pts = []
    for i, p in enumerate(pieces):
        for loop in list(p.cut) + list(p.sew):
            q = layout.place(i, loop)
            b = np.roll(q, -1, axis=0)
            t = np.linspace(0.0, 1.0, 21)[:, None, None]
            pts.append((q[None] + t * (b - q)[None]).reshape(-1, 2))
    pts = np.concatenate(pts)
    empty = 0
    for r, c in zip(*np.nonzero(ink)):
        w = grid.window(r, c)
        if not np.any(np.all((pts >= w[0]) & (pts <= w[1]), axis=1)):
            empty += 1
    return n, empty


def _two_readers(pattern, pieces, texts: dict) -> dict:
    """Every DXF variant through ezdxf (audit, recover) and the tests' independent reader: "pass", or what failed."""
    import ezdxf
    from ezdxf import recover

    reader = _load(DXF_READER, "ease_bench_dxf_reader")
    want_sew = [p.sew for p in pieces]
    want_len = sorted(sum(reader.polyline_length(l * 1000, True) for l in s) for s in want_sew)
    want_notches = sum(len(p.notches) for p in pieces)
    failed = []
    for fmt in ("dxf", "dxf_r12", "dxf_plain"):
        text = texts[fmt]
        try:
            doc = ezdxf.read(io.StringIO(text))
            if doc.audit().has_errors:
                failed.append(f"{fmt}: ezdxf audit")
            if recover.read(io.BytesIO(text.encode("utf-8")))[1].has_errors:
                failed.append(f"{fmt}: ezdxf recover")
            dwg = reader.read(text)
        except Exception as exc:  # a reader that cannot read the file is what this row reports
            failed.append(f"{fmt}: {type(exc).__name__}")
            continue
        if fmt == "dxf_plain":
            ents = dwg.entities
            sew = [e for e in ents if e.layer == "SEW" and e.points is not None]
            notches = sum(1 for e in ents if e.kind == "LINE" and e.layer == "NOTCH")
        else:
            ents = [e for name in (e.value(2) for e in dwg.entities if e.kind == "INSERT") for e in dwg.blocks[name]]
            sew = [e for e in ents if e.layer == "14" and e.points is not None]
            notches = sum(1 for e in ents if e.kind == "LINE" and e.layer == "4")
        got = sorted(reader.polyline_length(e.points, e.closed) for e in sew)
        if len(got) != len(want_len) or np.abs(np.array(got) - want_len).max() > 0.01 or notches != want_notches:
            failed.append(f"{fmt}: pieces/sew lengths/notches differ")
        for var in ("$EXTMIN", "$EXTMAX"):
            v = dwg.header_number(var, 10)
            if v is None or abs(v) >= 1e19:
                failed.append(f"{fmt}: {var} unset")
    return {"dxf_readers": "pass" if not failed else "; ".join(failed)}


def _page_one(data: bytes) -> bytes:
    """Decoded content stream of the first page of a reportlab PDF."""
    import base64
    import zlib

    kids = re.search(rb"/Kids \[\s*(\d+) 0 R", data)
    page = re.search(rb"\n" + kids.group(1) + rb" 0 obj(.*?)endobj", data, re.S).group(1)
    cref = re.search(rb"/Contents (\d+) 0 R", page).group(1)
    obj = re.search(rb"\n" + cref + rb" 0 obj(.*?)endobj", data, re.S).group(1)
    length = int(re.search(rb"/Length (\d+)", obj).group(1))
    start = re.search(rb"stream\r?\n", obj).end()
    raw = obj[start : start + length]
    if b"ASCII85Decode" in obj[:start]:
        raw = base64.a85decode(raw.strip().removesuffix(b"~>"), adobe=False)
    return zlib.decompress(raw) if b"FlateDecode" in obj[:start] else raw


if __name__ == "__main__":
    import json
    import sys

    print(json.dumps(run(sys.argv[1] if len(sys.argv) > 1 else "bench_out"), indent=1, default=str))
