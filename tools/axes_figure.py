#!/usr/bin/env python
"""Draw the picture of the views and axes in the docs: how an exemplar lies in each view.

One asymmetric exemplar (an "F" with a bar along its first row and its first column) is
written into each visible face of a block the way the engine reads that view (front: rows y,
columns x; right: rows y, columns z; top: rows z, columns x), and the block is drawn as
``clsolid.preview.render_cube`` draws every preview, with each face and axis named.

    python tools/axes_figure.py -o docs/gallery/axes.png
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from clsolid.preview import render_cube

SIDE = 64


def letter() -> np.ndarray:
    """A SIDE x SIDE exemplar: an "F" (which shows any flip or turn), a dark bar along its
    first row and a grey one along its first column, on white."""
    img = Image.new("L", (SIDE, SIDE), 255)
    draw = ImageDraw.Draw(img)
    draw.rectangle([20, 14, 27, 50], fill=0)  # the stem
    draw.rectangle([20, 14, 46, 20], fill=0)  # the top arm
    draw.rectangle([20, 29, 40, 35], fill=0)  # the middle arm
    a = np.asarray(img).copy()
    a[:4, 4:] = 0  # row 0 .. 3: exemplar row 0 is up in every view drawn here
    a[4:, :4] = 140  # column 0 .. 3
    return a


def block(image: np.ndarray) -> np.ndarray:
    """A block whose visible faces (front z = 0, top y = 0, right x = X - 1) each show *image*
    as the engine reads that view."""
    vol = np.full((SIDE, SIDE, SIDE), 255, np.uint8)
    vol[:, :, -1] = image.T  # right: volume[:, :, x].T, rows y, columns z
    vol[:, 0, :] = image  # top: volume[:, y, :], rows z, columns x
    vol[0] = image  # front: volume[z], rows y, columns x (written last: its edges show it)
    return vol


def figure() -> Image.Image:
    """The labelled picture."""
    cube = render_cube(block(letter()), min_side=360, shade=0.0)
    h, w = cube.shape
    pad_l, pad_t, pad_r, pad_b = 120, 40, 200, 60
    canvas = Image.new("L", (w + pad_l + pad_r, h + pad_t + pad_b), 255)
    canvas.paste(Image.fromarray(cube), (pad_l, pad_t))
    draw = ImageDraw.Draw(canvas)
    try:
        font = ImageFont.load_default(size=15)
    except TypeError:  # Pillow without FreeType
        font = ImageFont.load_default()
    face = round(w / (1.0 + 0.5 * np.cos(np.radians(45.0))))  # render_cube's default depth 0.5 at 45 degrees
    x0, y0 = pad_l, pad_t + h - face  # the front face's top-left corner
    draw.text((x0 + 4, y0 + face + 8), "front: volume[z], rows y, columns x", fill=0, font=font)
    draw.text((pad_l + w + 10, y0 + face // 2), "right: volume[:, :, x].T,\nrows y, columns z", fill=0, font=font)
    draw.text((pad_l + 10, 10), "top: volume[:, y, :], rows z, columns x", fill=0, font=font)
    draw.line([(40, y0), (40, y0 + 80)], fill=0, width=2)
    draw.polygon([(35, y0 + 74), (45, y0 + 74), (40, y0 + 84)], fill=0)
    draw.text((10, y0 + 90), "y (down)", fill=0, font=font)
    draw.line([(x0, y0 + face + 34), (x0 + 80, y0 + face + 34)], fill=0, width=2)
    draw.polygon([(x0 + 76, y0 + face + 29), (x0 + 76, y0 + face + 39), (x0 + 86, y0 + face + 34)], fill=0)
    draw.text((x0 + 92, y0 + face + 26), "x", fill=0, font=font)
    draw.text((pad_l + w + 10, pad_t + 10), "z: away from the viewer,\nup and to the right", fill=0, font=font)
    return canvas


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output", type=Path, required=True, help="PNG to write")
    args = ap.parse_args(argv)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    figure().save(args.output, format="PNG")
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
