"""A mirrored garment's mesh made the exact mirror image of its left half.

The cut traces, splits and refines the left and right sides of a mirrored
design separately; the two triangulations then differ (the order of edge
splits, flips and geodesic crossings is not mirror-invariant), so their
flattenings differ by millimetres although the body and the ease are
symmetric. Here the garment's right half is thrown away and rebuilt as the
reflection of its left half through the body's symmetry map: a vertex with
embedding row ``w`` (weights on body vertices) mirrors to the row ``w``
with its columns permuted by ``body.symmetry``, a face ``(a, b, c)`` to
``(m(c), m(b), m(a))`` (a reflection reverses orientation), a ``*_left``
panel's label to its ``*_right`` panel's, a ``*_right`` line's runs are the
mirrored runs of its ``*_left`` line, and a line that is its own mirror (a
neckline, a hem ring) has its right stretches replaced by the reflection of
its left ones. On any body instance the right half is then what the body's
own asymmetry gives, never a meshing artefact.

The left half is the faces whose body triangle is on the body's left (the
template has no triangle across its midline). Vertices shared by both halves
lie on the midline; their rows get the mirror-symmetric average (a round-off
change). A centre seam between a ``*_left`` panel and its own mirror (the
pants' centre front and back: plane sections sampled every 3 cm and joined by
geodesics, up to 0.6 mm beside the midline) is moved onto the midline: the
``*_right`` panel's slivers on the body's left join the ``*_left`` panel, and
the seam's runs become the midline edges between the pair.

Whenever the garment is not mirror-symmetric by name and topology (a panel
or line without its mirror, a skirt bridge built without a symmetry map
(:mod:`.skirt` splits it on the midline otherwise), a line whose reflection is
not another line, a panel or line changed by more than :data:`SHAPE_TOLERANCE`),
:func:`symmetrize` returns None and the cut keeps its mesh.
"""

from __future__ import annotations

from typing import Dict, List, Optional, Sequence

import numpy as np
import scipy.sparse as sp

from ..design.naming import side_of, swap_side
from ..geom.mesh import triangle_areas
from ..geom.polyline import polyline_length

#: largest distance (m) between a shared (midline) vertex and its mirror image that is
#: averaged away; a larger one means the halves were not split at the midline
MIDLINE_TOLERANCE = 2e-3


def body_face_sides(body, X: np.ndarray) -> Optional[np.ndarray]:
    """(F,) int8 per body template triangle: 1 on the body's left (+X), 0 on its right; None
    when the body has no usable symmetry map or a triangle lies across the midline."""
    S = getattr(body, "symmetry", None)
    F = np.asarray(body.faces, dtype=np.int64)
    if S is None:
        return None
    S = np.asarray(S, dtype=np.int64)
    if S.shape != (len(X),) or np.any(S[S] != np.arange(len(S))):
        return None
    x = np.where(S == np.arange(len(S)), 0.0, X[:, 0])[F]
    left, right = (x > 0).any(1), (x < 0).any(1)
    if np.any(left & right) or np.any(~left & ~right):
        return None
    return left.astype(np.int8)


def mirror_plan(panel_names: Sequence[str], line_names: Sequence[str]) -> Optional[dict]:
    """Mirror index of every panel and line of a garment, or None when one has no mirror.

    Parameters
    ----------
    panel_names : the garment's panels (label ``i`` = ``panel_names[i]``).
    line_names : the garment's cut lines (in the order of the lines given to :func:`symmetrize`).
    """

    def index(names):
        at = {n: i for i, n in enumerate(names)}
        out = [at.get(swap_side(n), -1) for n in names]
        return None if min(out, default=0) < 0 else np.asarray(out, dtype=np.int64)

    pm, lm = index(panel_names), index(line_names)
    if pm is None or lm is None or (np.all(pm == np.arange(len(pm))) and np.all(lm == np.arange(len(lm)))):
        return None  # not mirrored: no panel or line has a mirror of another name
    return {"panel": pm, "line": lm, "panel_side": _sides(panel_names), "line_side": _sides(line_names)}


def _sides(names: Sequence[str]) -> np.ndarray:
    """(k,) int per name: 1 for a ``*_left`` name, 0 for ``*_right``, -1 for a midline name."""
    codes = {"left": 1, "right": 0, None: -1}
    return np.asarray([codes[side_of(n)] for n in names], dtype=np.int64)


