"""A numpy port of `ductile_core::ffsd` and of the area-restricted stack, for previews and
self-checks of the identikit library (the Rust crate stays the reference implementation).

Mirrors crates/ductile-core/src/ffsd.rs: for each point with centre X (C, or R in
directional mode), target T (C; 2·V_min − C; 2R − C) and parameters γ·gain, α, ε,
`d(V) = γ · exp(−(|X − V|^α − |X − V_min|^α) / (2ε²)) · (V − T)`, summed over points, then
the height limit relative to S_ref = max_k |D(V_min,k)|.
"""

import numpy as np


def _pow(d2, alpha):
    return np.power(d2, 0.5 * alpha)


def evaluate_points(points, height, gain, positions, active):
    """Deformed positions of the `active` welded vertices (returns (len(active), 3))."""
    v = positions[active].astype(np.float64)
    prepared = []
    for pt in points:
        c = np.asarray(pt["position"], np.float64)
        ref = pt.get("reference")
        centre = np.asarray(ref, np.float64) if ref is not None else c
        d2 = ((v - centre) ** 2).sum(1)
        anchor = int(np.argmin(d2))
        vmin = v[anchor]
        mode = pt.get("mode", "basic")
        if mode == "basic":
            target = c
        elif mode == "virtual":
            target = 2 * vmin - c
        else:
            target = 2 * centre - c
        prepared.append((centre, target, pt["gamma"] * gain, pt["alpha"], pt["epsilon"],
                         _pow(d2[anchor], pt["alpha"]), anchor))

    def total(x):
        out = np.zeros_like(x)
        for centre, target, gamma, alpha, eps, anchor_pow, _ in prepared:
            e = (_pow(((x - centre) ** 2).sum(-1), alpha) - anchor_pow) / (2 * eps * eps)
            out += (x - target) * (gamma * np.exp(-e))[..., None]
        return out

    d = total(v)
    s_ref = max((np.linalg.norm(total(v[p[6]][None])[0]) for p in prepared), default=0.0)
    if height is not None:
        s = np.linalg.norm(d, axis=1)
        kind = height[0]
        with np.errstate(divide="ignore", invalid="ignore"):
            if kind == "Above":
                s_max = height[1] * s_ref
                f = np.where(s > s_max, s_max / s, 1.0)
            elif kind == "Below":
                s_min = height[1] * s_ref
                f = np.where(s <= s_min, 0.0, (s - s_min) / s)
            else:
                lo, hi = height[1] * s_ref, height[2] * s_ref
                f = np.where(s <= lo, 0.0, np.minimum(s - lo, hi - lo) / s)
        f = np.where(s == 0, 1.0, f)
        d = d * f[:, None]
    return v + d


def region_members(shapes, positions):
    """Welded vertex indices inside any of the area's shapes (sorted)."""
    inside = np.zeros(len(positions), bool)
    for sh in shapes:
        local = positions - np.asarray(sh["translation"])
        rot = sh.get("rotation_matrix")
        if rot is not None:
            local = local @ rot          # inverse rotation: R^T applied to column vectors
        kind = sh["kind"]
        if kind == "sphere":
            t = np.linalg.norm(local, axis=1) / sh["radius"]
        elif kind == "box":
            t = (np.abs(local) / np.asarray(sh["half_extents"])).max(1)
        else:
            axis = np.zeros_like(local)
            axis[:, 1] = np.clip(local[:, 1], -sh["half_height"], sh["half_height"])
            t = np.linalg.norm(local - axis, axis=1) / sh["radius"]
        inside |= t <= 1.0
    return np.nonzero(inside)[0]


def evaluate_stack(library, areas, settings, rest):
    """Evaluates macros in order on welded rest positions; `settings` = [(macro, value)]."""
    p = rest.astype(np.float64).copy()
    members = {name: region_members(shapes, rest) for name, shapes in areas.items()}
    for name, value in settings:
        m = library[name]
        active = members[m["area"]]
        p[active] = evaluate_points(m["points"], m.get("height"), value, p, active)
    return p
