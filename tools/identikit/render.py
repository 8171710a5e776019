"""A small numpy z-buffer rasteriser with Lambert shading, for identikit previews.

    python3 tools/identikit/render.py MESH OUT.png [--view front|side|...]

As a module: `render(positions, triangles, view, size)` returns an (h, w) uint8 image;
`views` names the camera frames in the head's space (see docs/identikit.md). Needs numpy
and pillow (`pip install numpy pillow`).
"""

import argparse
import sys

import numpy as np

# Camera frames as (right, up, towards the viewer) in mesh space. The head looks along +Z with
# +Y up (see docs/identikit.md), so "front" looks at it from +Z.
VIEWS = {
    "front": ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
    "side": ((0, 0, 1), (0, 1, 0), (-1, 0, 0)),       # from the head's right (−X)
    "left": ((0, 0, -1), (0, 1, 0), (1, 0, 0)),       # from the head's left (+X)
    "back": ((-1, 0, 0), (0, 1, 0), (0, 0, -1)),
    "top": ((1, 0, 0), (0, 0, -1), (0, 1, 0)),
    "bottom": ((1, 0, 0), (0, 0, 1), (0, -1, 0)),
    "three-quarter": ((0.7071, 0, 0.7071), (0, 1, 0), (-0.7071, 0, 0.7071)),
}


def frame(view):
    """The rows of the view matrix (right, up, out) for a view name, orthonormalised."""
    r, u, o = (np.array(v, np.float64) for v in VIEWS[view])
    o /= np.linalg.norm(o)
    r -= o * r.dot(o)
    r /= np.linalg.norm(r)
    u = np.cross(o, r)
    return np.stack([r, u, o])


def vertex_normals(p, tris):
    """Area-weighted vertex normals."""
    fn = np.cross(p[tris[:, 1]] - p[tris[:, 0]], p[tris[:, 2]] - p[tris[:, 0]])
    n = np.zeros_like(p)
    for k in range(3):
        np.add.at(n, tris[:, k], fn)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return n / np.maximum(length, 1e-20)


def render(p, tris, view="front", size=400, bounds=None, light=(0.3, 0.4, 1.0)):
    """Renders welded positions `p` (n, 3) with triangles `tris` (m, 3) orthographically.

    `bounds` = (centre (3,), half-size) fixes the framing so several renders line up;
    by default the mesh's bounding box is used. Returns a greyscale uint8 image.
    """
    p = np.asarray(p, np.float64)
    m = frame(view)
    q = p @ m.T
    if bounds is None:
        lo, hi = p.min(0), p.max(0)
        bounds = ((lo + hi) / 2, (hi - lo).max() / 2 * 1.05)
    centre, half = bounds
    c = np.asarray(centre) @ m.T
    scale = size / (2 * half)
    x = (q[:, 0] - c[0]) * scale + size / 2
    y = size / 2 - (q[:, 1] - c[1]) * scale
    z = q[:, 2]
    n = vertex_normals(p, tris) @ m.T
    lv = np.array(light, np.float64)
    lv /= np.linalg.norm(lv)
    shade = 0.15 + 0.85 * np.clip(n @ lv, 0, 1)
    zbuf = np.full((size, size), -np.inf)
    img = np.zeros((size, size))
    tx, ty, tz, ts = x[tris], y[tris], z[tris], shade[tris]
    area = (tx[:, 1] - tx[:, 0]) * (ty[:, 2] - ty[:, 0]) - (tx[:, 2] - tx[:, 0]) * (ty[:, 1] - ty[:, 0])
    for k in np.nonzero(np.abs(area) > 1e-12)[0]:
        x0, x1 = int(max(np.floor(tx[k].min()), 0)), int(min(np.ceil(tx[k].max()), size - 1))
        y0, y1 = int(max(np.floor(ty[k].min()), 0)), int(min(np.ceil(ty[k].max()), size - 1))
        if x0 > x1 or y0 > y1:
            continue
        gx, gy = np.meshgrid(np.arange(x0, x1 + 1) + 0.5, np.arange(y0, y1 + 1) + 0.5)
        a = tx[k], ty[k]
        w0 = ((a[0][1] - gx) * (a[1][2] - gy) - (a[0][2] - gx) * (a[1][1] - gy)) / area[k]
        w1 = ((a[0][2] - gx) * (a[1][0] - gy) - (a[0][0] - gx) * (a[1][2] - gy)) / area[k]
        w2 = 1 - w0 - w1
        inside = (w0 >= 0) & (w1 >= 0) & (w2 >= 0)
        if not inside.any():
            continue
        depth = w0 * tz[k][0] + w1 * tz[k][1] + w2 * tz[k][2]
        col = w0 * ts[k][0] + w1 * ts[k][1] + w2 * ts[k][2]
        zb = zbuf[y0:y1 + 1, x0:x1 + 1]
        im = img[y0:y1 + 1, x0:x1 + 1]
        upd = inside & (depth > zb)
        zb[upd] = depth[upd]
        im[upd] = col[upd]
    out = np.where(np.isfinite(zbuf), img * 235 + 20, 255.0)
    return np.clip(out, 0, 255).astype(np.uint8)


def main():
    sys.path.insert(0, __file__.rsplit("/", 1)[0])
    from meshio import read_glb, read_obj, weld
    from PIL import Image

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mesh")
    ap.add_argument("out")
    ap.add_argument("--view", default="front", choices=sorted(VIEWS))
    ap.add_argument("--size", type=int, default=400)
    args = ap.parse_args()
    read = read_glb if args.mesh.endswith(".glb") else read_obj
    p, t = read(args.mesh)
    w, wp = weld(p)
    Image.fromarray(render(wp, w[t], args.view, args.size)).save(args.out)


if __name__ == "__main__":
    main()
