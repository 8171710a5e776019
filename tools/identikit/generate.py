#!/usr/bin/env python3
"""Generates the Ductile identikit on the Lee Perry-Smith head.

    pip install numpy
    python3 tools/identikit/generate.py            # writes scenes/identikit-{head,demo,variants}.ron
    python3 tools/identikit/generate.py --check    # also runs the numpy self-checks

Reads `assets/meshes/lee-perry-smith-head.glb`, finds the landmarks (landmarks.py), and
writes the named areas, the macro library (FFSD control points, Martínek & Kolingerová
2014) and three scenes (the last with four suspects saved as variants). The output is a pure function of the mesh: re-running it produces
byte-identical files. See docs/identikit.md for the landmarks, areas and macros.
"""

import argparse
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)

from landmarks import MIDLINE, X0, Head, mirror, q  # noqa: E402
from meshio import read_glb, weld  # noqa: E402

MESH = "assets/meshes/lee-perry-smith-head.glb"
MESH_FROM_SCENES = "../assets/meshes/lee-perry-smith-head.glb"

GROUPS = ["Chin & Jaw", "Cheeks", "Brows & Forehead", "Nose", "Mouth", "Eyes", "Ears"]

# Distance of the control point C from its reference point R in a translation point: the
# farther, the smaller γ for the same shift (γ = shift / LEVER) and the smaller the radial
# side effect γ·W/σ·(V − R) (see `shift`).
LEVER = 5.0


def unit(v):
    v = np.asarray(v, np.float64)
    return v / np.linalg.norm(v)


def pt(position, gamma, epsilon, alpha=2.0, reference=None):
    """One control point (a dict; coordinates on the scene grid)."""
    p = {"position": tuple(q(c) for c in position), "gamma": q(gamma),
         "alpha": alpha, "epsilon": q(epsilon)}
    if reference is not None:
        p["mode"] = "directional"
        p["reference"] = tuple(q(c) for c in reference)
    return p


def shift(r, direction, amount, epsilon):
    """A directional point that moves the surface around R by `amount` along û.

    With C = R + LEVER·û and γ = amount / LEVER, Eq. (4) gives
    `d(V) = γ W/σ (V − (2R − C)) = amount · W/σ · û + γ · W/σ · (V − R)`: the translation
    with a Gaussian falloff, plus a small radial expansion about R whose size is at most
    `amount/LEVER · ε · e^(−1/2)` (under 0.008 units for every macro here).
    """
    r = np.asarray(r, np.float64)
    u = unit(direction)
    return [pt(r + LEVER * u, amount / LEVER, epsilon, reference=r)]


def scale(c, factor, epsilon):
    """A radial scaling about C: `d(V) = factor · W(C, V)/σ · (V − C)` (basic mode)."""
    return [pt(c, factor, epsilon)]


def mirrored(points):
    """The mirror image of a list of points about x = X0 (exact on the scene grid)."""
    out = []
    for p in points:
        m = dict(p)
        m["position"] = mirror(p["position"])
        if "reference" in p:
            m["reference"] = mirror(p["reference"])
        out.append(m)
    return out


def both(points):
    """Left points followed by their mirror images (a bilateral macro)."""
    return points + mirrored(points)


def sphere(centre, radius):
    return {"kind": "sphere", "translation": tuple(q(c) for c in centre), "radius": q(radius)}


def box(centre, half_extents):
    return {"kind": "box", "translation": tuple(q(c) for c in centre),
            "half_extents": tuple(q(c) for c in half_extents)}


def mirror_shape(s):
    m = dict(s)
    m["translation"] = mirror(s["translation"])
    return m


