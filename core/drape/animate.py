"""A drape carried through a body's motion: the garment on an animated character.

:func:`pose_frames` makes the body's frames: the default body (Anny) through a
list of poses (``["A", "P1", "P3"]``, presets or JSON poses) with in-betweens,
each joint's rotation interpolated (slerp) from one pose to the next, skinned
by the model (so limbs keep their length, as linear blends of vertices would not).

:func:`drape_motion` drapes the pattern on the first frame until it settles
(the static drape, :func:`core.drape.simulate.drape`'s schedule), then carries
it through the following frames, one simulation frame each (several where a body
vertex moves more than :data:`MAX_MOVE` from one frame to the next): the body moves a
little before every substep (linearly from one frame to the next, its BVH
refitted) and the contacts are searched every substep, so the cloth is pushed
by the body as it moves instead of finding itself inside it at the frame's
start. Pinned vertices (a waistband held while draping) ride on their nearest
body vertex. Each frame reports the share of garment vertices more than 2 mm inside
the body (SPEC item 7) and its wall time.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Mapping, Optional, Sequence, Union

import numpy as np

from ..errors import DrapeError
from ..progress import Progress, report
from .materials import Material, get_material
from .options import DrapeOptions
from .pleats import draped_cloth
from .schedule import check_divergence, run
from .strain import face_strains
from .xpbd import DrapeSolver, check_body

MAX_MOVE = 0.03  # m: a body vertex moves at most this far in one simulation frame (20 substeps)
PENETRATION_DEPTH = 0.002  # m: SPEC item 7 (core.metrics.drape.penetration, a later stage) counts deeper


@dataclass
class MotionResult:
    """A garment through a body's motion.

    Attributes
    ----------
    positions : (K, N, 3) float, every global garment vertex per body frame (frame 0: the
        settled drape on the first), metres; ids no panel uses stay at 0 (see ``used``).
    faces : (T, 3) int, the garment's triangles (global vertex ids).
    used : (N,) bool.
    penetration : (K,) float, share of the used vertices more than 2 mm inside the body.
    stretch : (K,) float, residual stretch: the 95th percentile over the triangles of the larger
        of their weft and warp strain (0.02 = 2 % longer than the pattern).
    frame_seconds : (K - 1,) float, wall time of each moving frame.
    settle_frames : int, frames the first drape took; settled : bool.
    material : dict; device : str; solver : str, the drape solver (``DrapeOptions.solver``).
    """

    positions: np.ndarray
    faces: np.ndarray
    used: np.ndarray
    penetration: np.ndarray
    stretch: np.ndarray
    frame_seconds: np.ndarray
    settle_frames: int
    settled: bool
    material: dict
    device: str
    solver: str = ""


def pose_frames(model, shape=None, poses: Sequence = ("A", "P1", "P3"), between: int = 10) -> list:
    """The body's vertices through ``poses`` with ``between`` in-betweens from each to the next.

    Returns a list of ``(len(poses) - 1) * (between + 1) + 1`` arrays (V, 3), metres; the
    frames at the poses are the model's own instances of them.
    """
    from scipy.spatial.transform import Rotation

    from ..body.anny import ANNY_TO_EASE
    from ..body.instance import instance_pose, instance_shape

    if not hasattr(model, "pose_rotations") or not hasattr(model, "joint_names"):
        raise DrapeError(
            f"pose in-betweens need a body model with joint rotations (Anny); "
            f"{getattr(model, 'name', type(model).__name__)} has none"
        )
    if len(poses) < 2 or int(between) < 0:
        raise DrapeError("a motion needs two poses or more and between >= 0 in-betweens")
    inst = instance_shape(model, shape)
    names = list(model.joint_names)
    E = np.asarray(ANNY_TO_EASE, dtype=float)
    # per pose: the joints' delta rotations in our frame (what a JSON pose's axis-angles mean)
    rots = [Rotation.from_matrix(E @ model.pose_rotations(instance_pose(p), inst) @ E.T) for p in poses]
    frames = [np.asarray(model.vertices(inst, instance_pose(poses[0])), dtype=np.float64)]
    for k in range(1, len(poses)):
        a, b = rots[k - 1], rots[k]
        rel = (a.inv() * b).as_rotvec()
        for i in range(1, int(between) + 2):
            t = i / (int(between) + 1)
            if i == int(between) + 1:
                frames.append(np.asarray(model.vertices(inst, instance_pose(poses[k])), dtype=np.float64))
                continue
            r = (a * Rotation.from_rotvec(t * rel)).as_rotvec()
            pose = {names[j]: r[j] for j in range(len(names)) if np.linalg.norm(r[j]) > 1e-9}
            frames.append(np.asarray(model.vertices(inst, pose), dtype=np.float64))
    return frames


def pose_from_bone_rotations(names: Sequence[str], parents, world) -> dict:
    """A JSON pose (joint -> axis-angle, radians; :mod:`core.body.poses`) from each joint's world
    rotation away from the reference pose.

    ``world`` (J, 3, 3): joint j's rotation from its orientation at the reference pose to its
    posed orientation, in the body's frame (a rig's posed bone orientation times the inverse
    of its rest orientation). The pose's rotations are 'local-ref' (a joint's world rotation is
    its parent's times its own), so each is the parent's inverse times the joint's.
    """
    from scipy.spatial.transform import Rotation

    G = np.asarray(world, dtype=float)
    parents = np.asarray(parents)
    if G.shape != (len(names), 3, 3) or parents.shape != (len(names),):
        raise DrapeError(f"bone rotations: expected ({len(names)}, 3, 3) and {len(names)} parents, got {G.shape}")
    local = np.array([G[j] if parents[j] < 0 else G[parents[j]].T @ G[j] for j in range(len(names))])
    aa = Rotation.from_matrix(local).as_rotvec()
    return {n: aa[j] for j, n in enumerate(names) if np.linalg.norm(aa[j]) > 1e-9}


def posed_frames(model, shape, poses: Sequence, root_moves=None) -> list:
    """The body's vertices (V, 3), metres, at each of ``poses`` (presets or JSON poses).

    ``root_moves`` (K, 3), optional: how far each frame's root joint moved from where it stands
    at the reference pose (a rig's root bone moved: the body carried as a whole).
    """
    from ..body.instance import instance_pose, instance_shape

    if not hasattr(model, "vertices_and_joints"):
        raise DrapeError(
            f"posing frames needs a body model with joints (Anny); "
            f"{getattr(model, 'name', type(model).__name__)} has none"
        )
    inst = instance_shape(model, shape)
    rest_root = np.asarray(model.joints(inst, None), dtype=np.float64)[0]
    frames = []
    for k, pose in enumerate(poses):
        v, j = model.vertices_and_joints(inst, instance_pose(pose))
        v = np.asarray(v, dtype=np.float64)
        if root_moves is not None:
            v = v + (np.asarray(root_moves[k], dtype=np.float64) - (np.asarray(j[0]) - rest_root))
        frames.append(v)
    return frames


def drape_motion(
    pattern,
    body_frames: Sequence[np.ndarray],
    body_faces,
    material: Union[None, str, Material, Mapping] = None,
    options: Union[None, DrapeOptions, Mapping] = None,
    progress: Optional[Progress] = None,
) -> MotionResult:
    """Drape ``pattern`` on ``body_frames[0]``, then carry it through the other frames.

    Parameters
    ----------
    pattern : :class:`core.pattern.types.Pattern`, its skintight embedding on the first frame.
    body_frames : K >= 1 arrays (V, 3), metres, one body's vertices per frame (same triangles).
    body_faces : (F, 3) int, outward-oriented.
    material, options : as for :func:`core.drape.simulate.drape` (the options' ``max_frames``
        bounds the first drape only; the default solver, pd, carries the cloth a moving body holds:
        :meth:`core.drape.xpbd.DrapeSolver._carry`).
    progress : optional ``progress(fraction, message)``; may raise Cancelled.

    Raises
    ------
    DrapeError on invalid input or divergence (naming the frame).
    """
    from ..geom.queries import distance_to_mesh

    opts = DrapeOptions.coerce(options)
    if material is None:
        material = (getattr(pattern, "materials", None) or {}).get("fabric")
    mat = get_material(material)
    if len(body_frames) == 0:
        raise DrapeError("a motion needs at least one body frame")
    first, faces = check_body(body_frames[0], body_faces)
    for k, v in enumerate(body_frames[1:], 1):
        if np.shape(v) != first.shape:
            raise DrapeError(
                f"body frame {k} has shape {np.shape(v)}: every frame must have the first "
                f"frame's vertex count ({first.shape[0]}, 3)"
            )
    frames = [first] + [check_body(v, faces)[0] for v in body_frames[1:]]
    # the static drape's cloth (pleats opened, stitched and creased) on the pattern's own mesh
    cloth = draped_cloth(pattern)
    solver = DrapeSolver(cloth, first, faces, mat, opts)
    state = solver.state()
    K = len(frames)

    def settle_progress(fraction, message):
        report(progress, 0.3 * fraction, message)

    settling = run(solver, state, settle_progress if progress is not None else None)
    used = cloth.particle_of >= 0
    src = np.where(used, cloth.particle_of, 0)

    valid = ~cloth.sliver if len(cloth.sliver) else np.ones(len(cloth.faces), bool)

    def snapshot(body):
        x = state.x.numpy().astype(np.float64)
        pos = np.where(used[:, None], x[src], 0.0)
        sd = distance_to_mesh(pos[used], body, faces, signed=True, max_dist=0.5)
        weft, warp, _ = face_strains(x, cloth)
        stretch.append(float(np.percentile(np.maximum(weft, warp)[valid], 95)) if valid.any() else 0.0)
        return pos, float(np.mean(sd < -PENETRATION_DEPTH)) if len(sd) else 0.0

    stretch = []
    pos, share = snapshot(first)
    positions, pens, seconds = [pos], [share], []
    n = opts.substeps
    # pinned particles (a waistband held while draping) ride on their nearest body vertex
    pinned = np.flatnonzero(~state.free)
    if len(pinned):
        from scipy.spatial import cKDTree

        x0 = state.x.numpy().astype(np.float64)
        nearest = cKDTree(first).query(x0[pinned])[1]
        offset = x0[pinned] - first[nearest]

    def move(body):
        solver.move_body(body)
        if len(pinned):
            x = state.x.numpy()
            x[pinned] = (body[nearest] + offset).astype(np.float32)
            state.x.assign(x)

    for k in range(1, K):
        a, b = frames[k - 1], frames[k]
        t0 = time.perf_counter()
        # a body frame that moves far is simulated as several frames (cloth tunnels through a limb
        # that jumps more than a few mm a substep)
        parts = max(1, int(np.ceil(np.abs(b - a).max() / MAX_MOVE)))
        for j in range(parts):
            lo, hi = a + (b - a) * (j / parts), a + (b - a) * ((j + 1) / parts)
            solver.step(state, before_substep=lambda i, lo=lo, hi=hi: move(lo + (hi - lo) * ((i + 1) / n)))
        xs = state.x.numpy()
        check_divergence(settling.frames + k, xs, state.v.numpy()[state.free], opts, mat, solver.dt, cloth)
        seconds.append(time.perf_counter() - t0)
        pos, share = snapshot(b)
        positions.append(pos)
        pens.append(share)
        report(progress, 0.3 + 0.7 * k / max(K - 1, 1), f"motion: frame {k}/{K - 1}, penetration {100 * share:.2f} %")
    return MotionResult(
        positions=np.stack(positions),
        faces=cloth.faces_global.copy(),
        used=used,
        penetration=np.asarray(pens),
        stretch=np.asarray(stretch),
        frame_seconds=np.asarray(seconds),
        settle_frames=int(settling.frames),
        settled=bool(settling.settled),
        material=mat.to_json(),
        device=str(solver.device),
        solver=str(opts.solver),
    )


def parse_poses(text: str, label: str = "poses") -> list:
    """The pose presets of ``text`` (comma, space or ``->`` separated: ``"A, P1, P3"``); DrapeError
    naming ``label`` (a CLI flag, a panel field) and the first unknown name."""
    from ..choices import POSE_PRESETS

    names = [t for t in str(text).replace("->", ",").replace(" ", ",").split(",") if t]
    for n in names:
        if n not in POSE_PRESETS:
            raise DrapeError(f"{label}: {n!r} is not a pose ({', '.join(POSE_PRESETS)})")
    if len(names) < 2:
        raise DrapeError(f"{label}: name two poses or more (e.g. A, P1, P3), got {text!r}")
    return names


def load_poses(path, label: str = "--animation") -> list:
    """The poses of the JSON file ``path``: a list of two or more, each a preset name or a JSON pose
    ``{joint: [rx, ry, rz]}`` (radians, :mod:`core.body.poses`; ``"preset"`` names the preset it
    starts from), e.g. ``["A", {"preset": "P1", "lowerarm01.L": [0, 0, 0.5]}, "P3"]``.
    DrapeError naming ``label``, the file and the entry at fault (joints: :func:`check_poses`)."""
    import json
    from pathlib import Path

    from ..choices import POSE_PRESETS

    try:
        poses = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise DrapeError(f"{label}: cannot read {path}: {exc.strerror or exc}") from None
    except ValueError as exc:
        raise DrapeError(f"{label}: {path} is not JSON: {exc}") from None
    if not isinstance(poses, list) or len(poses) < 2:
        raise DrapeError(f"{label}: {path} must hold a list of two poses or more (preset names or joint rotations)")
    for i, pose in enumerate(poses):
        preset = pose if isinstance(pose, str) else pose.get("preset") if isinstance(pose, dict) else None
        if not isinstance(pose, (str, dict)):
            raise DrapeError(
                f"{label}: {path}[{i}]: expected a preset name or {{joint: [rx, ry, rz]}}, got {type(pose).__name__}"
            )
        if preset is not None and preset not in POSE_PRESETS:
            raise DrapeError(f"{label}: {path}[{i}]: {preset!r} is not a pose ({', '.join(POSE_PRESETS)})")
    return poses


def check_poses(model, poses, where: str) -> None:
    """Each JSON pose's joints and angles checked against ``model``; DrapeError naming ``where[i]``."""
    from ..body.model import check_axis_angle
    from ..errors import BodyError

    names = list(getattr(model, "joint_names", []))
    for i, pose in enumerate(poses):
        if isinstance(pose, dict):
            for joint, aa in pose.items():
                if joint == "preset":
                    continue
                try:
                    check_axis_angle(aa, joint, names, getattr(model, "name", ""))
                except BodyError as exc:
                    raise DrapeError(f"{where}[{i}]: {exc}") from None


def pose_label(pose, i: int) -> str:
    """A pose's name in a sequence: the preset's, else ``pose <i>`` (a JSON pose)."""
    return pose if isinstance(pose, str) else f"pose {i}"


def distinct_poses(poses, own) -> list:
    """The different poses of ``poses`` other than ``own`` (the pattern's), in order: what to adapt to."""
    import json

    seen, out = {json.dumps(own, sort_keys=True)}, []
    for p in poses:
        key = json.dumps(p, sort_keys=True)
        if key not in seen:
            seen.add(key)
            out.append(p)
    return out


def pc2_bytes(frames: np.ndarray) -> bytes:
    """A Point Cache 2 file (``.pc2``: Blender's Mesh Cache modifier, 3ds Max, Maya and others read it)
    of ``frames`` (K, V, 3): the header (start frame 1, one sample a frame), then K x V x 3
    little-endian float32, frame 1 first."""
    import struct

    f = np.ascontiguousarray(frames, dtype="<f4")
    return struct.pack("<12siiffi", b"POINTCACHE2\0", 1, f.shape[1], 1.0, 1.0, f.shape[0]) + f.tobytes()


def _obj_bytes(vertices: np.ndarray, faces: np.ndarray, name: str, up: str = "y") -> bytes:
    """The OBJ of frame 1 (``vertices`` already in the file frame ``up``)."""
    from ..geom.frame import frame_text

    lines = [
        f"# EASE motion: the mesh {name}.pc2 moves (its vertex order)",
        f"# frame: {frame_text(up, 'root', 'frame 1 of the motion; the .pc2 in the same frame')}",
        f"o {name}",
    ]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in np.asarray(vertices, dtype=float)]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in np.asarray(faces, dtype=np.int64)]
    return ("\n".join(lines) + "\n").encode("utf-8")


