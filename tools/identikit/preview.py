#!/usr/bin/env python3
"""Renders the identikit macros with the numpy FFSD port (ffsd.py) and render.py.

    pip install numpy pillow
    python3 tools/identikit/preview.py sheet docs/images/identikit-macros.png
    python3 tools/identikit/preview.py demo docs/images/identikit-demo.png
    python3 tools/identikit/preview.py macro OUT.png NAME [NAME ...]   # bigger, for checking

`sheet`: every macro at its range minimum, 0 and maximum, in the view that shows it best.
`demo`: the demo scene's settings (generate.DEMO) before/after, front and side.
"""

import os
import sys

import numpy as np
from PIL import Image, ImageDraw

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from ffsd import evaluate_stack  # noqa: E402
from generate import DEMO, layer_order, library  # noqa: E402
from landmarks import X0  # noqa: E402
from render import render  # noqa: E402

SIDE = {"nose-length", "nose-bridge", "nose-hump", "nose-tip-up", "chin-projection",
        "chin-height", "forehead-slope", "forehead-height", "brow-ridge", "mouth-protrusion",
        "eye-depth", "upper-lip", "lower-lip", "jaw-angle"}


def framing(name, macro, lm):
    """(view, centre, half-size) for a macro's preview."""
    group = macro["group"]
    if group == "Ears":
        if name.endswith("ear-protrusion"):
            return "back", (X0, 1.3, 0.0), 2.2
        return "left", (X0, 1.25, 0.0), 1.1
    if name in ("forehead-slope", "forehead-height", "brow-ridge"):
        return "side", (X0, 1.9, 1.7), 1.5
    if name in SIDE:
        return "side", (X0, 0.9, 1.9), 1.5
    if group == "Eyes":
        return "front", (X0, 1.75, 0), 0.9
    if group == "Mouth":
        return "front", (X0, 0.4, 0), 0.8
    if group == "Nose":
        return "front", (X0, 1.3, 0), 0.8
    if group == "Brows & Forehead":
        return "front", (X0, 2.2, 0), 1.3
    return "front", (X0, 0.5, 0), 1.5


def cell(p, tris, view, centre, half, size, text):
    img = Image.fromarray(render(p, tris, view, size, bounds=(np.array(centre), half)))
    ImageDraw.Draw(img).text((4, 3), text, fill=0)
    return img


def macro_cells(name, areas, macros, lm, welded, tris, size, values=None):
    m = macros[name]
    view, centre, half = framing(name, m, lm)
    values = values or (m["range"][0], 0.0, m["range"][1])
    return [cell(evaluate_stack(macros, areas, [(name, v)], welded) if v else welded, tris,
                 view, centre, half, size, f"{name} {v:+.1f}") for v in values]


def grid(cells, columns):
    w, h = cells[0].size
    rows = (len(cells) + columns - 1) // columns
    sheet = Image.new("L", (columns * w, rows * h), 255)
    for k, c in enumerate(cells):
        sheet.paste(c, ((k % columns) * w, (k // columns) * h))
    return sheet


def main():
    what, out = sys.argv[1], sys.argv[2]
    lm, areas, macros, welded, tris = library()
    if what == "sheet":
        cells = []
        for name in layer_order(macros):
            cells += macro_cells(name, areas, macros, lm, welded, tris, 180)
        grid(cells, 9).save(out, optimize=True)
    elif what == "macro":
        cells = []
        for name in sys.argv[3:]:
            cells += macro_cells(name, areas, macros, lm, welded, tris, 300)
        grid(cells, 3).save(out)
    elif what == "demo":
        settings = [(n, DEMO[n]) for n in layer_order(macros) if n in DEMO]
        after = evaluate_stack(macros, areas, settings, welded)
        cells = []
        for view, centre in [("front", (X0, 1.2, 0)), ("side", (X0, 1.2, 0.6))]:
            for p, text in [(welded, "reference"), (after, "demo suspect")]:
                cells.append(cell(p, tris, view, centre, 2.6, 360, f"{text} ({view})"))
        grid(cells, 4).save(out, optimize=True)


if __name__ == "__main__":
    main()
