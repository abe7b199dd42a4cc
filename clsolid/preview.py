"""A labelled one-image preview of a synthesis: the exemplar beside a front, right and top slice."""

from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from .errors import InputError
from .core.views import DEPTH_AXIS
from .volumeio import PathLike, _as_path, _check_volume, _suffix

#: Smallest long side, in pixels, of every preview panel (small blocks are enlarged).
PREVIEW_MIN_SIDE = 256
#: White space, in pixels, between and around panels.
PREVIEW_GAP = 8
#: Height of the caption strip above the panels.
CAPTION_HEIGHT = 24
_FONT_SIZE = 15
_AXIS_LETTER = "zyx"


def view_slice(volume: np.ndarray, view: str, depth: int) -> np.ndarray:
    """One slice as the metrics see it: front (y, x), right (y, z), top (z, x)."""
    if view == "front":
        return volume[depth]
    if view == "right":
        return volume[:, :, depth].T
    return volume[:, depth, :]


def grey8(panels: list[np.ndarray]) -> list[np.ndarray]:
    """Every panel through one linear scale, the joint min to black and max to white."""
    lo = min(float(p.min()) for p in panels)
    hi = max(float(p.max()) for p in panels)
    half_span = hi / 2 - lo / 2  # halving first keeps the span finite for extreme floats
    out = []
    for p in panels:
        scaled = (p.astype(np.float64) / 2 - lo / 2) * (255.0 / half_span) if half_span > 0 else np.zeros(p.shape)
        out.append(np.clip(np.rint(scaled), 0, 255).astype(np.uint8))
    return out


def enlarge(panel: np.ndarray, min_side: int = PREVIEW_MIN_SIDE) -> np.ndarray:
    """Nearest-neighbour enlargement by the smallest integer factor giving a long side >= *min_side*."""
    k = max(1, math.ceil(min_side / max(panel.shape)))
    return np.repeat(np.repeat(panel, k, axis=0), k, axis=1)


def _font() -> Any:
    try:
        return ImageFont.load_default(size=_FONT_SIZE)
    except (TypeError, OSError):  # Pillow without FreeType: the fixed bitmap font
        return ImageFont.load_default()


def _check_inputs(exemplar: Any, volume: Any) -> tuple[np.ndarray, np.ndarray]:
    if not isinstance(exemplar, np.ndarray) or exemplar.ndim != 2 or exemplar.size == 0:
        shape = getattr(exemplar, "shape", type(exemplar).__name__)
        raise InputError(f"exemplar must be a non-empty 2D numpy array, got {shape}; pass the 2D exemplar")
    vol = _check_volume(volume)
    for name, arr in (("exemplar", exemplar), ("volume", vol)):
        if arr.dtype.kind not in "biuf":
            raise InputError(f"{name} has unsupported dtype {arr.dtype}; use an integer or float array")
        if arr.dtype.kind == "f" and not np.isfinite(arr).all():
            raise InputError(f"{name} contains NaN or infinite values; replace them before previewing")
    return exemplar, vol


