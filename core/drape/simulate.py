"""``drape()``: a sewing pattern draped on a body, start to settled, in one call.

The garment starts on the body (the skintight embedding), relaxes to its
pattern size under gravity, pins and body contact (the rest shape grows from
the skintight stretch to the pattern's over the first ``grow_frames``, so
loose fabric unfolds quasi-statically and a looser pattern drapes like a
continuation of a tighter one), and stops once it has settled (its kinetic
energy stays under a threshold for some frames) or at a frame limit; the
result says which. The solver is :class:`core.drape.xpbd.DrapeSolver`, the
schedule :mod:`core.drape.schedule`.
"""

from __future__ import annotations

import time
from typing import Mapping, Optional, Union

from ..progress import Progress, report
from .materials import Material, get_material
from .options import DrapeOptions
from .pleats import draped_cloth
from .result import DrapeResult, collect
from .schedule import run
from .xpbd import DrapeSolver, check_body


def drape(
    pattern,
    body_vertices,
    body_faces,
    material: Union[None, str, Material, Mapping] = None,
    options: Union[None, DrapeOptions, Mapping] = None,
    progress: Optional[Progress] = None,
    on_frame=None,
) -> DrapeResult:
    """Drape a sewing pattern on a body (``options.solver``: projective dynamics by default).

    Parameters
    ----------
    pattern : :class:`core.pattern.types.Pattern`, with the skintight embedding ``xyz``
        of every panel on this body.
    body_vertices : (V, 3) float, metres, +Z up.
    body_faces : (F, 3) int, outward-oriented triangles.
    material : preset name, :class:`Material` or dict; default: the pattern's
        ``materials["fabric"]``, else cotton.
    options : :class:`DrapeOptions` or a dict of its fields.
    progress : optional ``progress(fraction, message)``; may raise Cancelled.
    on_frame : optional ``on_frame(frame, particle positions (P, 3), still frames in a row)``
        after every frame (:func:`core.drape.schedule.run`).

    Returns
    -------
    DrapeResult

    Raises
    ------
    DrapeError on invalid input, an unavailable device, or divergence (naming
    the frame and the likely cause).
    """
    t_start = time.perf_counter()
    opts = DrapeOptions.coerce(options)
    if material is None:
        material = (getattr(pattern, "materials", None) or {}).get("fabric")
    mat = get_material(material)
    # the body is checked before the pattern is welded (the solver checks it again at its own door)
    body_v, body_f = check_body(body_vertices, body_faces)
    report(progress, 0.0, "drape: welding the pattern")
    # pleats opened (their cloth inserted, pre-folded and stitched, pressed creases held); the drape's
    # own mesh (refined where the cloth hangs free), on which gathered seams are sewn as gathers
    # (their long side refined on its own); on the pattern's mesh they stay welded as paired
    cloth = draped_cloth(pattern, opts.refine_edge)
    t_cloth = time.perf_counter()
    solver = DrapeSolver(cloth, body_v, body_f, mat, opts)
    state = solver.state()
    t_ready = time.perf_counter()
    settling = run(solver, state, progress, on_frame=on_frame)
    t_sim = time.perf_counter()
    x, v = state.x.numpy(), state.v.numpy()
    report(progress, 1.0, "drape: settled" if settling.settled else "drape: frame limit reached")
    timings = {
        "prepare": t_cloth - t_start + solver.timings["prepare"],
        "compile": solver.timings["compile"],
        "simulate": t_sim - t_ready,
    }
    result = collect(cloth, x, v, settling, timings, mat, opts, str(solver.device), solver.self_radius)
    result.timings["total"] = time.perf_counter() - t_start
    return result
