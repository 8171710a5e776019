#!/usr/bin/env python3
"""Small numpy z-buffer renderer for checking deformations by eye.

Reads an OBJ (v/f lines) or a glTF binary (.glb, first mesh's POSITION + indices, all
primitives) and writes a flat-shaded PNG from an orthographic camera.

    python3 tools/render/render.py MESH OUT.png [--view side|front|top|iso] [--size 512]
        [--axis x0,y0,z0;x1,y1,z1;...]   # optional polyline drawn on top (mesh space)
"""
import argparse
import json
import struct

import numpy as np
from PIL import Image, ImageDraw


def load_obj(path):
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                verts.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                idx = [int(t.split("/")[0]) for t in line.split()[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                for k in range(1, len(idx) - 1):
                    faces.append([idx[0], idx[k], idx[k + 1]])
    return np.array(verts, np.float64), np.array(faces, np.int64)


COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
DTYPES = {5121: np.uint8, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}


def load_glb(path):
    data = open(path, "rb").read()
    magic, _, _ = struct.unpack_from("<III", data, 0)
    assert magic == 0x46546C67, "not a glb"
    off, doc, binary = 12, None, None
    while off < len(data):
        length, kind = struct.unpack_from("<II", data, off)
        chunk = data[off + 8 : off + 8 + length]
        if kind == 0x4E4F534A:
            doc = json.loads(chunk)
        elif kind == 0x004E4942:
            binary = chunk
        off += 8 + length

    def accessor(i):
        a = doc["accessors"][i]
        view = doc["bufferViews"][a["bufferView"]]
        start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
        n = COMPONENTS[a["type"]]
        dt = np.dtype(DTYPES[a["componentType"]])
        stride = view.get("byteStride", 0) or dt.itemsize * n
        raw = np.frombuffer(binary, np.uint8, count=stride * (a["count"] - 1) + dt.itemsize * n, offset=start)
        out = np.empty((a["count"], n), dt)
        for c in range(a["count"]):
            out[c] = np.frombuffer(raw[c * stride : c * stride + dt.itemsize * n].tobytes(), dt)
        return out

    verts, faces = [], []
    for mesh in doc["meshes"]:
        for prim in mesh["primitives"]:
            base = sum(len(v) for v in verts)
            v = accessor(prim["attributes"]["POSITION"]).astype(np.float64)
            idx = accessor(prim["indices"]).reshape(-1, 3).astype(np.int64) if "indices" in prim else np.arange(len(v)).reshape(-1, 3)
            verts.append(v)
            faces.append(idx + base)
    return np.concatenate(verts), np.concatenate(faces)


VIEWS = {
    # (right, up) axes in mesh space; the camera looks along right x up.
    "side": (np.array([0, 0, 1.0]), np.array([0, 1.0, 0])),  # viewer on -x
    "front": (np.array([1.0, 0, 0]), np.array([0, 1.0, 0])),  # viewer on +z
    "back": (np.array([-1.0, 0, 0]), np.array([0, 1.0, 0])),  # viewer on -z
    "top": (np.array([1.0, 0, 0]), np.array([0, 0, -1.0])),  # viewer on +y
    "iso": (np.array([0.7071, 0, 0.7071]), np.array([-0.4082, 0.8165, 0.4082])),
}


def render(verts, faces, view, size, bounds=None, axes=()):
    right, up = VIEWS[view]
    right = right / np.linalg.norm(right)
    up = up - right * up.dot(right)
    up = up / np.linalg.norm(up)
    fwd = np.cross(right, up)  # towards the viewer
    x, y, z = verts @ right, verts @ up, verts @ fwd
    if bounds is None:
        bounds = (x.min(), x.max(), y.min(), y.max())
    x0, x1, y0, y1 = bounds
    scale = 0.9 * size / max(x1 - x0, y1 - y0)
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    px = (x - cx) * scale + size / 2
    py = size / 2 - (y - cy) * scale
    zbuf = np.full((size, size), -np.inf)
    img = np.full((size, size, 3), 255.0)
    light = np.array([0.3, 0.5, 0.8])
    light /= np.linalg.norm(light)
    tri = verts[faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True) + 1e-20
    cam_n = np.stack([normals @ right, normals @ up, normals @ fwd], 1)
    shade = 0.25 + 0.75 * np.abs(cam_n @ light)
    for k, (a, b, c) in enumerate(faces):
        xs, ys, zs = px[[a, b, c]], py[[a, b, c]], z[[a, b, c]]
        xmin, xmax = int(max(np.floor(xs.min()), 0)), int(min(np.ceil(xs.max()), size - 1))
        ymin, ymax = int(max(np.floor(ys.min()), 0)), int(min(np.ceil(ys.max()), size - 1))
        if xmin > xmax or ymin > ymax:
            continue
        gx, gy = np.meshgrid(np.arange(xmin, xmax + 1) + 0.5, np.arange(ymin, ymax + 1) + 0.5)
        d = (ys[1] - ys[2]) * (xs[0] - xs[2]) + (xs[2] - xs[1]) * (ys[0] - ys[2])
        if abs(d) < 1e-12:
            continue
        w0 = ((ys[1] - ys[2]) * (gx - xs[2]) + (xs[2] - xs[1]) * (gy - ys[2])) / d
        w1 = ((ys[2] - ys[0]) * (gx - xs[2]) + (xs[0] - xs[2]) * (gy - ys[2])) / d
        w2 = 1 - w0 - w1
        inside = (w0 >= 0) & (w1 >= 0) & (w2 >= 0)
        if not inside.any():
            continue
        depth = w0 * zs[0] + w1 * zs[1] + w2 * zs[2]
        sub = zbuf[ymin : ymax + 1, xmin : xmax + 1]
        upd = inside & (depth > sub)
        sub[upd] = depth[upd]
        img[ymin : ymax + 1, xmin : xmax + 1][upd] = np.array([200, 170, 140]) * shade[k]
    im = Image.fromarray(img.clip(0, 255).astype(np.uint8))
    draw = ImageDraw.Draw(im)
    for pts, colour in axes:
        p = np.asarray(pts, np.float64)
        q = [((a @ right - cx) * scale + size / 2, size / 2 - (a @ up - cy) * scale) for a in p]
        draw.line(q, fill=colour, width=2)
        for u, v in q:
            draw.ellipse([u - 3, v - 3, u + 3, v + 3], outline=colour)
    return im, bounds


def parse_axis(text):
    return [[float(c) for c in p.split(",")] for p in text.split(";") if p.strip()]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("out")
    ap.add_argument("--view", default="side", choices=VIEWS)
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--bounds", help="x0,x1,y0,y1 in view coordinates (to share framing)")
    ap.add_argument("--axis", action="append", default=[], help="polyline 'x,y,z;x,y,z;...' drawn in red")
    ap.add_argument("--axis2", action="append", default=[], help="polyline drawn in blue")
    args = ap.parse_args()
    verts, faces = load_glb(args.mesh) if args.mesh.endswith(".glb") else load_obj(args.mesh)
    bounds = tuple(float(b) for b in args.bounds.split(",")) if args.bounds else None
    axes = [(parse_axis(a), (220, 30, 30)) for a in args.axis] + [(parse_axis(a), (30, 60, 220)) for a in args.axis2]
    im, b = render(verts, faces, args.view, args.size, bounds, axes)
    im.save(args.out)
    print("bounds", ",".join(f"{v:.4f}" for v in b))


if __name__ == "__main__":
    main()
