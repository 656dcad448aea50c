"""Synthetic bodies for the cutting-engine tests (no tests here).

A closed capsule-like tube (staggered rings, so cut lines cross edges
obliquely) with a "head" and "feet" region, helpers to make SurfacePoints at
3D positions, and a two-panel tube "shirt" cut spec.
"""

import numpy as np

from core.body.model import SurfacePoint
from core.design.spec import CutLine, CutSpec, GarmentSpec, PanelSpec

R = 0.15


def capsule(r=R, h=1.0, nt=48, nz=40, twist=0.0, scale=1.0):
    """Closed tube mesh: (V, 3) vertices, (F, 3) outward triangles."""
    zs = np.linspace(0.05, h - 0.05, nz)
    V = []
    for k, z in enumerate(zs):
        th = 2 * np.pi * (np.arange(nt) + 0.5 * (k % 2)) / nt + twist * z
        V.append(np.stack([r * scale * np.cos(th), r * scale * np.sin(th), np.full(nt, z)], 1))
    V = np.concatenate(V)
    F = []
    for k in range(nz - 1):
        a, b = k * nt, (k + 1) * nt
        for i in range(nt):
            i1 = (i + 1) % nt
            if k % 2 == 0:
                F += [[a + i, a + i1, b + i], [a + i1, b + i1, b + i]]
            else:
                F += [[a + i, b + i1, b + i], [a + i, a + i1, b + i1]]
    bot, top = len(V), len(V) + 1
    V = np.concatenate([V, [[0, 0, 0.0], [0, 0, h]]])
    t = (nz - 1) * nt
    for i in range(nt):
        i1 = (i + 1) % nt
        F.append([bot, i1, i])
        F.append([top, t + i, t + i1])
    return V, np.array(F)


class SynthBody:
    """A minimal BodyModel-like object on the capsule."""

    name = "synth"

    def __init__(self, forbidden=True, **kw):
        self.V, self.faces = capsule(**kw)
        z = self.V[:, 2]
        empty = np.zeros(0, dtype=np.int64)
        self.regions = {
            "head": np.nonzero(z > 0.9)[0] if forbidden else empty,
            "hands": empty,
            "feet": np.nonzero(z < 0.08)[0] if forbidden else empty,
        }
        self.joint_names = []
        self.landmarks = {}
        self.symmetry = np.arange(len(self.V))

    def vertices(self, shape=None, pose=None):
        return self.V

    def point(self, p):
        """SurfacePoint at the surface point closest to p (3,)."""
        import igl

        _, fi, c = igl.point_mesh_squared_distance(np.asarray(p, float)[None], self.V, self.faces)
        f = int(np.atleast_1d(fi)[0])
        c = np.atleast_2d(c)[0]
        T = self.V[self.faces[f]]
        M = np.stack([T[1] - T[0], T[2] - T[0]], 1)
        l, *_ = np.linalg.lstsq(M, c - T[0], rcond=None)
        b = np.clip(np.array([1 - l.sum(), l[0], l[1]]), 0, None)
        return SurfacePoint(f, tuple(b / b.sum()))

    def ring(self, z, angles, r=R):
        return [self.point([r * np.cos(a), r * np.sin(a), z]) for a in angles]


# angles around the tube: +X is the body's left, the front faces -Y
LEFT, FRONT, RIGHT, BACK = 0.0, -np.pi / 2, np.pi, np.pi / 2


def tube_spec(body, refine=None, close_top=True, extra_panels=False):
    """Two-panel tube shirt: neck and hem loops, left/right side seams."""
    top = body.ring(0.8, [LEFT, FRONT, RIGHT, BACK])
    bot = body.ring(0.2, [LEFT, FRONT, RIGHT, BACK])
    lines = [
        CutLine("shirt.neck", top if close_top else top[:3], closed=close_top, role="opening"),
        CutLine("shirt.hem", bot, closed=True, role="opening"),
        CutLine("shirt.side_left", [top[0], bot[0]]),
        CutLine("shirt.side_right", [top[2], bot[2]]),
    ]
    panels = [
        PanelSpec("shirt.front", "shirt", body.point([0, -R, 0.5])),
        PanelSpec("shirt.back", "shirt", body.point([0, R, 0.5])),
    ]
    if extra_panels:
        panels += [
            PanelSpec("shirt.cap_top", "shirt", body.point([0, -R, 0.9])),
            PanelSpec("shirt.cap_bottom", "shirt", body.point([0, -R, 0.1])),
        ]
    return CutSpec(
        lines,
        panels,
        [GarmentSpec("shirt", "upper", pin_line="shirt.neck")],
        refine_edge_length=refine,
        body={"model": "synth"},
    )


def triangle_areas(X, F):
    return 0.5 * np.linalg.norm(np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]]), axis=1)


def surface_distance(P, V, F):
    import igl

    d, _, _ = igl.point_mesh_squared_distance(np.asarray(P, float), V, F)
    return np.sqrt(d)
