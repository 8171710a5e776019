"""Limb lengths in a baked glTF animation (morph targets and a weights animation), for the
character artist's story: the exported file is read with the standard library only (JSON
chunk, binary chunk, dense and sparse accessors) and the mesh rebuilt at a sampled time."""
import json
import math
import re
import struct

COMPONENTS = {"SCALAR": 1, "VEC3": 3}
FORMATS = {5126: ("f", 4), 5123: ("H", 2), 5125: ("I", 4), 5121: ("B", 1)}


def read_glb(path):
    data = open(path, "rb").read()
    n = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + n])
    at = 20 + n
    m = struct.unpack_from("<I", data, at)[0]
    return doc, data[at + 8:at + 8 + m]


def view_values(doc, binary, view, offset, count, fmt, size, width):
    v = doc["bufferViews"][view]
    start = v.get("byteOffset", 0) + offset
    stride = v.get("byteStride", size * width)
    return [struct.unpack_from("<" + fmt * width, binary, start + i * stride)
            for i in range(count)]


def accessor(doc, binary, index):
    """The accessor's elements as tuples (dense or sparse)."""
    a = doc["accessors"][index]
    fmt, size = FORMATS[a["componentType"]]
    width = COMPONENTS[a["type"]]
    if "bufferView" in a:
        out = view_values(doc, binary, a["bufferView"], a.get("byteOffset", 0), a["count"],
                          fmt, size, width)
    else:
        out = [(0.0,) * width] * a["count"]
    sparse = a.get("sparse")
    if sparse:
        out = list(out)
        ifmt, isize = FORMATS[sparse["indices"]["componentType"]]
        idx = view_values(doc, binary, sparse["indices"]["bufferView"],
                          sparse["indices"].get("byteOffset", 0), sparse["count"], ifmt, isize, 1)
        val = view_values(doc, binary, sparse["values"]["bufferView"],
                          sparse["values"].get("byteOffset", 0), sparse["count"], fmt, size, width)
        for (i,), v in zip(idx, val):
            out[i] = v
    return out


def positions_at(path, time):
    """The first mesh's positions at `time` (a sampled key time) of the weights animation."""
    doc, binary = read_glb(path)
    prim = doc["meshes"][0]["primitives"][0]
    base = accessor(doc, binary, prim["attributes"]["POSITION"])
    targets = [accessor(doc, binary, t["POSITION"]) for t in prim.get("targets", [])]
    sampler = doc["animations"][0]["samplers"][0]
    times = [t for (t,) in accessor(doc, binary, sampler["input"])]
    weights = [w for (w,) in accessor(doc, binary, sampler["output"])]
    k = min(range(len(times)), key=lambda i: abs(times[i] - time))
    w = weights[k * len(targets):(k + 1) * len(targets)]
    out = [list(p) for p in base]
    for wt, target in zip(w, targets):
        if wt != 0.0:
            for i, d in enumerate(target):
                if d != (0.0, 0.0, 0.0):
                    out[i][0] += wt * d[0]
                    out[i][1] += wt * d[1]
                    out[i][2] += wt * d[2]
    return base, out


def reference_points(scene_text):
    """The points of the first `reference: Points([...])` of a saved scene."""
    block = scene_text.split("reference: Points([", 1)[1].split("])", 1)[0]
    return [tuple(float(x) for x in m.groups())
            for m in re.finditer(r"\(([-\d.e]+), ([-\d.e]+), ([-\d.e]+)\)", block)]


def limb_lengths(glb, scene_text, times):
    """Shoulder-elbow-wrist length (vertices nearest the bend's reference start, middle and
    end) at each of `times`."""
    ref = reference_points(scene_text)
    base, _ = positions_at(glb, 0.0)
    picks = [min(range(len(base)), key=lambda i: math.dist(base[i], p))
             for p in (ref[0], ref[len(ref) // 2], ref[-1])]
    out = []
    for t in times:
        _, pos = positions_at(glb, t)
        a, b, c = (pos[i] for i in picks)
        out.append(math.dist(a, b) + math.dist(b, c))
    return out
