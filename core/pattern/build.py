"""Assemble a :class:`~core.pattern.types.Pattern` from a solve: pieces laid out in a row, achieved scales."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence

import numpy as np

from ..errors import PatternError
from ..geom.mesh import boundary_loops, signed_areas_2d
from .types import Pattern, PatternPanel, PatternSeam

#: Gap between laid-out pieces, metres.
PIECE_GAP = 0.05


@dataclass
class SolveResult:
    """The outcome of one solve: per panel ``uv`` (n, 2), per-triangle targets (f,), the body positions
    ``xyz`` (n, 3) it was solved on, the solve's time, iterations, flip-guard backtracks, energies and
    gathered seam names."""

    uv: Dict[str, np.ndarray]
    target_weft: Dict[str, np.ndarray]
    target_warp: Dict[str, np.ndarray]
    xyz: Dict[str, np.ndarray]
    seconds: float
    iterations: int
    backtracks: int
    energy: List[float] = field(default_factory=list)
    gathered: tuple = ()


def solve_result(panels, state) -> SolveResult:
    """The :class:`SolveResult` of a solve's current iterate (a :class:`~.state.SolveState`) on the stacked
    ``panels`` (:class:`~.panels.PanelData`): per panel uv, targets and body positions."""
    out_uv, tw, tgw, xyz = {}, {}, {}, {}
    f0 = 0
    U, pos = state.U, state.positions
    for pd in panels:
        out_uv[pd.name] = U[pd.offset : pd.offset + pd.n].copy()
        tw[pd.name] = np.asarray(state.c_weft[f0 : f0 + len(pd.faces)], float).copy()
        tgw[pd.name] = np.asarray(state.c_warp[f0 : f0 + len(pd.faces)], float).copy()
        xyz[pd.name] = pos[pd.vertex_ids]
        f0 += len(pd.faces)
    return SolveResult(
        out_uv,
        tw,
        tgw,
        xyz,
        state.seconds,
        state.iteration,
        state.backtracks,
        list(state.energies),
        state.plan.gathered,
    )


def row_layout(uv: Dict[str, np.ndarray], order: Sequence[str], gap: float = PIECE_GAP) -> Dict[str, np.ndarray]:
    """Translate the pieces into one row (left to right, bottoms aligned), gap in metres."""
    out, x = {}, 0.0
    for name in order:
        p = uv[name]
        lo, hi = p.min(axis=0), p.max(axis=0)
        out[name] = p - lo + np.array([x, 0.0])
        x += (hi - lo)[0] + gap
    return out


def build_pattern(
    cut,
    result: SolveResult,
    style: str = "",
    body: Optional[dict] = None,
    mode: str = "reference",
    materials: Optional[dict] = None,
) -> Pattern:
    """Assemble a :class:`Pattern` from a solve; checks it has no flipped triangle."""
    order = [p.name for p in cut.panels]
    uv = row_layout(result.uv, order)
    panels = []
    for p in cut.panels:
        xyz = result.xyz[p.name]
        s = signed_areas_2d(uv[p.name], p.faces)
        if np.any(s <= 0):
            raise PatternError(f"panel {p.name!r}: {int(np.sum(s <= 0))} flipped triangles in the optimized pattern")
        piece = PatternPanel(
            name=p.name,
            garment=p.garment,
            uv=uv[p.name],
            faces=np.asarray(p.faces, int),
            vertex_ids=np.asarray(p.vertex_ids, int),
            xyz=np.asarray(xyz, float),
            grain=np.array([0.0, 1.0]),
            target_weft=result.target_weft[p.name],
            target_warp=result.target_warp[p.name],
            achieved_weft=None,
            achieved_warp=None,
            boundary=[np.asarray(b, int) for b in (p.boundary or boundary_loops(p.faces))],
            hems=[np.asarray(h, int) for h in cut.hems.get(p.name, [])],
            mirror_of=p.mirror_of,
        )
        # the piece keeps its scales: the pattern's report reads them again (PatternPanel.scales)
        piece.achieved_weft, piece.achieved_warp, _ = piece.scales()
        panels.append(piece)
    seams = [
        PatternSeam(
            s.name,
            s.panel_a,
            s.panel_b,
            np.asarray(s.verts_a, int),
            np.asarray(s.verts_b, int),
            gathered=s.name in result.gathered,
        )
        for s in cut.seams
    ]
    body = dict(body if body is not None else cut.body)
    report = {
        "optimize_seconds": result.seconds,
        "iterations": result.iterations,
        "backtracks": result.backtracks,
        "gathered_seams": list(result.gathered),
    }
    darts = dart_report(cut, uv, seams)
    if darts:
        report["darts"] = darts
    return Pattern(
        style=style,
        body=body,
        garments=dict(cut.garments),
        panels=panels,
        seams=seams,
        pins={g: np.asarray(v, int) for g, v in cut.pins.items()},
        materials=dict(materials if materials is not None else cut.materials),
        mode=mode,
        report=report,
    )


def dart_report(cut, uv: Dict[str, np.ndarray], seams: List[PatternSeam]) -> Dict[str, dict]:
    """Per dart: its intake at the mouth in the pattern (``intake_mm``: the mouth's width across
    the dart, negative where the legs cross, i.e. the flattening overlaps cloth there instead of
    taking it in; ``intake_set_mm`` where the design sets one), its legs' lengths and their
    difference (mm), its panel."""
    out = {}
    for s in seams:
        if s.kind != "dart":
            continue
        p = uv[s.panel_a]
        a, b = p[s.verts_a], p[s.verts_b]
        la = float(np.linalg.norm(np.diff(a, axis=0), axis=1).sum())
        lb = float(np.linalg.norm(np.diff(b, axis=0), axis=1).sum())
        rec = (getattr(cut, "darts", {}) or {}).get(s.name, {})
        out[s.name] = {
            "panel": s.panel_a,
            "intake_mm": round(1000 * dart_intake(a[0], b[0], a[-1]), 3),
            "legs_mm": [round(1000 * la, 3), round(1000 * lb, 3)],
            "leg_difference_mm": round(1000 * abs(la - lb), 4),
        }
        if rec.get("intake") is not None:
            out[s.name]["intake_set_mm"] = round(1000 * float(rec["intake"]), 3)
    return out


def dart_intake(mouth_a: np.ndarray, mouth_b: np.ndarray, apex: np.ndarray) -> float:
    """The width (m) of a dart's mouth across the dart in a counter-clockwise piece: leg ``a``
    (the side on the left of mouth -> apex) minus leg ``b`` along the left normal of the dart's
    axis; negative when the legs cross (points (2,), metres)."""
    axis = apex - 0.5 * (mouth_a + mouth_b)
    across = np.array([-axis[1], axis[0]]) / max(float(np.linalg.norm(axis)), 1e-300)
    return float(np.dot(mouth_a - mouth_b, across))