def build(lm):
    """The areas and the macro library from the landmarks `lm` (left side for pairs)."""
    P = {k: np.asarray(v, np.float64) for k, v in lm.items()}
    mid = lambda *names: np.mean([P[n] for n in names], axis=0)  # noqa: E731
    on_plane = lambda p: np.array([X0, p[1], p[2]])  # noqa: E731

    # ---- Areas (left shapes; right ones are exact mirrors) ----
    a = {}
    a["nose"] = [sphere(P["nose-tip"] + [0, 0, -0.2], 0.8),
                 sphere(mid("nose-bridge", "nose-tip") + [0, 0, -0.1], 0.75)]
    a["nostrils"] = [sphere(P["nose-wing"], 0.5), mirror_shape(sphere(P["nose-wing"], 0.5))]
    a["left-eye"] = [sphere(P["eye"] + [0, 0, -0.15], 0.8)]
    a["right-eye"] = [mirror_shape(s) for s in a["left-eye"]]
    a["both-eyes"] = list(a["left-eye"] + a["right-eye"])
    a["left-brow"] = [sphere(P["brow"] + [0, 0, -0.15], 0.85)]
    a["right-brow"] = [mirror_shape(s) for s in a["left-brow"]]
    a["brows"] = list(a["left-brow"] + a["right-brow"]) + [sphere(P["glabella"], 0.7)]
    a["forehead"] = [sphere(P["forehead"] + [0, 0.3, -0.6], 1.5)]
    a["mouth"] = [sphere(P["mouth-centre"] + [0, 0, -0.2], 1.0),
                  sphere(P["mouth-corner"] + [0.1, 0, -0.2], 0.7),
                  mirror_shape(sphere(P["mouth-corner"] + [0.1, 0, -0.2], 0.7))]
    a["lips"] = [sphere(P["mouth-centre"] + [0, 0, -0.1], 0.8),
                 sphere(P["mouth-corner"], 0.55),
                 mirror_shape(sphere(P["mouth-corner"], 0.55))]
    a["chin"] = [sphere(P["chin"] + [0, -0.15, -0.35], 1.0)]
    a["jaw"] = [box((X0, -0.35, 0.9), (1.5, 1.0, 1.5))]
    a["left-cheek"] = [sphere(mid("cheekbone", "cheek") + [0, 0, -0.1], 1.0)]
    a["right-cheek"] = [mirror_shape(s) for s in a["left-cheek"]]
    a["cheeks"] = list(a["left-cheek"] + a["right-cheek"])
    # Tighter areas for the macros with small ε (less work per evaluation).
    pair = lambda c, r: [sphere(c, r), mirror_shape(sphere(c, r))]  # noqa: E731
    a["eye-corners"] = pair(P["eye-inner"], 0.3) + pair(P["eye-outer"], 0.3)
    a["nose-wings"] = pair(P["nose-wing"], 0.35)
    a["cheekbones"] = pair(P["cheekbone"], 0.6)
    a["ear-lobes"] = pair(P["ear-lobe"], 0.4)
    a["left-ear"] = [sphere(P["ear"], 1.35)]
    a["right-ear"] = [mirror_shape(s) for s in a["left-ear"]]
    a["both-ears"] = list(a["left-ear"] + a["right-ear"])

    # ---- Macros ----
    m = {}

    def macro(name, label, group, area, points, height=None, rng=(-1.0, 1.0)):
        m[name] = {"label": label, "group": group, "area": area, "points": points,
                   "height": height, "range": rng}

    lateral = (1.0, 0.0, 0.0)
    up, fwd = (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)

    # Nose.
    macro("nose-length", "Nose longer / shorter", "Nose", "nose",
          shift(P["nose-tip"], (0, -0.35, 1), 0.22, 0.24), ("Above", 0.85))
    macro("nose-size", "Nose bigger / smaller", "Nose", "nose",
          scale(on_plane(mid("nose-tip", "nose-wing") + [0, 0.1, -0.25]), 0.3, 0.3))
    macro("nose-width", "Nose wider / narrower", "Nose", "nose-wings",
          both(shift(P["nose-wing"] + [0, 0.1, 0], lateral, 0.08, 0.17)), ("Above", 0.9))
    macro("nostril-flare", "Nostrils flared / pinched", "Nose", "nostrils",
          both(shift(P["nose-wing"], (1, 0.2, -0.3), 0.06, 0.1)))
    macro("nose-bridge", "Nose bridge higher / lower", "Nose", "nose",
          shift(P["nose-bridge"], fwd, 0.1, 0.22)
          + shift(mid("nose-bridge", "nose-tip"), fwd, 0.08, 0.2), ("Above", 0.9))
    macro("nose-hump", "Nose hump / straight", "Nose", "nose",
          shift(mid("nose-bridge", "nose-tip", "nose-tip") + [0, 0, 0.02], fwd, 0.07, 0.14))
    macro("nose-tip-up", "Nose tip up / down", "Nose", "nose",
          shift(P["nose-tip"], up, 0.12, 0.2), ("Above", 0.9))
    macro("nose-bridge-width", "Nose bridge wider / narrower", "Nose", "nose-wings",
          both(shift(mid("nose-bridge", "nose-tip") + [0.15, 0, -0.08], lateral, 0.06, 0.16)))

    # Eyes.
    macro("eye-size", "Eyes bigger / smaller", "Eyes", "both-eyes",
          both(scale(P["eye"] + [0, -0.02, -0.15], 0.35, 0.28)))
    macro("eye-spacing", "Eyes wider apart / closer", "Eyes", "both-eyes",
          both(shift(P["eye"], lateral, 0.12, 0.3)), ("Above", 0.9))
    macro("eye-height", "Eyes higher / lower", "Eyes", "both-eyes",
          both(shift(P["eye"], up, 0.1, 0.3)), ("Above", 0.9))
    macro("eye-tilt", "Eyes tilted up / down at the outer corners", "Eyes", "eye-corners",
          both(shift(P["eye-outer"], up, 0.07, 0.17) + shift(P["eye-inner"], up, -0.04, 0.14)))
    macro("eye-depth", "Eyes deep-set / prominent", "Eyes", "both-eyes",
          both(shift(P["eye"], (0.1, 0, -1), 0.1, 0.28)), ("Above", 0.9))
    macro("eye-width", "Eyes longer / shorter", "Eyes", "eye-corners",
          both(shift(P["eye-outer"], lateral, 0.06, 0.14) + shift(P["eye-inner"], lateral, -0.04, 0.12)))

    # Brows & forehead.
    macro("brow-height", "Brows higher / lower", "Brows & Forehead", "brows",
          both(shift(P["brow"], up, 0.1, 0.22) + shift(P["brow-outer"], up, 0.06, 0.18)),
          ("Above", 0.9))
    macro("left-brow-height", "Left brow higher / lower", "Brows & Forehead", "left-brow",
          shift(P["brow"], up, 0.1, 0.22) + shift(P["brow-outer"], up, 0.06, 0.18),
          ("Above", 0.9))
    macro("right-brow-height", "Right brow higher / lower", "Brows & Forehead", "right-brow",
          mirrored(m["left-brow-height"]["points"]), ("Above", 0.9))
    macro("brow-ridge", "Brow ridge prominent / flat", "Brows & Forehead", "brows",
          both(shift(P["brow-inner"], fwd, 0.07, 0.2) + shift(P["brow-outer"], (0.3, 0, 1), 0.06, 0.2))
          + shift(P["glabella"], fwd, 0.06, 0.22), ("Above", 0.9))
    macro("brow-tilt", "Brows slanted up / down at the outer ends", "Brows & Forehead", "brows",
          both(shift(P["brow-outer"], up, 0.09, 0.18) + shift(P["brow-inner"], up, -0.06, 0.15)))
    macro("forehead-slope", "Forehead sloping / upright", "Brows & Forehead", "forehead",
          shift(P["forehead"] + [0, 0.35, -0.1], (0, -0.3, -1), 0.2, 0.45), ("Above", 0.9))
    macro("forehead-height", "Forehead higher / lower", "Brows & Forehead", "forehead",
          shift(P["forehead"] + [0, 0.45, -0.2], up, 0.18, 0.42), ("Above", 0.85))
    macro("forehead-width", "Temples wider / narrower", "Brows & Forehead", "forehead",
          both(shift(P["brow-outer"] + [0.35, 0.55, -0.5], (1, 0, 0.2), 0.1, 0.35)))

    # Cheeks.
    macro("cheekbones", "Cheekbones prominent / flat", "Cheeks", "cheekbones",
          both(shift(P["cheekbone"], (0.7, 0.1, 0.7), 0.1, 0.28)), ("Above", 0.9))
    macro("cheek-fullness", "Cheeks full / hollow", "Cheeks", "cheeks",
          both(shift(P["cheek"] + [0.05, 0.05, 0], (0.6, 0, 0.8), 0.12, 0.3)))
    macro("cheekbone-height", "Cheekbones higher / lower", "Cheeks", "cheekbones",
          both(shift(P["cheekbone"], up, 0.08, 0.28)), ("Above", 0.9))

    # Mouth.
    macro("mouth-width", "Mouth wider / narrower", "Mouth", "mouth",
          both(shift(P["mouth-corner"], (1, 0, -0.2), 0.09, 0.16)), ("Above", 0.9))
    macro("mouth-size", "Mouth bigger / smaller", "Mouth", "mouth",
          scale(P["mouth-centre"] + [0, 0, -0.2], 0.25, 0.35))
    macro("mouth-height", "Mouth higher / lower", "Mouth", "mouth",
          shift(P["mouth-centre"], up, 0.1, 0.33), ("Above", 0.9))
    macro("smile", "Smile / frown", "Mouth", "mouth",
          both(shift(P["mouth-corner"], (0.3, 1, -0.3), 0.1, 0.17)), ("Above", 0.9))
    macro("upper-lip", "Upper lip thicker / thinner", "Mouth", "lips",
          shift(P["upper-lip"], (0, 0.4, 1), 0.06, 0.14)
          + both(shift(P["upper-lip"] + [0.2, -0.03, -0.05], (0, 0.4, 1), 0.045, 0.12)))
    macro("lower-lip", "Lower lip thicker / thinner", "Mouth", "lips",
          shift(P["lower-lip"], (0, -0.4, 1), 0.07, 0.14)
          + both(shift(P["lower-lip"] + [0.2, 0.03, -0.05], (0, -0.4, 1), 0.05, 0.12)))
    macro("mouth-protrusion", "Lips pouting / drawn in", "Mouth", "lips",
          shift(P["mouth-centre"], fwd, 0.1, 0.28), ("Above", 0.9))

    # Chin & jaw.
    macro("chin-height", "Chin longer / shorter", "Chin & Jaw", "chin",
          shift(P["chin"] + [0, -0.1, -0.1], (0, -1, 0.2), 0.15, 0.3), ("Above", 0.9))
    macro("chin-projection", "Chin forward / receding", "Chin & Jaw", "chin",
          shift(P["chin"], fwd, 0.15, 0.3), ("Above", 0.9))
    macro("chin-width", "Chin wider / narrower", "Chin & Jaw", "chin",
          both(shift(P["chin-side"], lateral, 0.08, 0.22)))
    macro("chin-cleft", "Chin cleft / smooth", "Chin & Jaw", "chin",
          shift(P["chin"] + [0, 0.02, 0], fwd, -0.06, 0.08))
    macro("jaw-width", "Jaw wider / narrower", "Chin & Jaw", "jaw",
          both(shift(P["jaw-angle"], (1, -0.1, 0), 0.14, 0.4)), ("Above", 0.9))
    macro("jaw-angle", "Jaw angle lower / higher", "Chin & Jaw", "jaw",
          both(shift(P["jaw-angle"], (0, -1, -0.2), 0.12, 0.38)), ("Above", 0.9))

    # Ears.
    macro("ear-protrusion", "Ears protruding / flat", "Ears", "both-ears",
          both(shift(P["ear-back"], (1, 0, 0.3), 0.2, 0.3)
               + shift(P["ear-lobe"] + [0, 0.1, -0.15], (1, 0, 0.3), 0.1, 0.25)))
    macro("ear-height", "Ears higher / lower", "Ears", "both-ears",
          both(shift(P["ear"], up, 0.5, 0.4)), ("Above", 0.3))
    macro("ear-position", "Ears further back / forward", "Ears", "both-ears",
          both(shift(P["ear"], (0, 0, -1), 0.5, 0.4)), ("Above", 0.3))
    macro("left-ear-protrusion", "Left ear protruding / flat", "Ears", "left-ear",
          shift(P["ear-back"], (1, 0, 0.3), 0.2, 0.3)
          + shift(P["ear-lobe"] + [0, 0.1, -0.15], (1, 0, 0.3), 0.1, 0.25))
    macro("right-ear-protrusion", "Right ear protruding / flat", "Ears", "right-ear",
          mirrored(m["left-ear-protrusion"]["points"]))
    macro("ear-size", "Ears bigger / smaller", "Ears", "both-ears",
          both(scale(P["ear"] + [-0.15, 0, 0], 0.3, 0.45)))
    macro("ear-lobe", "Ear lobes longer / shorter", "Ears", "ear-lobes",
          both(shift(P["ear-lobe"], (0, -1, 0), 0.1, 0.16)), ("Above", 0.9))
    cover(a, m)
    return a, m