def symmetrize(
    X: np.ndarray,
    F: np.ndarray,
    lab: np.ndarray,
    face_side: np.ndarray,
    W: sp.csr_matrix,
    lines: List[List[np.ndarray]],
    plan: dict,
    symmetry: np.ndarray,
    body_X: np.ndarray,
):
    """The garment mesh rebuilt as its left half and that half's mirror image.

    Parameters
    ----------
    X : (n, 3) float, garment mesh vertices on the reference body (m).
    F : (f, 3) int faces; lab : (f,) int panel labels.
    face_side : (f,) int, 1 where the face's body triangle is on the body's left, else 0.
    W : (n, V) sparse embedding rows (weights on body vertices).
    lines : per cut line, its vertex runs in the mesh.
    plan : :func:`mirror_plan` of the garment.
    symmetry : (V,) int, the body's mirror vertex of every vertex; body_X : (V, 3) reference body.

    Returns
    -------
    (X, F, lab, W, lines) of the same meaning, or None when the garment is not mirror-symmetric.
    """
    F = np.asarray(F, dtype=np.int64)
    lab = np.asarray(lab, dtype=np.int64)
    n = len(X)
    left = np.asarray(face_side) == 1
    if not left.any():
        return None
    pm = plan["panel"]
    # a centre seam between a *_left panel and its own mirror (the pants' centre front and
    # back) is traced a fraction of a millimetre beside the midline: the slivers of the
    # *_right panel on the body's left join the *_left panel, and the seam is rebuilt on the
    # midline (_centre_runs); _same_shape bounds what this moves
    centre = _centre_lines(F, lab, lines, plan, n)
    lab = np.where(left & (plan["panel_side"][lab] == 0), pm[lab], lab)
    inL = np.zeros(n, dtype=bool)
    inL[F[left].reshape(-1)] = True
    inR = np.zeros(n, dtype=bool)
    inR[F[~left].reshape(-1)] = True
    mid = inL & inR
    keep = np.nonzero(inL)[0]
    twin = np.nonzero(inL & ~mid)[0]
    new = np.full(n, -1, dtype=np.int64)
    new[keep] = np.arange(len(keep))
    mir = new.copy()  # old left id -> new id of its mirror image
    mir[twin] = len(keep) + np.arange(len(twin))
    S = np.asarray(symmetry, dtype=np.int64)
    V = W.shape[1]
    P = sp.csr_matrix((np.ones(V), (np.arange(V), S)), shape=(V, V))  # column j -> S[j]
    Wl = sp.csr_matrix(W)[keep]
    Wm = Wl @ P
    is_mid = mid[keep]
    if is_mid.any():
        pos, mpos = Wl[is_mid] @ body_X, Wm[is_mid] @ body_X
        if np.linalg.norm(pos - mpos, axis=1).max() > MIDLINE_TOLERANCE:
            return None
        D = sp.diags(is_mid.astype(float))
        Wl = Wl + 0.5 * (D @ (Wm - Wl))  # shared rows: their symmetric average
        Wl.eliminate_zeros()
    Wnew = sp.vstack([Wl, (Wl @ P)[~is_mid]]).tocsr()
    Wnew.sort_indices()
    Xnew = np.concatenate([np.asarray(X, float)[keep], Wnew[len(keep) :] @ body_X])
    if is_mid.any():
        Xnew[np.nonzero(is_mid)[0]] = Wl[is_mid] @ body_X
    FL = F[left]
    Fnew = np.concatenate([new[FL], mir[FL][:, ::-1]])
    labnew = np.concatenate([lab[left], pm[lab[left]]])
    out_lines = _mirror_lines(
        lines, plan, inL, mid, new, mir, centre, _midline_edges(F, left, lab, pm, new), np.asarray(X, float), Xnew
    )
    if out_lines is None or not _lines_mirror(out_lines, plan, new, mir, n_new=len(Xnew)):
        return None
    if not _same_shape(X, F, lab, lines, Xnew, Fnew, labnew, out_lines):
        return None  # the right side was not the left's mirror image (not a mirrored design)
    return Xnew, Fnew, labnew, Wnew, out_lines


#: relative change of a panel's area or a line's length above which the two sides are not
#: mirror images of each other (a design with a different right side): the mesh is kept
SHAPE_TOLERANCE = 0.02


def _same_shape(X, F, lab, lines, X2, F2, lab2, lines2) -> bool:
    """Every panel's area and every line's length and centroid the same within tolerance."""

    def areas(X, F, lab):
        return np.bincount(lab, triangle_areas(X, F), minlength=int(max(lab.max(), lab2.max())) + 1)

    A, A2 = areas(np.asarray(X, float), F, lab), areas(X2, F2, lab2)
    if np.any(np.abs(A2 - A) > SHAPE_TOLERANCE * np.maximum(A, 1e-12)):
        return False
    for r1, r2 in zip(lines, lines2):
        P1 = [np.asarray(X, float)[r] for r in r1]
        P2 = [X2[r] for r in r2]
        L1 = sum(polyline_length(p) for p in P1)
        L2 = sum(polyline_length(p) for p in P2)
        if abs(L2 - L1) > SHAPE_TOLERANCE * L1 + 2e-3:
            return False
        if P1 and P2 and np.linalg.norm(np.concatenate(P1).mean(0) - np.concatenate(P2).mean(0)) > 5e-3:
            return False
    return True


