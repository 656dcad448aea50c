"""The layered drape: an outfit's garments patterned on one body and draped inner first, each over
the ones before it (:func:`drape_outfit`), and its files (:func:`write_outfit`)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np

from ..progress import Progress, report, sub


@dataclass
class LayerRun:
    """One garment of a layered drape.

    Attributes
    ----------
    layer : core.design.outfit.Layer
    pattern : core.workflows.PatternRun, its pattern on the outfit's body.
    drape : core.workflows.DrapeRun, its drape (fit figures against the body).
    over : dict, inner layer name -> :func:`core.drape.layers.layer_measure` of this garment's
        draped vertices against that layer's draped surface (the final frame).
    settled_penetration_pct : float, the largest penetration share (%) into any inner layer over the
        frames that counted as still (the settled frames); 0 for the innermost layer.
    frame_penetration_pct : list of (frame, still frames in a row, largest penetration share %), for
        every frame after the fabric's growth (``grow_frames``) and every still frame.
    pushed : int, start vertices moved out over the inner layers.
    measured_on : dict, the surface its pattern was solved and its ease measured on: ``{"surface":
        "body"}`` or ``{"surface": "skintight over", "layers": [inner names], "offset_mm"}``.
    measure_s : float, s of the drape's wall time spent measuring the penetration frame by frame
        (left out of :attr:`time_per_frame`).
    skin : ((V, 3), (F, 3)) or None, its draped surface closed with the body
        (:func:`core.drape.layers.measure_skin`): the measure of an outer layer over it tells inside
        from outside by it.
    tucked : dict or None, for a tucked garment: its hem's vertices (its longest open edge loop) that
        lie over a later lower garment (``edge_vertices``), how many of them are inside it or less than
        2 mm out (``inside``, ``inside_pct``), the farthest out (``most_outside_mm``) and how far the
        hem's top lies below the lower garment's top (``below_waistband_mm``).
    """

    layer: object
    pattern: object
    drape: object
    over: Dict[str, dict] = field(default_factory=dict)
    settled_penetration_pct: float = 0.0
    frame_penetration_pct: list = field(default_factory=list)
    pushed: int = 0
    tucked: Optional[dict] = None
    measure_s: float = 0.0
    skin: Optional[tuple] = None
    measured_on: dict = field(default_factory=lambda: {"surface": "body", "offset_mm": 0.0})

    @property
    def surface(self):
        r = self.drape.result
        return np.asarray(r.positions, float), np.asarray(r.faces, np.int64)

    @property
    def thickness(self) -> float:
        r = self.drape.result
        t = (r.options or {}).get("thickness")
        return float(t if t is not None else r.material["thickness"])

    @property
    def time_per_frame(self) -> float:
        r = self.drape.result
        return (float(r.timings["simulate"]) - self.measure_s) / max(int(r.frames), 1)


@dataclass
class OutfitRun:
    outfit: object
    layers: List[LayerRun]
    body_vertices: np.ndarray
    body_faces: np.ndarray
    timings: Dict[str, float] = field(default_factory=dict)

    def report(self) -> dict:
        """outfit_report.json: per layer its fit on the body, and on every inner layer."""
        out = {"outfit": self.outfit.to_json(), "layers": [], "timings": self.timings}
        for lr in self.layers:
            a = lr.drape.metrics["all"]
            out["layers"].append(
                {
                    "name": lr.layer.name,
                    "design": lr.layer.source,
                    "tucked": lr.layer.tucked,
                    "frames": int(lr.drape.result.frames),
                    "settled": lr.drape.result.settle_reason,
                    "time_per_frame_s": lr.time_per_frame,
                    "body": {"gap_mm": a["gap_mm"], "penetration_pct": a["penetration_pct"]},
                    "over": lr.over,
                    "settled_penetration_pct": lr.settled_penetration_pct,
                    "start_vertices_pushed_out": lr.pushed,
                    "tucked_hem": lr.tucked,
                    "pattern_measured_on": lr.measured_on,
                }
            )
        return out


def _pushed(pattern, collider, n_body: int, inner: List[LayerRun], thickness: float, rings: int = 40, smooth: int = 10):
    """``pattern`` with every panel's skintight embedding moved out over the inner layers: onto the
    collider's inner-garment and strip faces (those not on the body's ``n_body`` vertices), ``thickness``
    + 1 mm outside them (the strips make the push continuous down to the body past an inner hem);
    then what still lies over an inner garment and inside it (where the body under a loose garment
    is nearer than the garment) onto that garment, as far out. The vertices left where they were
    then follow their moved neighbours over up to ``rings`` mesh rings (the displacement averaged
    outward), and every displacement is smoothed ``smooth`` times, so the start has no step for the
    drape's first frame to tear."""
    from ..drape.layers import push_outside

    if not inner:
        return pattern, 0
    v, f = collider
    movable = np.asarray(f).min(axis=1) >= n_body

    def push(xyz):
        new, _ = push_outside(xyz, v, f, clearance=thickness + 0.001, movable=movable)
        for lr in inner:
            new, _ = push_outside(new, *lr.surface, clearance=lr.thickness + thickness + 0.001)
        return new

    n = 1 + max(int(np.max(p.vertex_ids)) for p in pattern.panels)
    shift = np.zeros((n, 3))
    moved = np.zeros(n, bool)
    for p in pattern.panels:
        xyz = np.asarray(p.xyz, float)
        new = push(xyz)
        ids = np.asarray(p.vertex_ids, int)
        hit = np.any(new != xyz, axis=1)
        shift[ids[hit]] = new[hit] - xyz[hit]
        moved[ids[hit]] = True
    # the unmoved vertices take the mean displacement of their neighbours, ring by ring
    edges = _directed_edges(
        np.concatenate([np.asarray(p.vertex_ids, int)[np.asarray(p.faces, int)] for p in pattern.panels])
    )
    free = ~moved
    for _ in range(rings):
        shift[free] = _neighbour_mean(shift, edges)[free]
    # then every vertex half-way to its neighbours' mean, a few times (neighbours pushed onto different
    # folds of the inner garment, an armpit, no longer start centimetres apart), and pushed out again
    for _ in range(smooth):
        shift = 0.5 * shift + 0.5 * _neighbour_mean(shift, edges)
    panels = [
        replace(p, xyz=push(np.asarray(p.xyz, float) + shift[np.asarray(p.vertex_ids, int)])) for p in pattern.panels
    ]
    return replace(pattern, panels=panels), int(moved.sum())