# An area must hold every vertex where its macros' weight W/σ is above exp(−COVER²/2)
# (≈ 0.004 for COVER = 3.3, with α = 2): outside it the macro would have moved a vertex by
# more than about 1e-3 units, and the area's border would show a step.
COVER = 3.3


def cover(areas, macros):
    """Adds to each macro's area a sphere of radius COVER·ε around every control point's
    centre (R, or C) that the area's shapes do not already contain."""
    for name in sorted(macros):
        shapes = areas[macros[name]["area"]]
        for p in macros[name]["points"]:
            centre = np.asarray(p.get("reference", p["position"]), np.float64)
            radius = q(COVER * p["epsilon"])
            inside = any(s["kind"] == "sphere"
                         and np.linalg.norm(centre - s["translation"]) + radius <= s["radius"]
                         for s in shapes)
            if not inside:
                shapes.append(sphere(centre, radius))


# ---- RON output ----

def fmt(x):
    """A float as RON text (always with a decimal point, never `-0.0`)."""
    x = float(x) + 0.0
    text = repr(x)
    return text if ("." in text or "e" in text) else text + ".0"


def vec(v):
    return "(" + ", ".join(fmt(c) for c in v) + ")"


def ron_shape(s):
    if s["kind"] == "sphere":
        shape = f"Sphere(radius: {fmt(s['radius'])})"
    else:
        shape = f"Box(half_extents: {vec(s['half_extents'])})"
    return f"(shape: {shape}, transform: (translation: {vec(s['translation'])}))"


