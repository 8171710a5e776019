"""Landmarks of the Lee Perry-Smith head, found from its geometry.

Mesh space of `assets/meshes/lee-perry-smith-head.glb`: +Y up, the face looks along +Z,
+X is the subject's left. Units are the file's (Blender units; crown to chin ≈ 4.9, so one
unit ≈ 4.7 cm). The approximate mirror plane is `x = X0` (normal +X), found by a scan that
minimises the median distance between the head (y > −1) and its mirror image.

Midline landmarks are extremes of the profile (vertices with |x − X0| < 0.05); bilateral
landmarks are found on the subject's left (+X) by local searches around documented seed
coordinates (checked visually on renders) and mirrored exactly: x' = 2·X0 − x.
"""

import numpy as np

X0 = -0.09          # mirror plane x = X0
DECIMALS = 4        # every coordinate written to the scenes is rounded to 1e-4


def q(x):
    """Rounds a coordinate to the scene grid."""
    return round(float(x) + 0.0, DECIMALS) + 0.0


def mirror(p):
    """Mirror image of point p about the plane x = X0, on the scene grid (exact decimals)."""
    return (q(2 * X0 - q(p[0])), q(p[1]), q(p[2]))


def mirror_dir(v):
    """Mirror image of a direction."""
    return (-v[0], v[1], v[2])


class Head:
    """Welded vertex positions and the landmark searches on them."""

    def __init__(self, welded):
        self.v = np.asarray(welded, np.float64)
        v = self.v
        mid = v[(np.abs(v[:, 0] - X0) < 0.06) & (v[:, 2] > 0)]
        # The profile: the frontmost midline vertex in each 0.03-high band (drops the
        # vertices inside the nostrils and the mouth).
        bands = np.floor(mid[:, 1] / 0.03).astype(int)
        keep = [np.nonzero(bands == b)[0][np.argmax(mid[bands == b, 2])]
                for b in np.unique(bands)]
        self.mid = mid[sorted(keep)]

    def _mid_extreme(self, y_lo, y_hi, fn):
        band = self.mid[(self.mid[:, 1] >= y_lo) & (self.mid[:, 1] <= y_hi)]
        return band[fn(band[:, 2])]

    def front(self, x, y, r=0.05, deepest=False):
        """The surface point seen from the front (+Z) near (x, y): the frontmost vertex within
        r; with `deepest`, the least forward among the front-facing vertices there (a crease)."""
        v = self.v
        near = v[((v[:, 0] - x) ** 2 + (v[:, 1] - y) ** 2 < r * r) & (v[:, 2] > 0)]
        if len(near) == 0:
            return self.front(x, y, 2 * r, deepest)
        if deepest:
            top = near[:, 2].max()
            near = near[near[:, 2] > top - 0.25]
            return near[np.argmin(near[:, 2])]
        return near[np.argmax(near[:, 2])]

    def lateral(self, y, z, r=0.06):
        """The surface point seen from the subject's left (+X) near (y, z)."""
        v = self.v
        near = v[((v[:, 1] - y) ** 2 + (v[:, 2] - z) ** 2 < r * r) & (v[:, 0] > X0)]
        if len(near) == 0:
            return self.lateral(y, z, 2 * r)
        return near[np.argmax(near[:, 0])]

    def compute(self):
        """All landmarks: midline ones as points, bilateral ones on the left (+X) side."""
        v = self.v
        lm = {}
        face = v[(v[:, 1] > 0) & (v[:, 1] < 2.5)]
        tip = face[np.argmax(face[:, 2])]
        lm["nose-tip"] = tip
        lm["nose-bridge"] = self._mid_extreme(tip[1] + 0.4, tip[1] + 1.3, np.argmin)
        sellion = lm["nose-bridge"]
        lm["glabella"] = self._mid_extreme(sellion[1], sellion[1] + 0.6, np.argmax)
        lm["forehead"] = self.front(X0, sellion[1] + 1.0)
        lm["subnasale"] = self._mid_extreme(tip[1] - 0.5, tip[1] - 0.1, np.argmin)
        sn = lm["subnasale"]
        lm["upper-lip"] = self._mid_extreme(sn[1] - 0.45, sn[1] - 0.05, np.argmax)
        ls = lm["upper-lip"]
        lm["lower-lip"] = self._mid_extreme(ls[1] - 0.5, ls[1] - 0.15, np.argmax)
        li = lm["lower-lip"]
        # The mouth slit: between the lip centres, on the front surface.
        lm["mouth-centre"] = self.front(X0, (ls[1] + li[1]) / 2, r=0.04)
        lm["chin"] = self._mid_extreme(li[1] - 1.0, li[1] - 0.3, np.argmax)
        # Left side (+X). Nose wing: the most lateral point of the lower nose.
        lower_nose = v[(v[:, 1] > tip[1] - 0.25) & (v[:, 1] < tip[1] + 0.1)
                       & (v[:, 2] > tip[2] - 0.45) & (v[:, 0] > X0)]
        lm["nose-wing"] = lower_nose[np.argmax(lower_nose[:, 0])]
        # Seeds below were read off front renders with a 0.1 grid (docs/identikit.md).
        lm["nostril"] = self.front(0.10, 0.95, r=0.05, deepest=True)
        lm["eye-inner"] = self.front(0.21, 1.70, r=0.05, deepest=True)
        lm["eye-outer"] = self.front(0.78, 1.665, r=0.05, deepest=True)
        ei, eo = lm["eye-inner"], lm["eye-outer"]
        lm["eye"] = self.front((ei[0] + eo[0]) / 2, (ei[1] + eo[1]) / 2 + 0.02)
        for name, x in [("brow-inner", ei[0] + 0.05), ("brow", (ei[0] + eo[0]) / 2),
                        ("brow-outer", eo[0])]:
            col = v[(np.abs(v[:, 0] - x) < 0.03) & (v[:, 1] > lm["eye"][1] + 0.15)
                    & (v[:, 1] < lm["eye"][1] + 0.5) & (v[:, 2] > 0)]
            lm[name] = col[np.argmax(col[:, 2])]
        lm["mouth-corner"] = self.front(0.37, 0.42, r=0.05, deepest=True)
        lm["cheekbone"] = self.front(0.95, 1.25)
        lm["cheek"] = self.front(0.80, 0.60)
        lm["chin-side"] = self.front(X0 + 0.4, lm["chin"][1] - 0.05)
        lm["jaw-angle"] = self.lateral(-0.35, 0.55, r=0.1)
        ear = v[(v[:, 0] > X0 + 1.5) & (v[:, 1] > 0.55) & (v[:, 1] < 1.95)
                & (v[:, 2] > -0.55) & (v[:, 2] < 0.6)]
        lm["ear-top"] = ear[np.argmax(ear[:, 1])]
        lm["ear-lobe"] = ear[np.argmin(ear[:, 1])]
        lm["ear-back"] = ear[np.argmin(ear[:, 2])]
        lo, hi = ear.min(0), ear.max(0)
        lm["ear"] = (lo + hi) / 2
        self.ear_vertices = ear
        # Midline landmarks lie on the mirror plane (the mesh is only nearly symmetric; the
        # snap moves them by less than 0.06 units).
        for k in MIDLINE:
            lm[k] = np.array([X0, lm[k][1], lm[k][2]])
        return {k: tuple(q(c) for c in p) for k, p in lm.items()}


MIDLINE = ["nose-tip", "nose-bridge", "glabella", "forehead", "subnasale", "upper-lip",
           "lower-lip", "mouth-centre", "chin"]
