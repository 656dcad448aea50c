"""Conforming refinement of the cut panels to a target edge length.

``h`` is the target *mean* edge length: every edge longer than
``SPLIT_RATIO * h`` (at the reference body) is split at its midpoint, so the
halves are at least ``0.75 h`` long and the mean edge lands near ``h`` (0.92 h
on the long-sleeve shirt, 21.5k triangles at 1 cm). Splitting every edge longer
than ``h`` instead would leave a mean of 0.62 h and 2.2x the triangles, which
every later stage (pattern solve, drape) pays for. Each triangle is then
re-split by the number of its split edges (1 -> 2, 2 -> 3 with the shorter
diagonal, 3 -> 4, "red-green"). An edge is split once for both its triangles,
so the mesh stays conforming and both sides of every seam get the same new
vertices. Rounds repeat until no edge exceeds ``SPLIT_RATIO * h``. New
vertices are midpoints, i.e. averages of two embedding rows, so the refinement
applies to every body instance.
"""

from __future__ import annotations

from typing import List

import numpy as np
import scipy.sparse as sp

#: edges longer than this multiple of the target length are split
SPLIT_RATIO = 1.5


def _edges(F: np.ndarray):
    """Unique undirected edges (e, 2) and per-face edge ids (f, 3), edge k = (F[k], F[k+1])."""
    a = F.reshape(-1)
    b = np.roll(F, -1, axis=1).reshape(-1)
    n = np.int64(F.max()) + 1
    key = np.minimum(a, b) * n + np.maximum(a, b)
    uk, inv = np.unique(key, return_inverse=True)
    E = np.stack([uk // n, uk % n], axis=1)
    return E, inv.reshape(-1, 3)


def refine(
    X: np.ndarray,
    F: np.ndarray,
    labels: np.ndarray,
    W: sp.csr_matrix,
    lines: List[np.ndarray],
    h: float,
    max_rounds: int = 12,
):
    """Refine triangles ``F`` to a mean edge length near ``h``.

    Parameters
    ----------
    X : (n, 3) float, reference positions.
    F : (f, 3) int triangles (orientation is kept).
    labels : (f,) int, carried to the children (panel index).
    W : (n, V) sparse, embedding rows of the vertices (body weights).
    lines : list of (k,) int vertex sequences along cut lines; midpoints of
        their edges are inserted in order.
    h : float, target mean edge length in metres (no edge stays longer than
        ``SPLIT_RATIO * h``).

    Returns
    -------
    X, F, labels, W, lines : refined arrays of the same meaning.
    """
    X = np.asarray(X, float)
    F = np.asarray(F, np.int64)
    labels = np.asarray(labels)
    W = sp.csr_matrix(W)
    lines = [np.asarray(l, np.int64) for l in lines]
    for _ in range(max_rounds):
        if len(F) == 0:
            break
        E, fe = _edges(F)
        length = np.linalg.norm(X[E[:, 0]] - X[E[:, 1]], axis=1)
        split = length > SPLIT_RATIO * h
        if not split.any():
            break
        n = len(X)
        ids = np.full(len(E), -1, dtype=np.int64)
        ids[split] = n + np.arange(split.sum())
        Es = E[split]
        X = np.concatenate([X, 0.5 * (X[Es[:, 0]] + X[Es[:, 1]])])
        m = len(Es)
        S = sp.csr_matrix((np.full(2 * m, 0.5), (np.repeat(np.arange(m), 2), Es.reshape(-1))), shape=(m, n))
        W = sp.vstack([W, S @ W]).tocsr()
        F, labels = _split_faces(F, labels, ids[fe], X)
        lines = [_split_line(l, E, ids, n) for l in lines]
    return X, F, labels, W, lines


def _split_faces(F, labels, mid, X):
    """Re-triangulate faces given per-edge midpoint ids ``mid`` (f, 3), -1 = unsplit."""
    cnt = (mid >= 0).sum(1)
    outF = [F[cnt == 0]]
    outL = [labels[cnt == 0]]
    for r in range(3):
        # rotate so that the pattern is canonical: edge k = (v_k, v_{k+1})
        Fr = np.roll(F, -r, axis=1)
        Mr = np.roll(mid, -r, axis=1)
        one = (cnt == 1) & (Mr[:, 0] >= 0)
        if one.any():
            v, m = Fr[one], Mr[one]
            outF += [np.stack([v[:, 0], m[:, 0], v[:, 2]], 1), np.stack([m[:, 0], v[:, 1], v[:, 2]], 1)]
            outL += [labels[one]] * 2
        two = (cnt == 2) & (Mr[:, 2] < 0)
        if two.any():
            v, m = Fr[two], Mr[two]
            outF.append(np.stack([m[:, 0], v[:, 1], m[:, 1]], 1))
            # quad v0, m0, m1, v2: take the shorter diagonal
            d1 = np.linalg.norm(X[v[:, 0]] - X[m[:, 1]], axis=1)
            d2 = np.linalg.norm(X[m[:, 0]] - X[v[:, 2]], axis=1)
            a = d1 <= d2
            t1 = np.where(
                a[:, None], np.stack([v[:, 0], m[:, 0], m[:, 1]], 1), np.stack([v[:, 0], m[:, 0], v[:, 2]], 1)
            )
            t2 = np.where(
                a[:, None], np.stack([v[:, 0], m[:, 1], v[:, 2]], 1), np.stack([m[:, 0], m[:, 1], v[:, 2]], 1)
            )
            outF += [t1, t2]
            outL += [labels[two]] * 3
    three = cnt == 3
    if three.any():
        v, m = F[three], mid[three]
        outF += [
            np.stack([v[:, 0], m[:, 0], m[:, 2]], 1),
            np.stack([m[:, 0], v[:, 1], m[:, 1]], 1),
            np.stack([m[:, 2], m[:, 1], v[:, 2]], 1),
            np.stack([m[:, 0], m[:, 1], m[:, 2]], 1),
        ]
        outL += [labels[three]] * 4
    # keep a deterministic order: children grouped by pattern, parents in order
    return np.concatenate(outF).astype(np.int64), np.concatenate(outL)


def _split_line(line: np.ndarray, E: np.ndarray, ids: np.ndarray, n: int) -> np.ndarray:
    if len(line) < 2:
        return line
    a, b = line[:-1], line[1:]
    und = np.sort(np.stack([a, b], 1), axis=1)
    key_e = E[:, 0] * n + E[:, 1]
    key_l = und[:, 0] * n + und[:, 1]
    pos = np.searchsorted(key_e, key_l)
    pos = np.clip(pos, 0, len(E) - 1)
    found = key_e[pos] == key_l
    mid = np.where(found, ids[pos], -1)
    out = np.empty(len(line) + (mid >= 0).sum(), dtype=np.int64)
    # interleave: vertex, [midpoint], vertex, ...
    seq = []
    for i in range(len(a)):
        seq.append(a[i])
        if mid[i] >= 0:
            seq.append(mid[i])
    seq.append(line[-1])
    out[:] = seq
    return out


def _member(q: np.ndarray, sorted_keys: np.ndarray) -> np.ndarray:
    """Whether each of ``q`` is in the sorted array ``sorted_keys``."""
    if len(sorted_keys) == 0:
        return np.zeros(len(q), dtype=bool)
    pos = np.clip(np.searchsorted(sorted_keys, q), 0, len(sorted_keys) - 1)
    return sorted_keys[pos] == q


def delaunay_flips(
    X: np.ndarray,
    F: np.ndarray,
    labels: np.ndarray,
    fixed: np.ndarray,
    max_length: float = np.inf,
    max_rounds: int = 2,
    max_dihedral_deg: float = 10.0,
    _retest_all: bool = False,
) -> np.ndarray:
    """Improve triangle shapes by flipping edges to the (extrinsic) Delaunay criterion.

    An interior edge is flipped when the two angles opposite it sum to more
    than pi, both its triangles carry the same label (panel), it is not in
    ``fixed`` (cut lines), the triangles are nearly coplanar (dihedral below
    ``max_dihedral_deg``, so the surface barely changes) and the flipped
    triangles keep their orientation. No vertex moves or is added, so the
    embedding is unchanged. Flips are applied in rounds of independent edges.

    Parameters
    ----------
    X : (n, 3) float; F : (f, 3) int; labels : (f,) int.
    fixed : (k,) int64 undirected edge keys ``min * n + max`` never flipped.
    max_length : no flip makes an edge longer than this (keeps a refinement's bound).
    _retest_all : test every edge in every round (slower, same result; for tests).

    Returns
    -------
    F : (f, 3) int, same faces count and face order, labels unchanged.
    """
    F = np.array(F, dtype=np.int64, copy=True)
    n = np.int64(len(X))
    cos_max = np.cos(np.deg2rad(max_dihedral_deg))
    fixed_sorted = np.sort(np.asarray(fixed, dtype=np.int64))
    # After the first round only edges next to a flipped face, or edges that qualified
    # but were held back (by a neighbour's flip, or an existing edge), can qualify: every
    # other edge has the same two triangles as before. Testing just those gives the same
    # flips as testing all.
    dirty = None  # (f,) bool: faces changed by the last round
    pending = None  # half-edges that qualified last round but were not flipped
    for _ in range(max_rounds):
        a = F.reshape(-1)
        b = np.roll(F, -1, axis=1).reshape(-1)
        o = np.roll(F, -2, axis=1).reshape(-1)
        key = a * n + b
        order = np.argsort(key, kind="stable")
        rkey = b * n + a
        pos = np.clip(np.searchsorted(key[order], rkey), 0, len(key) - 1)
        twin = np.where(key[order][pos] == rkey, order[pos], -1)
        h = np.nonzero((twin > np.arange(len(key))))[0]  # each interior edge once
        if dirty is not None and not _retest_all:
            look = dirty[h // 3] | dirty[twin[h] // 3]
            look[np.searchsorted(h, pending)] = True  # pending half-edges are still in h
            h = h[look]
        t = twin[h]
        fh, ft = h // 3, t // 3
        ukey = np.minimum(a[h], b[h]) * n + np.maximum(a[h], b[h])
        ok = (labels[fh] == labels[ft]) & ~_member(ukey, fixed_sorted)
        h, t, fh, ft = h[ok], t[ok], fh[ok], ft[ok]
        A, B, O1, O2 = X[a[h]], X[b[h]], X[o[h]], X[o[t]]

        def angle(p, q, r):  # angle at p between q and r
            u, v = q - p, r - p
            c = (u * v).sum(1) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1), 1e-300)
            return np.arccos(np.clip(c, -1.0, 1.0))

        viol = angle(O1, A, B) + angle(O2, A, B) - np.pi
        n1 = np.cross(B - A, O1 - A)
        n2 = np.cross(A - B, O2 - B)
        nn = lambda v: v / np.maximum(np.linalg.norm(v, axis=1), 1e-300)[:, None]
        n1, n2 = nn(n1), nn(n2)
        m1 = nn(np.cross(O2 - A, O1 - A))  # new face (a, o2, o1)
        m2 = nn(np.cross(O1 - B, O2 - B))  # new face (b, o1, o2)
        good = (viol > 1e-6) & ((n1 * n2).sum(1) > cos_max) & (o[h] != o[t])
        good &= np.linalg.norm(O1 - O2, axis=1) <= max_length
        good &= (
            ((m1 * n1).sum(1) > 0.5) & ((m1 * n2).sum(1) > 0.5) & ((m2 * n1).sum(1) > 0.5) & ((m2 * n2).sum(1) > 0.5)
        )
        # the new edge must not exist already
        okey = np.minimum(o[h], o[t]) * n + np.maximum(o[h], o[t])
        idx = np.nonzero(good)[0]
        qualified = h[idx]
        sk = key[order]
        exists = _member(o[h[idx]] * n + o[t[idx]], sk) | _member(o[t[idx]] * n + o[h[idx]], sk)
        idx = idx[~exists]
        if len(idx) == 0:
            break
        # independent flips: each face takes part in at most one, the worst violation wins
        idx = idx[np.argsort(-viol[idx], kind="stable")]
        rank = np.arange(len(idx))
        best = np.full(len(F), len(idx), dtype=np.int64)
        np.minimum.at(best, fh[idx], rank)
        np.minimum.at(best, ft[idx], rank)
        idx = idx[(best[fh[idx]] == rank) & (best[ft[idx]] == rank)]
        _, first = np.unique(okey[idx], return_index=True)  # one flip per new edge
        idx = idx[np.sort(first)]
        if len(idx) == 0:
            break
        va, vb, v1, v2 = a[h[idx]], b[h[idx]], o[h[idx]], o[t[idx]]
        F[fh[idx]] = np.stack([va, v2, v1], axis=1)
        F[ft[idx]] = np.stack([vb, v1, v2], axis=1)
        dirty = np.zeros(len(F), dtype=bool)
        dirty[fh[idx]] = True
        dirty[ft[idx]] = True
        pending = qualified[~dirty[qualified // 3]]
    return F