def ron_point(p):
    mode = ""
    if p.get("mode") == "directional":
        mode = f"mode: Directional(reference: {vec(p['reference'])}), "
    return (f"(position: {vec(p['position'])}, {mode}gamma: {fmt(p['gamma'])}, "
            f"alpha: {fmt(p['alpha'])}, epsilon: {fmt(p['epsilon'])})")


def ron_height(h):
    if h is None:
        return "None"
    if h[0] == "Both":
        return f"Some(Both(below: {fmt(h[1])}, above: {fmt(h[2])}))"
    return f"Some({h[0]}(theta: {fmt(h[1])}))"


def layer_order(macros):
    """Macro names in stack order: by group (broad shapes first), then by name."""
    return sorted(macros, key=lambda n: (GROUPS.index(macros[n]["group"]), n))


def scene_text(areas, macros, values, title, variants=None):
    """The scene file: the head mesh with one macro layer per macro, and the library; with
    `variants` (name -> macro values), format version 2 and one variant per suspect holding
    every macro's value."""
    out = [f"// {title}", "// Generated by tools/identikit/generate.py; do not edit by hand.", "("]
    out.append(f"    version: {1 if variants is None else 2},")
    out.append("    nodes: [")
    out.append("        (")
    out.append('            name: "head",')
    out.append("            kind: Mesh((")
    out.append(f'                source: "{MESH_FROM_SCENES}",')
    out.append("                stack: [")
    order = layer_order(macros)
    for name in order:
        area = macros[name]["area"]
        out.append(f'                    (tool: "{name}", influence: Some((area: Some("{area}")))),')
    out.append("                ],")
    out.append("                areas: {")
    for name in sorted(areas):
        out.append(f'                    "{name}": Region([')
        for s in areas[name]:
            out.append(f"                        {ron_shape(s)},")
        out.append("                    ]),")
    out.append("                },")
    out.append("            )),")
    out.append("        ),")
    for name in order:
        out.append(f'        (name: "{name}", parent: Some("head"), '
                   f'kind: Macro((name: "{name}", value: {fmt(values.get(name, 0.0))}))),')
    out.append("    ],")
    out.append("    macros: {")
    for name in sorted(macros):
        m = macros[name]
        out.append(f'        "{name}": (')
        out.append(f'            label: "{m["label"]}",')
        out.append(f'            group: "{m["group"]}",')
        out.append(f'            area: Some("{m["area"]}"),')
        out.append("            points: [")
        for p in m["points"]:
            out.append(f"                {ron_point(p)},")
        out.append("            ],")
        out.append(f"            height: {ron_height(m['height'])},")
        out.append(f"            range: ({fmt(m['range'][0])}, {fmt(m['range'][1])}),")
        out.append("        ),")
    out.append("    },")
    if variants is not None:
        out.append("    variants: {")
        for vname in sorted(variants):
            out.append(f'        "{vname}": (')
            out.append("            states: {")
            for name in sorted(macros):
                out.append(f'                "{name}": (state: Macro({fmt(variants[vname].get(name, 0.0))})),')
            out.append("            },")
            out.append("        ),")
        out.append("    },")
    out.append(")")
    return "\n".join(out) + "\n"


