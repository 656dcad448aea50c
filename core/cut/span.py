"""The skirt's reference surface spans the body's concavities between the legs.

A skirt does not dip into the gluteal cleft, into the creases at the front of
the crotch, or into the kinks where the skirt topology's curtains meet the
legs (:mod:`.skirt`): cloth under its own tension spans a concavity. Cut on
the body surface itself, the skirt's pieces would have to follow those creases,
and a flat pattern can only do that by shearing (issue 14: the skirt's shear
p95 sat at the crotch and the cleft). Here the surface the skirt is cut from,
flattened from and measured on is a *membrane* stretched over the body in that
region: the solution of an obstacle problem.

- The membrane minimises the Dirichlet energy ``sum_ij w_ij |x_i - x_j|^2`` of
  the skirt mesh (cotangent weights of the reference surface, clamped at 0, so
  a flat or convex patch keeps its own layout) over the *free* vertices, with
  every other vertex held at the body.
- A vertex is free only where the membrane lies on the outside of the body
  (its displacement along the vertex normal is >= 0), and a held vertex is
  released where the membrane pulls it outwards: the free set is found by an
  active-set iteration. On a convex part of the body the membrane would sink
  into it, so nothing moves there; across a crease it lifts off and bridges it.
- Only vertices between the two legs' centre lines, from :data:`SPAN_BOTTOM`
  of the way from the crotch down to the bridge's bottom (6.8 cm below the
  crotch on M: the gluteal folds) up to :data:`SPAN_TOP` of the way from the
  crotch to the back waist (above the cleft), are candidates: the concavities
  across the cleft and the crotch, not a general smoothing of the body. Lower
  down, the curtains' joins with the legs are left as the bridge makes them:
  spanned there too (``SPAN_BOTTOM`` 1), the figures barely change (skirt M
  shear p95 6.1 against 6.3 deg, P1 6.8 against 5.6) while a scissored pose
  (P2) puts 102 spanned vertices up to 34 mm inside the legs (19, up to 2.5 mm,
  as it is; igl signed distance to the P2 body), since a vertex of one leg's join is then a combination of both
  legs' vertices.

The membrane's free vertices are fixed linear combinations of held body
vertices (the harmonic extension: ``x_F = -Q_FF^-1 Q_FC x_C``), so the
spanned surface is a linear operator ``B`` on the body's vertices, built on
the reference body and evaluated on every shape and pose like the rest of the
cut's embedding (the cut's embedding becomes ``W @ B``). On a body with a
left/right symmetry map ``B`` is made its own mirror image, so a mirrored
skirt stays exactly mirrored.

The cost is in the stored cut: a spanned vertex is a combination of about 25
held vertices (the rim of its free region; :data:`SPAN_DROP` drops 4 % of
the weights for a 36 um change of the surface on M), so a garment vertex on a
spanned triangle carries up to about 75 body weights instead of 3. The
skirt's ``cut_embedding.npz`` grows from 41 to 168 kB (1145 of its 6934 rows;
the weights are float64 and incompressible). Dropping more moves the surface
by millimetres (a relative 1e-2: 126 kB and 2.6 mm on M; 1e-1: 84 kB and
18 mm); storing ``B``'s 95 free rows (11 kB) once beside the skin embedding
would keep it near 52 kB, a change of the cut's file format.
"""

from __future__ import annotations

from typing import Optional

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..geom.mesh import vertex_normals
from .split import CutMesh

SPAN_BOTTOM = 0.1  # candidates down to this fraction of the crotch -> bridge bottom (6.8 cm on M)
SPAN_TOP = 0.5  # candidates up to this fraction of the crotch -> waist (back) height
SPAN_TOL = 1e-5  # m: a membrane vertex lifted off the body by less than this is held (touching)
SPAN_DROP = 1e-4  # harmonic weights below this (relative to the row's largest) are dropped
COT_MAX = 1e3  # largest cotangent weight (an angle of 0.06 deg; Anny's smallest: 0.8 deg)
_MAX_ROUNDS = 40  # a guard: a vertex is freed again at most once, so the rounds end (5-12 on 40 sampled bodies)


def _cotan_laplacian(X: np.ndarray, F: np.ndarray, n: int) -> sp.csr_matrix:
    """(n, n) graph Laplacian ``D - W`` with clamped cotangent edge weights on ``X``.

    Clamping (an obtuse angle contributes 0, never a negative weight) keeps the
    membrane's weights positive, so the harmonic extension is a convex combination.
    Clamped at :data:`COT_MAX` too: a degenerate triangle (an OBJ template with two
    vertices at one place) gave a weight of ~1e297, and the solve lost every other weight
    to rounding (a pit spanned 7.6 cm deep of its 10 instead of flat)."""
    rows, cols, vals = [], [], []
    for k in range(3):
        i, j, o = F[:, (k + 1) % 3], F[:, (k + 2) % 3], F[:, k]  # edge i-j opposite corner o
        a, b = X[i] - X[o], X[j] - X[o]
        cross = np.linalg.norm(np.cross(a, b), axis=1)
        cot = (a * b).sum(1) / np.maximum(cross, 1e-300)
        w = 0.5 * np.clip(cot, 0.0, COT_MAX)
        rows += [i, j]
        cols += [j, i]
        vals += [w, w]
    W = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    return (sp.diags(np.asarray(W.sum(1)).ravel()) - W).tocsr()