def pattern_label(pattern) -> str:
    """What pattern a motion drapes: ``"pattern adapted to P1, P3"``, ``"reference pattern"`` ..."""
    poses = (pattern.report or {}).get("poses") if pattern.mode == "adapt" else None
    return f"pattern adapted to {', '.join(map(str, poses))}" if poses else f"{pattern.mode} pattern"


def motion_report(result: MotionResult, poses, between: int, pattern=None) -> dict:
    """The figures of a motion, per frame: penetration and residual stretch (%) and seconds.
    With the draped ``pattern``: which it is (:func:`pattern_label`) and, for an adapted one,
    its adaptation's residual stretch per pose before and after (% of the area stretched beyond
    the tolerance, :func:`core.workflows.adapt`)."""
    out = {
        "poses": list(poses),
        "in_betweens": int(between),
        "frames": int(len(result.positions)),
        "penetration_pct": [round(100 * float(p), 4) for p in result.penetration],
        "stretch_p95_pct": [round(100 * float(p), 3) for p in result.stretch],
        "frame_seconds": [round(float(t), 4) for t in result.frame_seconds],
        "worst_penetration_pct": round(100 * float(result.penetration.max()), 4),
        "settle_frames": result.settle_frames,
        "settled": result.settled,
        "material": result.material.get("name"),
        "device": result.device,
        "solver": result.solver,
    }
    if pattern is not None:
        out["pattern"] = pattern_label(pattern)
        if pattern.mode == "adapt" and (pattern.report or {}).get("residual_stretch") is not None:
            out["adaptation_residual_stretch_pct"] = pattern.report["residual_stretch"]
    return out