# The demo suspect: broad jaw, long receding-ish chin, wide flat nose, thin lips, deep-set
# close eyes, heavy brows, protruding ears.
DEMO = {
    "jaw-width": 0.8, "chin-height": 0.6, "chin-projection": -0.4, "cheekbones": 0.7,
    "cheek-fullness": -0.5, "brow-ridge": 0.8, "brow-height": -0.5, "forehead-slope": 0.6,
    "nose-length": 0.7, "nose-width": 0.8, "nose-hump": 0.8, "nostril-flare": 0.5,
    "mouth-width": 0.6, "upper-lip": -0.6, "lower-lip": 0.5, "smile": -0.4,
    "eye-depth": 0.6, "eye-spacing": -0.5, "eye-tilt": -0.5, "ear-protrusion": 0.9,
    "ear-size": 0.5,
}


# Four suspects for the variants scene: A is the demo face; B narrow and delicate; C round
# and fleshy; D gaunt and angular, with a raised left brow and a protruding left ear (the
# kind of asymmetry a witness remembers).
SUSPECTS = {
    "suspect-a": DEMO,
    "suspect-b": {
        "jaw-width": -0.7, "chin-width": -0.5, "chin-projection": 0.5, "chin-height": 0.3,
        "nose-size": -0.5, "nose-tip-up": 0.7, "nose-width": -0.5, "upper-lip": 0.6,
        "lower-lip": 0.7, "mouth-size": 0.3, "eye-spacing": 0.6, "eye-size": 0.5,
        "forehead-height": 0.6, "brow-ridge": -0.5, "ear-protrusion": -0.6, "ear-size": -0.3,
    },
    "suspect-c": {
        "cheek-fullness": 0.8, "jaw-width": 0.4, "chin-width": 0.6, "nose-size": 0.6,
        "nose-bridge-width": 0.5, "nostril-flare": 0.4, "mouth-size": 0.4, "mouth-width": 0.3,
        "eye-size": -0.4, "brow-height": 0.3, "ear-lobe": 0.6, "forehead-width": 0.5,
    },
    "suspect-d": {
        "cheek-fullness": -0.8, "cheekbones": 0.9, "cheekbone-height": 0.5, "jaw-angle": 0.7,
        "nose-hump": 0.5, "nose-bridge": 0.6, "nose-length": 0.4, "eye-depth": 0.8,
        "brow-ridge": 0.6, "upper-lip": -0.5, "lower-lip": -0.4, "mouth-width": -0.3,
        "forehead-height": 0.5, "chin-projection": 0.5, "left-brow-height": 0.4,
        "left-ear-protrusion": 0.5,
    },
}


