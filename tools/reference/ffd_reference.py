#!/usr/bin/env python3
"""Independent reference evaluation of Sederberg–Parry FFD, written from the paper.

Writes `crates/ductile-core/tests/data/ffd-reference.json`, which the Rust test
`crates/ductile-core/tests/ffd_reference.rs` compares against (so CI needs no Python).

The evaluation below follows Sederberg & Parry (1986) as summarised in Bechmann's survey
§2.1, with the cross products corrected (the survey prints S∧T in all three formulas):

    s = (T×U)·(X − X0) / ((T×U)·S),  t = (S×U)·(X − X0) / ((S×U)·T),
    u = (S×T)·(X − X0) / ((S×T)·U),
    P_ijk = X0 + (i/l) S + (j/m) T + (k/n) U   (+ the user's offset),
    X_ffd = Σ_i C(l,i)(1−s)^(l−i) s^i  Σ_j C(m,j)(1−t)^(m−j) t^j  Σ_k C(n,k)(1−u)^(n−k) u^k  P_ijk.

Points outside 0 ≤ s, t, u ≤ 1 are not deformed. Everything is in float64 with explicit
binomial coefficients and powers (no de Casteljau, no shared code with the Rust crate).

One case follows the conventions of mathLab's PyGeM `FFD` (box_origin, box_length, a rotation
and displacements μ given in the unit-cube frame, i.e. in units of the box lengths along the
rotated box axes): the physical offset of control point (i, j, k) is R · diag(L) · μ_ijk and the
deformed point is ψ⁻¹(ψ(X) + Σ b_ijk(ψ(X)) μ_ijk) with ψ the affine map of the box to the unit
cube. PyGeM itself is not needed; the case shows how its parameters translate to a Ductile
lattice (frame S = R·(Lx,0,0), T = R·(0,Ly,0), U = R·(0,0,Lz), offsets R·diag(L)·μ).

Usage: python3 tools/reference/ffd_reference.py   (from the repository root)
"""

import json
import math
import os

import numpy as np


def lattice_coords(x, x0, s, t, u):
    d = x - x0
    tu, su, st = np.cross(t, u), np.cross(s, u), np.cross(s, t)
    return np.stack(
        [d @ tu / tu.dot(s), d @ su / su.dot(t), d @ st / st.dot(u)], axis=-1
    )


def bernstein(n, i, x):
    return math.comb(n, i) * (1.0 - x) ** (n - i) * x**i


def sederberg_parry(points, x0, s, t, u, counts, offsets):
    """`offsets[i, j, k]` is the displacement of control point (i, j, k)."""
    l, m, n = (c - 1 for c in counts)
    stu = lattice_coords(points, x0, s, t, u)
    out = points.copy()
    inside = np.all((stu >= 0.0) & (stu <= 1.0), axis=1)
    for p in np.nonzero(inside)[0]:
        a, b, c = stu[p]
        acc = np.zeros(3)
        for i in range(l + 1):
            bi = bernstein(l, i, a)
            for j in range(m + 1):
                bj = bernstein(m, j, b)
                for k in range(n + 1):
                    bk = bernstein(n, k, c)
                    pijk = x0 + (i / l) * s + (j / m) * t + (k / n) * u + offsets[i, j, k]
                    acc += bi * bj * bk * pijk
        out[p] = acc
    return out


def pygem_style(points, box_origin, box_length, rot, mu):
    """PyGeM's FFD map, written from its documented formula: ψ⁻¹(ψ(X) + Σ b μ)."""
    a = rot @ np.diag(box_length)  # columns: the box edges
    inv = np.linalg.inv(a)
    ref = (points - box_origin) @ inv.T  # ψ(X)
    out = points.copy()
    nx, ny, nz = mu.shape[:3]
    for p in range(len(points)):
        r = ref[p]
        if np.any(r < 0.0) or np.any(r > 1.0):
            continue
        shift = np.zeros(3)
        for i in range(nx):
            for j in range(ny):
                for k in range(nz):
                    w = (
                        bernstein(nx - 1, i, r[0])
                        * bernstein(ny - 1, j, r[1])
                        * bernstein(nz - 1, k, r[2])
                    )
                    shift += w * mu[i, j, k]
        out[p] = box_origin + a @ (r + shift)
    return out