def write_motion(
    out, result: MotionResult, body_frames, body_faces, poses, between: int, pattern=None, up: str = "y"
) -> list:
    """The motion's files into the folder ``out`` at once: ``motion.npz`` (garment positions by
    global vertex id, faces, used; body frames and faces), ``motion_report.json``
    (:func:`motion_report`), and for other tools ``garment_motion.obj`` / ``.pc2`` and
    ``body_motion.obj`` / ``.pc2`` (each OBJ is frame 1, its point cache the K frames).
    With ``pattern`` (the one draped) the report names it, and an adapted one is written
    too (``pattern.json``: what the garment was cut from). ``up``: the frame of the OBJs and
    point caches, ``"y"`` (default, OBJ readers' convention: ``(x, z, -y)``) or ``"z"`` (the core
    frame, that of ``motion.npz``)."""
    import io

    from ..fileio import write_files
    from ..geom.frame import to_frame
    from ..geom.mesh import compact_vertices
    from ..jsontext import dumps_json

    used = np.asarray(result.used, dtype=bool)
    ids, gfaces = compact_vertices(result.faces, used)
    garment = np.asarray(result.positions)[:, ids]
    body = np.stack([np.asarray(b, dtype=np.float64) for b in body_frames])
    buf = io.BytesIO()
    np.savez_compressed(
        buf,
        positions=np.asarray(result.positions, dtype=np.float32),
        faces=result.faces,
        used=used,
        body_vertices=body.astype(np.float32),
        body_faces=np.asarray(body_faces),
    )
    files = {
        "motion.npz": buf.getvalue(),
        "motion_report.json": (dumps_json(motion_report(result, poses, between, pattern)) + "\n").encode("utf-8"),
        "garment_motion.obj": _obj_bytes(to_frame(garment[0], up), gfaces, "garment_motion", up),
        "garment_motion.pc2": pc2_bytes(to_frame(garment, up)),
        "body_motion.obj": _obj_bytes(to_frame(body[0], up), body_faces, "body_motion", up),
        "body_motion.pc2": pc2_bytes(to_frame(body, up)),
    }
    if pattern is not None and pattern.mode == "adapt":
        from ..pattern.io import pattern_text

        files["pattern.json"] = pattern_text(pattern).encode("utf-8")
    return write_files(out, files)