def load_head():
    positions, tris = read_glb(os.path.join(ROOT, MESH))
    mapping, welded = weld(positions)
    return welded, mapping[tris]


def library():
    welded, tris = load_head()
    lm = Head(welded).compute()
    areas, macros = build(lm)
    return lm, areas, macros, welded, tris


BORDER = 0.003


def partner(name):
    """The mirror partner's name: left-X <-> right-X, else the name itself."""
    for a, b in (("left-", "right-"), ("right-", "left-")):
        if name.startswith(a):
            return b + name[len(a):]
    return name


def mirror_invariant(items, others, mirror_item):
    """True when every item's mirror image is in `others` and vice versa."""
    key = lambda x: repr(sorted(x.items()))  # noqa: E731
    return (len(items) == len(others)
            and sorted(key(mirror_item(x)) for x in items) == sorted(key(y) for y in others))


def check_mirror(areas, macros):
    """Every macro and area is the exact mirror image of its partner (or of itself)."""
    ok = True
    for name, m in macros.items():
        other = macros[partner(name)]
        if not mirror_invariant(m["points"], other["points"], lambda p: mirrored([p])[0]):
            print(f"{name}: not the mirror image of {partner(name)}")
            ok = False
    for name, shapes in areas.items():
        if not mirror_invariant(shapes, areas[partner(name)], mirror_shape):
            print(f"area {name}: not the mirror image of {partner(name)}")
            ok = False
    return ok


