"""The drape's schedule: rest-shape growth, the settle test, the divergence check.

The solver (:class:`core.drape.xpbd.DrapeSolver`) advances a state frame by
frame; this module decides how the rest shape grows over the first frames,
when the drape has settled, and when it has blown up (naming the frame and
the likely cause).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..errors import DrapeError
from ..progress import Progress, report
from .materials import Material
from .mesh import Cloth
from .options import DrapeOptions
from .strain import face_strains

# Half a percent of the fabric torn is a blow-up; a few bad triangles are input defects.
TORN_SHARE = 0.005


def initial_growth(options: DrapeOptions) -> float:
    """Rest-shape growth at the start: 0 (skintight rest shape) when the fabric grows, else 1 (pattern size)."""
    return 0.0 if options.grow_frames > 0 else 1.0


def growth_per_substep(options: DrapeOptions) -> Optional[float]:
    """Growth added every substep (reaching 1 after ``grow_frames`` frames); None when it starts grown."""
    if options.grow_frames > 0:
        return 1.0 / (options.grow_frames * options.substeps)
    return None


def settle_speed(velocities: np.ndarray, trim: float = 0.0) -> float:
    """RMS speed of the particles, leaving out the fastest ``trim`` fraction.

    Parameters
    ----------
    velocities : (n, 3) float, m/s.
    trim : fraction in [0, 0.5).

    Returns
    -------
    float, m/s (0 for no particles).
    """
    if len(velocities) == 0:
        return 0.0
    sq = np.sum(np.asarray(velocities, dtype=float) ** 2, axis=1)
    keep = len(sq) - int(np.floor(trim * len(sq)))
    if keep < len(sq):
        sq = np.partition(sq, keep - 1)[:keep]
    return float(np.sqrt(np.mean(sq)))


def check_divergence(
    frame: int,
    xs: np.ndarray,
    vs: np.ndarray,
    opts: DrapeOptions,
    mat: Material,
    dt: float,
    cloth: Optional[Cloth] = None,
) -> None:
    """Raise DrapeError naming the frame and the likely cause when the state blew up.

    Parameters
    ----------
    frame : the frame just simulated (1-based).
    xs : (P, 3) float, particle positions, metres.
    vs : (n, 3) float, velocities of the free particles, m/s.
    opts, mat : the drape's options (its limits) and material (named in the message).
    dt : substep, seconds.
    cloth : the cloth, for the strain test (skipped without it).
    """
    step = f"time step {dt * 1e3:.3g} ms ({opts.substeps} substeps at {opts.fps:g} fps)"
    if not np.all(np.isfinite(xs)) or not np.all(np.isfinite(vs)):
        raise DrapeError(
            f"drape diverged at frame {frame}: positions became NaN/inf; likely cause: "
            f"{step} too large for the stiffness of {mat.name!r}, or a degenerate pattern triangle"
        )
    extent = float(np.linalg.norm(xs.max(axis=0) - xs.min(axis=0)))
    if extent > opts.max_extent:
        raise DrapeError(
            f"drape diverged at frame {frame}: the garment's bounding box grew to {extent:.1f} m "
            f"(limit {opts.max_extent:g} m); likely cause: {step} too large, or stiffness "
            f"of {mat.name!r} out of range"
        )
    if len(vs):
        rms = float(np.sqrt(np.mean(np.sum(vs.astype(float) ** 2, axis=1))))
        if rms > opts.max_speed:
            raise DrapeError(
                f"drape diverged at frame {frame}: kinetic energy exploded (RMS speed "
                f"{rms:.1f} m/s > {opts.max_speed:g} m/s); likely cause: {step} too large "
                f"for the stiffness of {mat.name!r}"
            )
    if cloth is not None and len(cloth.faces):
        fw, fg, _ = face_strains(xs.astype(float), cloth)
        worst = np.maximum(np.abs(fw), np.abs(fg))
        area = cloth.rest_area * (~cloth.sliver if len(cloth.sliver) else 1.0)
        torn = float(area[worst > opts.max_strain].sum() / max(area.sum(), 1e-30))
        if torn > TORN_SHARE:
            raise DrapeError(
                f"drape diverged at frame {frame}: {torn * 100:.1f} % of the fabric is stretched "
                f"beyond {opts.max_strain * 100:.0f} % (up to {worst.max() * 100:.0f} %); likely "
                f"cause: {step} too large, a pattern far too small for the body, or pins far "
                f"from their pattern places"
            )


@dataclass
class Settling:
    """How a drape ended.

    Attributes
    ----------
    frames : int, frames simulated.
    settled : bool, True when the settle test passed (else the frame limit was hit).
    speeds : (frames,) float, m/s, the trimmed RMS particle speed after each frame.
    """

    frames: int
    settled: bool
    speeds: np.ndarray

    @property
    def reason(self) -> str:
        return "settled" if self.settled else "frame limit"


def run(solver, state, progress: Optional[Progress] = None, on_frame=None) -> Settling:
    """Step ``state`` frame by frame until it settles or reaches the frame limit.

    A frame is still when its trimmed RMS speed is under ``settle_speed`` and
    the fabric has grown to its pattern size; the drape has settled after
    ``settle_frames`` still frames in a row, once ``min_frames`` have passed.

    Parameters
    ----------
    solver : :class:`core.drape.xpbd.DrapeSolver`.
    state : its :class:`core.drape.xpbd.DrapeState`, advanced in place.
    progress : optional ``progress(fraction, message)``; may raise Cancelled.
    on_frame : optional ``on_frame(frame, positions (P, 3), still)`` after every frame (``still``:
        the frames in a row so far that count as still; the layered drape measures each one).

    Raises
    ------
    DrapeError when the drape diverges (see :func:`check_divergence`).
    """
    opts = solver.options
    speeds = []
    still = 0
    settled = False
    frame = 0
    for frame in range(1, opts.max_frames + 1):
        solver.step(state)
        xs = state.x.numpy()
        vs = state.v.numpy()[state.free]
        check_divergence(frame, xs, vs, opts, solver.material, solver.dt, solver.cloth)
        rms = settle_speed(vs, opts.settle_trim)
        speeds.append(rms)
        still = still + 1 if (rms < opts.settle_speed and frame > opts.grow_frames) else 0
        report(progress, frame / opts.max_frames, f"drape: frame {frame}, rms speed {rms * 1000:.1f} mm/s")
        if on_frame is not None:
            on_frame(frame, xs, still)
        if frame >= max(opts.min_frames, opts.grow_frames) and still >= opts.settle_frames:
            settled = True
            break
    return Settling(frames=frame, settled=settled, speeds=np.asarray(speeds))