def _embedding_rows(mesh: CutMesh, V: int) -> sp.csr_matrix:
    """(nv, V) body weights of every mesh vertex (identity rows for body vertices)."""
    rows, cols, vals = [np.arange(V)], [np.arange(V)], [np.ones(V)]
    for v in range(V, mesh.nv):
        c, w = mesh.vertex_weights(v)
        rows.append(np.full(len(c), v))
        cols.append(np.asarray(c, dtype=np.int64))
        vals.append(np.asarray(w, dtype=float))
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(mesh.nv, V))


def spanning_operator(
    mesh: CutMesh, X: np.ndarray, candidates: np.ndarray, symmetry: Optional[np.ndarray] = None
) -> Optional[sp.csr_matrix]:
    """The membrane over the body's concavities among ``candidates`` as a (V, V) operator.

    Parameters
    ----------
    mesh : CutMesh, the skirt topology's surface (body vertices and bridge vertices).
    X : (V, 3) reference body vertices.
    candidates : (V,) bool, body vertices that may leave the body.
    symmetry : optional (V,) left/right vertex map; the operator is then its own mirror.

    Returns
    -------
    (V, V) csr operator ``B`` (identity rows for held vertices) with ``B @ X`` the spanned
    surface, or None when no vertex lifts off.
    """
    V = len(X)
    F = mesh.F
    P = _embedding_rows(mesh, V)
    Q = (P.T @ _cotan_laplacian(mesh.X, F, mesh.nv) @ P).tocsr()
    on = np.zeros(V, dtype=bool)
    on[np.unique(F[F < V])] = True
    cand = np.asarray(candidates, bool) & on & (np.asarray(Q.diagonal()) > 0)
    if symmetry is not None:
        cand &= cand[symmetry]
    N = P.T @ vertex_normals(mesh.X, F)
    N /= np.maximum(np.linalg.norm(N, axis=1), 1e-300)[:, None]

    def pair(a):  # a per-vertex figure made equal on mirror pairs (mirror-invariant decisions)
        return a if symmetry is None else 0.5 * (a + a[symmetry])

    def solve(free):
        idx = np.nonzero(free)[0]
        held = ~free
        Y = X.copy()
        if len(idx):
            rhs = -(Q[idx][:, held] @ X[held])
            Y[idx] = spla.splu(Q[idx][:, idx].tocsc()).solve(rhs)
        return Y

    free = cand.copy()
    released = np.zeros(V, dtype=bool)  # vertices the active set freed again after holding them
    settled = np.zeros(V, dtype=bool)  # ... and then held once more: held for good
    for _ in range(_MAX_ROUNDS):
        Y = solve(free)
        h = pair(((Y - X) * N).sum(1))
        # the membrane sank into the body there, or only touches it: hold those vertices (held,
        # a touching vertex keeps its place instead of sliding along the body)
        inside = free & (h < SPAN_TOL)
        if inside.any():
            # a vertex freed by its pull and then held again is not freed a second time: its pull
            # (a force, compared with SPAN_TOL) and its lift once free can disagree in sign or
            # size. Without this, held and freed in turn until the round limit: on
            # sample_anny(40, seed=0) bodies 5 (a mirror pair pulled by 1.2e-5, lifted 3.3 um),
            # 8 (pulled 2.0e-5, then 53 um inside), 14, 23 and 28.
            settled |= inside & released
            free &= ~inside
            continue
        pull = pair(-((Q @ Y) * N).sum(1))  # the membrane's force on a held vertex, outwards > 0
        release = cand & ~free & ~settled & (pull > SPAN_TOL)
        if not release.any():
            break
        free |= release
        released |= release
    else:
        # no fixed point within the rounds: hold whatever does not lift off, until nothing sinks
        # (only holds, so this ends), never a membrane inside the body
        while True:
            inside = free & (pair(((solve(free) - X) * N).sum(1)) < SPAN_TOL)
            if not inside.any():
                break
            free &= ~inside
    idx = np.nonzero(free)[0]
    if len(idx) == 0:
        return None
    held = np.nonzero(~free)[0]
    Qfc = Q[idx][:, held].tocsc()
    cols = np.nonzero(np.diff(Qfc.indptr))[0]  # held vertices the free ones touch
    Wf = -spla.splu(Q[idx][:, idx].tocsc()).solve(Qfc[:, cols].toarray())
    Wf[Wf < SPAN_DROP * Wf.max(1, keepdims=True)] = 0.0
    Wf /= Wf.sum(1, keepdims=True)  # an affine (convex) combination
    r, c = np.nonzero(Wf)
    B = sp.csr_matrix(
        (
            np.concatenate([np.ones(V - len(idx)), Wf[r, c]]),
            (np.concatenate([held, idx[r]]), np.concatenate([held, held[cols][c]])),
        ),
        shape=(V, V),
    )
    if symmetry is not None:
        S = np.asarray(symmetry, dtype=np.int64)
        B = (0.5 * (B + B[S][:, S])).tocsr()  # exactly its own mirror image
    B.sort_indices()
    return B