def check(areas, macros, welded, tris):
    """Numpy self-checks: mirror symmetry, no step at area borders, no flipped triangles,
    a visible change at both ends of the range."""
    from ffsd import evaluate_points, region_members
    n = len(welded)
    ok = check_mirror(areas, macros)
    for name in sorted(macros):
        m = macros[name]
        members = region_members(areas[m["area"]], welded)
        inside = np.zeros(n, bool)
        inside[members] = True
        # The vertices just outside the area (a neighbour inside): there the macro, were it
        # evaluated everywhere, must move them by less than BORDER, else the cut shows.
        e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
        cut = e[inside[e[:, 0]] != inside[e[:, 1]]].ravel()
        outside = np.unique(cut[~inside[cut]])
        everything = np.arange(n)
        report = []
        for value in (m["range"][0], m["range"][1]):
            p = welded.astype(np.float64).copy()
            p[members] = evaluate_points(m["points"], m["height"], value, p, members)
            d = np.linalg.norm(p - welded, axis=1)
            full = evaluate_points(m["points"], m["height"], value, welded.astype(np.float64),
                                   everything)
            missed = np.linalg.norm(full - welded, axis=1)[outside].max() if len(outside) else 0.0
            n0 = np.cross(welded[tris[:, 1]] - welded[tris[:, 0]], welded[tris[:, 2]] - welded[tris[:, 0]])
            n1 = np.cross(p[tris[:, 1]] - p[tris[:, 0]], p[tris[:, 2]] - p[tris[:, 0]])
            flips = int(((n0 * n1).sum(1) < 0).sum())
            report.append(f"{value:+.0f}: max {d.max():.3f} cut {missed:.4f} flips {flips}")
            if missed > BORDER or flips or d.max() < 0.03:
                ok = False
                report[-1] += "  <-- PROBLEM"
        print(f"{name:20s} {len(members):5d} verts  " + " | ".join(report))
    return ok


def describe_point(p):
    kind = "directional" if p.get("mode") == "directional" else "basic"
    return kind


def print_tables(lm, areas, macros, welded):
    """Markdown tables for docs/identikit.md."""
    from ffsd import region_members
    print("| Landmark | Position (x, y, z) | Mirrored |")
    print("|---|---|---|")
    for k, v in lm.items():
        mirrored_text = "midline" if k in MIDLINE else str(mirror(v))
        print(f"| {k} | {v} | {mirrored_text} |")
    print()
    print("| Area | Shapes | Welded vertices |")
    print("|---|---|---|")
    for name in sorted(areas):
        shapes = ", ".join(f"{s['kind']} r={s['radius']} at {s['translation']}"
                           if s["kind"] == "sphere" else
                           f"box ±{s['half_extents']} at {s['translation']}"
                           for s in areas[name])
        print(f"| {name} | {shapes} | {len(region_members(areas[name], welded))} |")
    print()
    print("| Macro | Label | Group | Area | Points | ϑ |")
    print("|---|---|---|---|---|---|")
    for name in layer_order(macros):
        m = macros[name]
        pts = m["points"]
        nd = sum(1 for p in pts if p.get("mode") == "directional")
        eps = sorted({p["epsilon"] for p in pts})
        h = "–" if m["height"] is None else f"{m['height'][0]} {m['height'][1]}"
        print(f"| {name} | {m['label']} | {m['group']} | {m['area']} | "
              f"{len(pts)} ({nd} directional), ε {', '.join(map(str, eps))} | {h} |")


def main():
    ap = argparse.ArgumentParser(description="Generate the identikit scenes.")
    ap.add_argument("--check", action="store_true", help="run the numpy self-checks")
    ap.add_argument("--tables", action="store_true",
                    help="print the landmark, area and macro tables of docs/identikit.md")
    args = ap.parse_args()
    lm, areas, macros, welded, tris = library()
    if args.tables:
        print_tables(lm, areas, macros, welded)
        return
    for values in SUSPECTS.values():
        for name in values:
            assert name in macros, name
    os.makedirs(os.path.join(ROOT, "scenes"), exist_ok=True)
    for file, values, title, variants in [
        ("identikit-head.ron", {}, "Identikit: the Lee Perry-Smith head with every macro at 0.",
         None),
        ("identikit-demo.ron", DEMO, "Identikit demo: a suspect built from the macro library.",
         None),
        ("identikit-variants.ron", {},
         "Identikit variants: the reference head and four suspects saved as variants.",
         SUSPECTS),
    ]:
        with open(os.path.join(ROOT, "scenes", file), "w", newline="\n") as f:
            f.write(scene_text(areas, macros, values, title, variants))
    print(f"{len(macros)} macros, {len(areas)} areas, {len(lm)} landmarks")
    if args.check and not check(areas, macros, welded, tris):
        sys.exit(1)


if __name__ == "__main__":
    main()