def _edge_keys(F: np.ndarray, n: int) -> np.ndarray:
    """(3 f,) int64 undirected edge key ``min * n + max`` of each face's three edges."""
    e = np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)
    return e.min(1) * np.int64(n) + e.max(1)


def _centre_lines(F, lab, lines, plan, n) -> Dict[int, set]:
    """Midline lines that are centre seams: line index -> the set of their panels' pair keys
    ``min(a, mirror a)`` of the sided panels ``a`` they separate from their own mirror."""
    keys = _edge_keys(F, n)
    order = np.argsort(keys, kind="stable")
    sk, fl = keys[order], lab[order // 3]
    pm = plan["panel"]
    out = {}
    for k, runs in enumerate(lines):
        if plan["line_side"][k] >= 0 or not runs:
            continue
        e = np.concatenate([np.sort(np.stack([r[:-1], r[1:]], 1), axis=1) for r in runs])
        q = e[:, 0] * np.int64(n) + e[:, 1]
        lo, hi = np.searchsorted(sk, q, "left"), np.searchsorted(sk, q, "right")
        pairs = set()
        for a, b in zip(lo.tolist(), hi.tolist()):
            if b - a == 2 and fl[a] != fl[a + 1] and pm[fl[a]] == fl[a + 1]:
                pairs.add(int(min(fl[a], fl[a + 1])))
        if pairs:
            out[k] = pairs
    return out


def _midline_edges(F, left, lab, pm, new) -> Dict[int, np.ndarray]:
    """Per sided panel pair key (see :func:`_centre_lines`), its edges on the midline after
    the rebuild ((e, 2) new ids): the edges both halves share, on a face of that pair."""
    n = np.int64(len(new))
    kl, kr = _edge_keys(F[left], n), _edge_keys(F[~left], n)
    on_mid = np.isin(kl, kr)
    fl = np.repeat(lab[left], 3)
    out = {}
    for key in np.unique(np.minimum(fl, pm[fl])[on_mid & (fl != pm[fl])]).tolist():
        k = kl[on_mid & (np.minimum(fl, pm[fl]) == key)]
        out[int(key)] = new[np.stack([k // n, k % n], 1)]
    return out


def _chains(edges: np.ndarray) -> Optional[List[np.ndarray]]:
    """The vertex sequences of a set of edges that form disjoint open paths (None otherwise),
    each from its smaller end id."""
    if len(edges) == 0:
        return []
    adj: Dict[int, List[int]] = {}
    for a, b in edges.tolist():
        adj.setdefault(a, []).append(b)
        adj.setdefault(b, []).append(a)
    if max(len(v) for v in adj.values()) > 2:
        return None
    seen, out = set(), []
    for start in sorted(v for v, nb in adj.items() if len(nb) == 1):
        if start in seen:
            continue
        path, prev = [start], None
        while True:
            seen.add(path[-1])
            nxt = [w for w in adj[path[-1]] if w != prev]
            if not nxt:
                break
            prev = path[-1]
            path.append(nxt[0])
        out.append(np.asarray(path, dtype=np.int64))
    return out if len(seen) == len(adj) else None  # a closed loop is no centre seam


def _centre_runs(runs, pairs, midline, X, Xnew) -> Optional[List[np.ndarray]]:
    """A centre seam rebuilt on the midline: the midline edges of its panel pairs, each run
    running the way the old line ran (from the end nearer its first vertex; ``X``: the old
    mesh's vertices, ``Xnew``: the rebuilt mesh's)."""
    e = [midline[k] for k in sorted(pairs) if k in midline]
    chains = _chains(np.concatenate(e)) if e else None
    if not chains:
        return None
    first = X[np.concatenate(runs)[0]]
    return [
        c if np.linalg.norm(Xnew[c[0]] - first) <= np.linalg.norm(Xnew[c[-1]] - first) else c[::-1].copy()
        for c in chains
    ]


def _mirror_lines(lines, plan, inL, mid, new, mir, centre, midline, X, Xnew) -> Optional[List[List[np.ndarray]]]:
    """Every line's runs in the new ids: a left line's kept, a right line's the mirror of its
    left line's, a centre seam's rebuilt on the midline (:func:`_centre_runs`), another
    midline line's by :func:`_self_mirror_runs`."""
    out: List[List[np.ndarray]] = []
    for k, runs in enumerate(lines):
        side = plan["line_side"][k]
        if k in centre:
            got = _centre_runs(runs, centre[k], midline, X, Xnew)
        elif side < 0:
            got = _self_mirror_runs(runs, inL, mid, new, mir)
        else:
            src = runs if side == 1 else lines[plan["line"][k]]
            got = None if not all(inL[r].all() for r in src) else [(new if side == 1 else mir)[r] for r in src]
        if got is None:
            return None
        out.append(got)
    return out


def _self_mirror_runs(runs, inL, mid, new, mir) -> Optional[List[np.ndarray]]:
    """A line that is its own mirror: each stretch on the right replaced by the reflection of the
    line's left stretch between the same two midline vertices (or the same midline vertex and a
    free end)."""
    # the left stretches: maximal runs of left vertices, split at midline vertices
    stretches = []
    for r in runs:
        hit = np.nonzero(mid[r])[0]
        if len(r) > 2 and r[0] == r[-1] and len(hit):
            # a closed run (a hem ring around the skirt topology's bridge) starting on the left:
            # its left stretch across the start is whole when the run starts on the midline
            r = np.concatenate([r[hit[0] : -1], r[: hit[0] + 1]])
        cur: List[int] = []
        for v in r.tolist():
            if not inL[v]:
                if len(cur) >= 2:
                    stretches.append(cur)
                cur = []
                continue
            cur.append(v)
            if mid[v] and len(cur) >= 2:
                stretches.append(cur)
                cur = [v]
        if len(cur) >= 2:
            stretches.append(cur)

    def reflected(a: Optional[int], b: Optional[int]) -> Optional[List[int]]:
        """The mirror of the left stretch joining midline vertices a and b, from a to b
        (``None``: a free end)."""
        if a is None and b is None:
            return None
        for s in stretches:
            for seq in (s, s[::-1]):
                first = seq[0] == a if a is not None else not mid[seq[0]]
                last = seq[-1] == b if b is not None else not mid[seq[-1]]
                if first and last:
                    return [int(mir[v]) for v in seq]
        return None

    out = []
    for r in runs:
        vs = r.tolist()
        res: List[int] = []
        i = 0
        while i < len(vs):
            if inL[vs[i]]:
                res.append(int(new[vs[i]]))
                i += 1
                continue
            j = i
            while j < len(vs) and not inL[vs[j]]:
                j += 1
            a = vs[i - 1] if i > 0 else None
            b = vs[j] if j < len(vs) else None
            if (a is not None and not mid[a]) or (b is not None and not mid[b]):
                return None
            seg = reflected(a, b)
            if seg is None:
                return None
            if a is not None:
                seg = seg[1:]
            if b is not None:
                seg = seg[:-1]
            res += seg
            i = j
        if len(res) >= 2:
            out.append(np.asarray(res, dtype=np.int64))
    return out


def _lines_mirror(lines, plan, new, mir, n_new: int) -> bool:
    """Every line's edges reflect onto its mirror line's edges (new ids)."""
    m = np.arange(n_new, dtype=np.int64)
    ok = mir >= 0
    m[new[ok]] = mir[ok]
    m[mir[ok]] = new[ok]

    def keys(runs, f):
        if not runs:
            return np.zeros(0, np.int64)
        e = [np.stack([f[r[:-1]], f[r[1:]]], 1) for r in runs]
        e = np.sort(np.concatenate(e), axis=1)
        return np.unique(e[:, 0] * n_new + e[:, 1])

    ident = np.arange(n_new, dtype=np.int64)
    for k, runs in enumerate(lines):
        if not np.array_equal(keys(runs, m), keys(lines[plan["line"][k]], ident)):
            return False
    return True


def coded_labels(mirror, panel_names: Sequence[str], line_names: Sequence[str], parents: np.ndarray, lab: np.ndarray):
    """The garment's mirror plan and its face labels with the body side folded in.

    Refinement and edge flips then never join a left and a right face (labels differ), so the
    midline stays a polyline of the mesh. ``mirror``: ``(symmetry, body_face_sides)`` or None.

    Returns
    -------
    (plan or None, (f,) int labels: ``2 * label + side`` with a plan, else ``lab`` unchanged)
    """
    if mirror is None:
        return None, lab
    plan = mirror_plan(panel_names, line_names)
    sides = mirror[1]
    if plan is None or len(parents) == 0 or parents.max() >= len(sides):  # a bridge without sides
        return None, lab
    return plan, 2 * np.asarray(lab, dtype=np.int64) + sides[parents]


def mirrored_mesh(mirror, plan, X, F, coded, W, lines, body_X):
    """:func:`symmetrize` on a mesh with :func:`coded_labels`; ``(X, F, lab, W, lines)``, the
    input's (labels decoded) where the garment is not mirror-symmetric."""
    lab, side = coded // 2, coded % 2
    got = symmetrize(X, F, lab, side, W, lines, plan, mirror[0], body_X)
    return (X, F, lab, W, lines) if got is None else got