def _hem(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """The vertices of a garment's longest open edge loop (an upper garment's hem: longer than its
    neckline and cuffs)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from ..drape.layers import open_edges

    edges = open_edges(f)
    n = len(v)
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    length = np.linalg.norm(v[edges[:, 0]] - v[edges[:, 1]], axis=1)
    per = np.bincount(label[edges[:, 0]], weights=length, minlength=label.max() + 1)
    return np.unique(edges[label[edges[:, 0]] == int(np.argmax(per))])


def _tucked_hem(lr: LayerRun, outer: List[LayerRun]) -> Optional[dict]:
    """For a tucked garment: its hem's vertices over a later lower garment, and how many lie inside it."""
    from ..drape.layers import OVERLAP_BAND, PENETRATION_DEPTH, layer_distance

    lowers = [o for o in outer if "lower" in o.layer.kinds]
    if not lr.layer.tucked or not lowers:
        return None
    v, f = lr.surface
    hem = _hem(v, f)
    lv, lf = lowers[0].surface
    dist, over = layer_distance(v[hem], lv, lf, skin=lowers[0].skin)
    near = over & (np.abs(dist) <= OVERLAP_BAND)
    inside = near & (dist < PENETRATION_DEPTH)  # the hem's edge may poke 2 mm through, as in the penetration share
    n = int(near.sum())
    return {
        "under": lowers[0].layer.name,
        "hem_vertices": int(len(hem)),
        "edge_vertices": n,
        "inside": int(inside.sum()),
        "inside_pct": 100.0 * int(inside.sum()) / n if n else 0.0,
        "most_outside_mm": float(dist[near].max() * 1000.0) if n else 0.0,
        "below_waistband_mm": float((lv[np.unique(lf)][:, 2].max() - v[hem][:, 2].max()) * 1000.0),
    }


#: the surfaces an outer garment's pattern can be solved over (:func:`drape_outfit`'s ``over``)
OVER = ("skintight", "draped", "body")
#: times the draped offset is averaged with its body neighbours' (a fold of the inner garment, a
#: hem's ramp: no step in the surface the pattern is solved on)
DRAPED_SMOOTHING = 3


def _over_inner(prep, body, inner: List[LayerRun], over: str) -> dict:
    """Move ``prep``'s reference body out over the inner layers: their skintight surface (``over``
    "skintight") or their draped one ("draped"); returns the record of the surface the pattern is
    solved and measured on."""
    from ..body.instance import spec_instance
    from ..errors import DrapeError
    from ..geom.mesh import vertex_normals

    if over not in OVER:
        raise DrapeError(f"over: expected one of {', '.join(OVER)}, got {over!r}")
    if over == "body" or not inner:
        return {"surface": "body", "offset_mm": 0.0}
    _, faces = spec_instance(prep.cut.body, model=body)
    normals = vertex_normals(prep.reference, faces)
    names = [lr.layer.name for lr in inner]
    if over == "skintight":
        offset = sum(2.0 * lr.thickness for lr in inner)
        prep.reference = prep.reference + normals * offset
        return {"surface": "skintight over", "layers": names, "offset_mm": offset * 1000.0}
    offset = _draped_offset(prep.reference, np.asarray(faces, np.int64), normals, inner)
    prep.reference = prep.reference + normals * offset[:, None]
    on_cut = np.asarray(prep.cut.embedding @ offset).ravel() * 1000.0  # the garment's own vertices
    moved = on_cut[on_cut > 1e-6]
    return {
        "surface": "draped over",
        "layers": names,
        "offset_mm": float(moved.mean()) if len(moved) else 0.0,
        "offset_p95_mm": float(np.percentile(moved, 95)) if len(moved) else 0.0,
        "offset_max_mm": float(moved.max()) if len(moved) else 0.0,
        "covered_pct": 100.0 * len(moved) / max(len(on_cut), 1),
    }


def _draped_offset(body_v, body_f, normals, inner: List[LayerRun]) -> np.ndarray:
    """(V,) m, how far each body vertex moves out along its normal onto the inner layers' draped
    surfaces as the outer garment's drape meets them (:func:`core.drape.layers.layer_collider`: each
    moved out by its fabric's thickness, open edges joined to the body by a ramp): the first hit of
    the normal's ray within :data:`COVER_BAND <core.drape.layers.COVER_BAND>` on an inner garment or a
    ramp, 0 where it meets none; then averaged :data:`DRAPED_SMOOTHING` times with the vertex's
    neighbours (never below the hit where the ray met a garment)."""
    from ..drape.layers import COVER_BAND, layer_collider
    from ..geom.queries import ray_hit_distance

    coll_v, coll_f = layer_collider(body_v, body_f, [(*lr.surface, lr.thickness) for lr in inner])
    garment = coll_f[coll_f.min(axis=1) >= len(body_v)]  # the inner garments' and their ramps' triangles
    hit = ray_hit_distance(body_v, normals, coll_v, garment, max_t=COVER_BAND)
    edges = _directed_edges(np.asarray(body_f, int))
    offset = hit.copy()
    for _ in range(DRAPED_SMOOTHING):
        offset = np.maximum(0.5 * offset + 0.5 * _neighbour_mean(offset, edges), hit)
    return offset


def _directed_edges(faces: np.ndarray) -> np.ndarray:
    """(6F, 2) int, every triangle edge of ``faces`` (F, 3) in both directions (shared edges repeat:
    a neighbour across two triangles counts twice, as before)."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return np.concatenate([edges, edges[:, ::-1]])


def _neighbour_mean(values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """(N,) or (N, k), each vertex's mean of ``values`` over its neighbours along ``edges``
    (:func:`_directed_edges`); 0 for a vertex with none."""
    n = len(values)
    count = np.maximum(np.bincount(edges[:, 0], minlength=n), 1).reshape((n,) + (1,) * (values.ndim - 1))
    total = np.zeros_like(values, dtype=float)
    np.add.at(total, edges[:, 0], values[edges[:, 1]])
    return total / count


def drape_outfit(
    outfit,
    options=None,
    refine_edge_length: Optional[float] = None,
    over: str = "skintight",
    progress: Optional[Progress] = None,
) -> OutfitRun:
    """Pattern every layer of ``outfit`` on its body and drape them inner first, each against the body
    plus the inner layers' draped surfaces (:mod:`core.drape.layers`).

    Parameters
    ----------
    outfit : core.design.outfit.Outfit, or a path / dict for :func:`core.design.outfit.load_outfit`
    options : DrapeOptions or mapping, for every layer's drape
    refine_edge_length : float m or None: overrides every design's cut refinement (coarser: faster)
    over : ``"skintight"`` (default): an outer garment's pattern is solved, and its ease measured, over
        the inner layers' skintight surface: the body moved out along its normals by twice each inner
        fabric's thickness (its contact offset and its own); ``"draped"``: over the inner layers' draped
        surfaces (each out by its thickness, as the drape meets them: :func:`_draped_offset`);
        ``"body"``: over the body, as if worn alone
    """
    from ..body.registry import load_spec
    from ..design import load_design
    from ..design.outfit import Outfit, load_outfit
    from ..drape import drape as _drape
    from ..drape.layers import layer_collider, layer_measure, measure_skin
    from ..drape.options import DrapeOptions
    from ..metrics.drape import drape_metrics
    from ._drape import DrapeRun, _drape_figures, pattern_body
    from ._pattern import reference
    from ._prepare import prepare

    t0 = time.perf_counter()
    if not isinstance(outfit, Outfit):
        outfit = load_outfit(outfit)
    opts = DrapeOptions.coerce(options)
    body = load_spec(outfit.body)
    runs: List[LayerRun] = []
    n = len(outfit.layers)
    body_v = body_f = None
    for i, layer in enumerate(outfit.layers):
        span = sub(progress, i / n, (i + 1) / n)
        design = layer.design
        if refine_edge_length is not None:
            data = design.to_json()
            data["refine_edge_length"] = refine_edge_length
            design = load_design(data)
        report(span, 0.0, f"outfit: {layer.name}: cut and pattern")
        prep = prepare(design, body=body, progress=sub(span, 0.0, 0.2))
        surface = _over_inner(prep, body, runs, over)
        prun = reference(prep, progress=sub(span, 0.2, 0.35))
        prun.pattern.report["measured_on"] = surface
        pattern = prun.pattern
        if body_v is None:
            body_v, body_f = pattern_body(pattern, "ease outfit")
        from ..drape.materials import get_material

        mat = get_material((pattern.materials or {}).get("fabric"))
        thick = float(opts.thickness if opts.thickness is not None else mat.thickness)
        coll_v, coll_f = layer_collider(body_v, body_f, [(*lr.surface, lr.thickness) for lr in runs], buried=True)
        start, pushed = _pushed(pattern, (coll_v, coll_f), len(body_v), runs, thick)
        frames: list = []
        spent = [0.0]

        def on_frame(frame, x, still, _inner=tuple(runs), _frames=frames, _spent=spent):
            # every frame once the fabric has grown (the settled frames among them); not counted as drape time
            if not _inner or (frame <= opts.grow_frames and still == 0):
                return
            t = time.perf_counter()
            pct = max(layer_measure(x, *lr.surface, skin=lr.skin)["penetration_pct"] for lr in _inner)
            _frames.append((int(frame), int(still), pct))
            _spent[0] += time.perf_counter() - t

        report(span, 0.35, f"outfit: {layer.name}: drape over {i} layer(s)")
        result = _drape(
            start, coll_v, coll_f, material=mat, options=opts, progress=sub(span, 0.35, 0.95), on_frame=on_frame
        )
        metrics = drape_metrics(result, body_v, body_f, pattern=pattern)
        run = DrapeRun(result, metrics, body_v, body_f, _drape_figures(result, metrics))
        lr = LayerRun(layer, prun, run, pushed=pushed, frame_penetration_pct=frames, measure_s=spent[0])
        lr.measured_on = surface
        x = np.asarray(result.positions, float)[np.unique(result.faces)]
        lr.over = {inner.layer.name: layer_measure(x, *inner.surface, skin=inner.skin) for inner in runs}
        still = [p for (_, s, p) in frames if s > 0]
        lr.settled_penetration_pct = max(still) if still else (frames[-1][2] if frames else 0.0)
        if i < n - 1:  # an outer layer's measure over this one tells inside from outside by its skin
            lr.skin = measure_skin(body_v, body_f, *lr.surface)
        runs.append(lr)
    for i, lr in enumerate(runs):
        if lr.layer.tucked:  # the hem is measured over the lower garment's skin
            for lower in runs[i + 1 :]:
                if lower.skin is None and "lower" in lower.layer.kinds:
                    lower.skin = measure_skin(body_v, body_f, *lower.surface)
        lr.tucked = _tucked_hem(lr, runs[i + 1 :])
    report(progress, 1.0, "outfit: draped")
    return OutfitRun(outfit, runs, body_v, body_f, {"total": time.perf_counter() - t0})


def outfit_summary(run: OutfitRun) -> str:
    """The lines the CLI prints after a layered drape."""
    lines = []
    for lr in run.layers:
        r = lr.drape.result
        line = f"  {lr.layer.name}: {r.frames} frames ({r.settle_reason}), {lr.time_per_frame * 1000:.0f} ms/frame"
        settled = any(still > 0 for _, still, _ in lr.frame_penetration_pct)
        for name, m in lr.over.items():
            line += (
                f"; over {name}: penetration {m['penetration_pct']:.2f} % ({'settled max' if settled else 'last frame'} "
                f"{lr.settled_penetration_pct:.2f} %), gap {m['gap_mm']['mean']:.1f} mm mean, "
                f"{m['gap_mm']['p95']:.1f} mm p95"
            )
        if lr.tucked:
            line += f"; hem inside {lr.tucked['under']}: {lr.tucked['inside']}/{lr.tucked['edge_vertices']}"
        lines.append(line)
    return f"outfit {run.outfit.name}: {len(run.layers)} layers\n" + "\n".join(lines)


def write_outfit(out, run: OutfitRun, formats=("svg", "dxf", "pdf", "glb", "obj"), preview: bool = True) -> Path:
    """Into ``out``, atomically: per layer ``<layer>/pattern/`` (pattern.json, report.json),
    ``<layer>/drape/`` (the drape's files) and ``<layer>/export/`` (its cutting-room files in
    ``formats``, its own GLB/OBJ included); ``outfit.glb`` / ``outfit.obj`` + ``outfit.mtl`` (every
    garment its own mesh with its own material) and ``outfit_report.json``."""
    from ..export.outfit import outfit_files
    from ..fileio import output_dir, write_bytes, write_json
    from ._drape import write_drape
    from ._export import export
    from ._pattern import write_pattern

    with output_dir(out) as tmp:
        tmp = Path(tmp)
        for lr in run.layers:
            d = tmp / lr.layer.name.replace("/", "_").replace(" ", "_")
            r = lr.drape.result
            write_pattern(d / "pattern", lr.pattern, preview=preview)
            write_drape(d / "drape", lr.drape, pattern=lr.pattern.pattern, preview=preview)
            export(lr.pattern.pattern, d / "export", formats=list(formats), drape=(r.positions, r.faces))
        floor = float(np.min(run.body_vertices[:, 2]))
        garments = [(lr.layer.name, lr.drape.result, lr.pattern.pattern) for lr in run.layers]
        for name, data in outfit_files(garments, floor, formats, title=run.outfit.name).items():
            write_bytes(tmp / name, data)
        write_json(tmp / "outfit_report.json", run.report())
    return Path(out)
