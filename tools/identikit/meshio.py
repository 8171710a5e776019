"""Small mesh readers for the identikit tools: binary glTF (.glb) and Wavefront OBJ.

Only what the identikit needs: positions and triangle indices of the first primitive of the
first mesh, read with `struct`/`json` + numpy, and welding of seam copies by exact position
(the same rule as `ductile_core::mesh::Topology::weld`).
"""

import json
import struct

import numpy as np

_COMPONENT = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16,
              5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


def read_glb(path):
    """Returns (positions float32 (n, 3), indices uint32 (m, 3)) of the first primitive."""
    data = open(path, "rb").read()
    magic, _version, _length = struct.unpack_from("<III", data, 0)
    if magic != 0x46546C67:
        raise ValueError(f"{path}: not a binary glTF file")
    offset, doc, binary = 12, None, None
    while offset < len(data):
        chunk_len, chunk_type = struct.unpack_from("<II", data, offset)
        body = data[offset + 8: offset + 8 + chunk_len]
        if chunk_type == 0x4E4F534A:
            doc = json.loads(body)
        elif chunk_type == 0x004E4942:
            binary = body
        offset += 8 + chunk_len

    def accessor(i):
        acc = doc["accessors"][i]
        view = doc["bufferViews"][acc["bufferView"]]
        dtype = np.dtype(_COMPONENT[acc["componentType"]])
        width = _WIDTH[acc["type"]]
        start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
        stride = view.get("byteStride", dtype.itemsize * width)
        rows = [np.frombuffer(binary, dtype, width, start + k * stride)
                for k in range(acc["count"])] if stride != dtype.itemsize * width else None
        if rows is not None:
            return np.array(rows)
        return np.frombuffer(binary, dtype, acc["count"] * width, start).reshape(-1, width)

    prim = doc["meshes"][0]["primitives"][0]
    positions = accessor(prim["attributes"]["POSITION"]).astype(np.float32)
    indices = accessor(prim["indices"]).astype(np.uint32).reshape(-1, 3)
    return positions, indices


def read_obj(path):
    """Returns (positions float32 (n, 3), indices uint32 (m, 3)); polygons are fanned."""
    positions, faces = [], []
    for line in open(path):
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            positions.append([float(x) for x in parts[1:4]])
        elif parts[0] == "f":
            idx = [int(p.split("/")[0]) for p in parts[1:]]
            idx = [i - 1 if i > 0 else len(positions) + i for i in idx]
            for k in range(1, len(idx) - 1):
                faces.append([idx[0], idx[k], idx[k + 1]])
    return np.array(positions, np.float32), np.array(faces, np.uint32)


def weld(positions):
    """Welds stored vertices with bit-identical positions.

    Returns (weld (n,) stored -> welded, welded positions (w, 3)); welded vertices are
    numbered in order of first appearance, as in `Topology::weld`.
    """
    keys = {}
    mapping = np.empty(len(positions), np.int64)
    first = []
    for i, p in enumerate(positions):
        k = p.tobytes()
        j = keys.get(k)
        if j is None:
            j = len(first)
            keys[k] = j
            first.append(i)
        mapping[i] = j
    return mapping, positions[np.array(first)]