def random_case(rng, name, counts, skew):
    x0 = rng.uniform(-1.0, 1.0, 3)
    s = np.array([rng.uniform(0.8, 2.0), 0.0, 0.0]) + skew * rng.normal(size=3)
    t = np.array([0.0, rng.uniform(0.8, 2.0), 0.0]) + skew * rng.normal(size=3)
    u = np.array([0.0, 0.0, rng.uniform(0.8, 2.0)]) + skew * rng.normal(size=3)
    offsets = rng.normal(scale=0.15, size=tuple(counts) + (3,))
    coords = rng.uniform(-0.15, 1.15, size=(64, 3))
    coords[:48] = rng.uniform(0.0, 1.0, size=(48, 3))
    points = x0 + coords @ np.stack([s, t, u])
    expected = sederberg_parry(points, x0, s, t, u, counts, offsets)
    return case_json(name, x0, s, t, u, counts, offsets, points, expected)


def case_json(name, x0, s, t, u, counts, offsets, points, expected):
    edits = [
        {"at": [i, j, k], "offset": offsets[i, j, k].tolist()}
        for i in range(counts[0])
        for j in range(counts[1])
        for k in range(counts[2])
    ]
    return {
        "name": name,
        "origin": x0.tolist(),
        "s": s.tolist(),
        "t": t.tolist(),
        "u": u.tolist(),
        "counts": list(counts),
        "edits": edits,
        "points": points.tolist(),
        "expected": expected.tolist(),
    }


def main():
    rng = np.random.default_rng(20261121)
    cases = [
        random_case(rng, "axis-aligned 2x2x2", (2, 2, 2), 0.0),
        random_case(rng, "skew 4x4x4", (4, 4, 4), 0.25),
        random_case(rng, "skew 3x5x2", (3, 5, 2), 0.3),
        random_case(rng, "skew 8x8x8", (8, 8, 8), 0.2),
        random_case(rng, "axis-aligned 6x3x7", (6, 3, 7), 0.0),
    ]
    # PyGeM conventions: rotation about z by 30 degrees (rot_angle = [0, 0, 30]).
    box_origin = np.array([0.2, -0.4, 0.1])
    box_length = np.array([1.5, 0.8, 1.2])
    ang = math.radians(30.0)
    rot = np.array(
        [[math.cos(ang), -math.sin(ang), 0.0], [math.sin(ang), math.cos(ang), 0.0], [0, 0, 1.0]]
    )
    mu = np.zeros((3, 3, 3, 3))
    mu[1, 1, 2] = [0.0, 0.0, 0.4]
    mu[2, 0, 1] = [0.2, -0.1, 0.0]
    mu[0, 2, 0] = [-0.1, 0.3, 0.05]
    a = rot @ np.diag(box_length)
    offsets = mu @ a.T  # physical offsets R·diag(L)·μ
    coords = rng.uniform(-0.1, 1.1, size=(48, 3))
    points = box_origin + coords @ a.T
    expected = pygem_style(points, box_origin, box_length, rot, mu)
    s, t, u = a[:, 0], a[:, 1], a[:, 2]
    # The two formulations agree (checked here in float64).
    assert np.allclose(
        expected, sederberg_parry(points, box_origin, s, t, u, (3, 3, 3), offsets), atol=1e-12
    )
    cases.append(case_json("PyGeM conventions 3x3x3", box_origin, s, t, u, (3, 3, 3), offsets, points, expected))

    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    path = os.path.join(root, "crates", "ductile-core", "tests", "data", "ffd-reference.json")
    with open(path, "w") as f:
        json.dump({"generator": "tools/reference/ffd_reference.py", "cases": cases}, f)
        f.write("\n")
    print(f"wrote {len(cases)} cases to {path}")


if __name__ == "__main__":
    main()