def _depths(volume: np.ndarray, depths: dict[str, int] | None) -> dict[str, int]:
    out = {view: volume.shape[axis] // 2 for view, axis in DEPTH_AXIS.items()}
    for view, depth in (depths or {}).items():
        if view not in out:
            raise InputError(f"depths has an unknown view {view!r}; use front, right or top")
        size = volume.shape[DEPTH_AXIS[view]]
        if isinstance(depth, bool) or not isinstance(depth, (int, np.integer)) or not 0 <= depth < size:
            raise InputError(f"depths[{view!r}]={depth!r} must be an integer in [0, {size})")
        out[view] = int(depth)
    return out


@dataclass
class Preview:
    """A rendered preview: the grey image, each panel's box ``(x, y, width, height)`` and caption."""

    image: np.ndarray
    boxes: list[tuple[int, int, int, int]]
    captions: list[str]


def render_preview(exemplar: np.ndarray, volume: np.ndarray, *, depths: dict[str, int] | None = None,
                   constrained: Sequence[str] = ("front", "right"), name: str = "exemplar",
                   min_side: int = PREVIEW_MIN_SIDE) -> Preview:
    """Lay out the labelled preview of :func:`save_preview` without writing it.

    *name* starts the exemplar's caption; *min_side* is the smallest long side of a panel.
    """
    ex, vol = _check_inputs(exemplar, volume)
    chosen = _depths(vol, depths)
    captions = [f"{name} {ex.shape[0]}x{ex.shape[1]}"]
    raw = [ex]
    for view, axis in DEPTH_AXIS.items():
        raw.append(view_slice(vol, view, chosen[view]))
        mark = ", constrained" if view in constrained else ""
        captions.append(f"{view} {_AXIS_LETTER[axis]}={chosen[view]}{mark}")
    panels = [enlarge(panel, min_side) for panel in grey8(raw)]
    font = _font()
    measure = ImageDraw.Draw(Image.new("L", (1, 1)))
    widths = [max(panel.shape[1], int(measure.textlength(c, font=font)) + 4) for panel, c in zip(panels, captions)]
    height = CAPTION_HEIGHT + max(panel.shape[0] for panel in panels) + PREVIEW_GAP
    canvas = Image.new("L", (sum(widths) + PREVIEW_GAP * (len(panels) + 1), height), 255)
    draw = ImageDraw.Draw(canvas)
    boxes, x = [], PREVIEW_GAP
    for panel, caption, width in zip(panels, captions, widths):
        draw.text((x, 4), caption, fill=0, font=font)
        canvas.paste(Image.fromarray(np.ascontiguousarray(panel)), (x, CAPTION_HEIGHT))
        boxes.append((x, CAPTION_HEIGHT, panel.shape[1], panel.shape[0]))
        x += width + PREVIEW_GAP
    return Preview(np.asarray(canvas), boxes, captions)


def save_preview(path: PathLike, exemplar: np.ndarray, volume: np.ndarray, *,
                 depths: dict[str, int] | None = None,
                 constrained: Sequence[str] = ("front", "right")) -> pathlib.Path:
    """Save the exemplar beside a front, right and top slice of the volume as one labelled PNG.

    Parameters
    ----------
    path : str or os.PathLike
        Output ``.png`` file; parent directories are created, an existing file is replaced.
    exemplar : numpy.ndarray
        2D exemplar, in the same units as the volume.
    volume : numpy.ndarray
        ``(Z, Y, X)`` volume.
    depths : dict, optional
        Slice index per view (``front``: z, ``right``: x, ``top``: y); default the middle.
    constrained : sequence of str
        Views the synthesis constrained; their captions say so.

    Returns
    -------
    pathlib.Path
        The path written.

    Notes
    -----
    Panels, left to right: the exemplar, ``volume[z]`` (rows y, columns x),
    ``volume[:, :, x].T`` (rows y, columns z) and ``volume[:, y, :]`` (rows z,
    columns x), all through one grey scale (the joint minimum black, maximum white).
    Each is enlarged by an integer nearest-neighbour factor to a long side of at least
    :data:`PREVIEW_MIN_SIDE` pixels, under a caption naming it and its slice index.
    """
    p = _as_path(path, "path")
    _suffix(p, "path", (".png",))
    preview = render_preview(exemplar, volume, depths=depths, constrained=constrained)
    p.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(preview.image).save(p, format="PNG")
    return p


#: Colours of the position-histogram map: valid pixels no voxel used, and pixels that are no
#: site (no complete neighbourhood).
UNUSED_RGB = (220, 30, 30)
NO_SITE_RGB = (40, 60, 140)


def render_site_map(use: np.ndarray, min_side: int = PREVIEW_MIN_SIDE) -> np.ndarray:
    """The position histogram as an RGB image (thesis: how often each exemplar pixel is used).

    Used pixels are grey, white for the most used, on a square-root scale (so that
    pixels used a few times stay visible); valid pixels no voxel used are red
    (:data:`UNUSED_RGB`); pixels with no complete neighbourhood, which cannot be matched,
    dark blue (:data:`NO_SITE_RGB`). Enlarged by an integer factor to a side of at least
    *min_side*.
    """
    use = np.asarray(use)
    if use.ndim != 2 or use.size == 0 or not np.issubdtype(use.dtype, np.integer) or use.min() < -1:
        raise InputError("use must be a non-empty 2D integer array of counts, -1 for no site "
                         f"(SynthesisResult.site_use); got {use.dtype} {use.shape}")
    top = max(1, int(use.max()))
    grey = np.round(255 * np.sqrt(np.maximum(use, 0) / top)).astype(np.uint8)
    rgb = np.repeat(grey[..., None], 3, axis=2)
    rgb[use == 0] = UNUSED_RGB
    rgb[use == -1] = NO_SITE_RGB
    return enlarge(rgb, min_side)


def save_site_map(path: PathLike, use: np.ndarray) -> pathlib.Path:
    """Save :func:`render_site_map` of a position histogram as a PNG; returns the path."""
    p = _as_path(path, "path")
    _suffix(p, "path", (".png",))
    image = render_site_map(use)
    p.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(image).save(p, format="PNG")
    return p
