"""A labelled one-image preview of a synthesis: the exemplar beside a front, right and top slice,
and the block behind those slices drawn as a cube."""

from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from .errors import InputError
from .core.files import replaced_atomically
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
        return np.swapaxes(volume[:, :, depth], 0, 1)  # a colour's channels stay last
    return volume[:, depth, :]


def grey8(panels: list[np.ndarray]) -> list[np.ndarray]:
    """Every panel through one linear scale, the joint min to black and max to white; RGB
    panels ``(H, W, 3)`` as their colours (:func:`colour8`)."""
    if panels and panels[0].ndim == 3:
        return colour8(panels)
    lo = min(float(p.min()) for p in panels)
    hi = max(float(p.max()) for p in panels)
    half_span = hi / 2 - lo / 2  # halving first keeps the span finite for extreme floats
    out = []
    for p in panels:
        scaled = (p.astype(np.float64) / 2 - lo / 2) * (255.0 / half_span) if half_span > 0 else np.zeros(p.shape)
        out.append(np.clip(np.rint(scaled), 0, 255).astype(np.uint8))
    return out


def colour8(panels: list[np.ndarray]) -> list[np.ndarray]:
    """RGB panels as 8-bit colours: integers by their type's full range, floats by 0..1 (or
    0..their joint maximum, where that passes 1), so that a colour looks as it is, unstretched."""
    from .colour import float_top, full_scale

    top = max(float_top(p) for p in panels)
    out = []
    for p in panels:
        full = full_scale(p.dtype, top)
        out.append(np.clip(np.rint(p.astype(np.float64) * (255.0 / full)), 0, 255).astype(np.uint8))
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
    vol = _check_volume(volume)
    rgb = vol.ndim == 4  # then the exemplar is RGB too, (H, W, 3)
    if not isinstance(exemplar, np.ndarray) or exemplar.ndim != 2 + rgb or exemplar.size == 0 or (
            rgb and exemplar.shape[-1] != 3):
        shape = getattr(exemplar, "shape", type(exemplar).__name__)
        want = "an RGB (H, W, 3) array, as the volume is RGB" if rgb else "a non-empty 2D numpy array"
        raise InputError(f"exemplar must be {want}, got {shape}; pass the exemplar the volume was grown from")
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


#: Default obliqueness of :func:`render_cube`: depth drawn at half scale, at 45 degrees (cabinet).
CUBE_DEPTH, CUBE_ANGLE = 0.5, 45.0
#: Default shading of :func:`render_cube`: the top face this much lighter, the right face darker.
CUBE_SHADE = 0.2


def _cube_faces(volume: np.ndarray, corner: tuple[int, int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The visible faces of the block ``volume[z:, y:, :x + 1]``, corner ``(z, y, x)``, as the views
    orient them: front (rows y, columns x), top (rows z, columns x), right (rows y, columns z)."""
    z, y, x = corner
    block = volume[z:, y:, : x + 1]
    return view_slice(block, "front", 0), view_slice(block, "top", 0), view_slice(block, "right", x)


def _check_corner(volume: np.ndarray, corner: Any) -> tuple[int, int, int]:
    if corner is None:
        return 0, 0, volume.shape[2] - 1
    try:
        ok = len(corner) == 3 and all(not isinstance(c, bool) and isinstance(c, (int, np.integer)) and 0 <= c < n
                                      for c, n in zip(corner, volume.shape))
    except TypeError:
        ok = False
    if not ok:
        raise InputError(f"corner={corner!r} must be three voxel indices (z, y, x) inside the volume {volume.shape}")
    return int(corner[0]), int(corner[1]), int(corner[2])


def _check_cube_options(depth: Any, angle: Any, shade: Any, min_side: Any) -> None:
    ranges = (("depth", depth, lambda v: 0.0 < v <= 2.0, "in (0, 2]"),
              ("angle", angle, lambda v: 0.0 < v < 90.0, "in (0, 90) degrees"),
              ("shade", shade, lambda v: 0.0 <= v < 1.0, "in [0, 1)"))
    for name, value, inside, what in ranges:
        if not (_is_number(value) and inside(value)):
            raise InputError(f"{name}={value!r} must be a number {what}")
    if isinstance(min_side, bool) or not isinstance(min_side, (int, np.integer)) or min_side < 1:
        raise InputError(f"min_side={min_side!r} must be an integer >= 1")


def _is_number(value: Any) -> bool:
    return not isinstance(value, bool) and isinstance(value, (int, float, np.integer, np.floating)) \
        and bool(np.isfinite(value))


def _draw_cube(front: np.ndarray, top: np.ndarray, right: np.ndarray, scale: int, depth: float, angle: float,
               shade: float, edges: bool) -> np.ndarray:
    """The three uint8 faces (as :func:`_cube_faces` gives them) in an oblique projection.

    A voxel ``(z, y, x)`` of the block is drawn at ``(x + z d cos a, y - z d sin a)`` (columns
    right, rows down; d = *depth*, a = *angle*) times *scale* pixels. Each pixel samples the face
    its centre falls on, inverting that shear (nearest neighbour), so the front face is an exact
    ``scale`` x ``scale`` enlargement.
    """
    H, W = front.shape[:2]
    D = top.shape[0]
    du, dv = depth * np.cos(np.radians(angle)), depth * np.sin(np.radians(angle))
    # The front face starts on a whole pixel row, below the back edge's rise.
    rise = math.ceil(D * dv * scale)
    out = np.full((rise + H * scale + 1, math.ceil((W + D * du) * scale) + 1, *front.shape[2:]), 255, np.uint8)
    v, u = np.mgrid[: out.shape[0], : out.shape[1]]
    u = (u + 0.5) / scale
    v = (v + 0.5 - rise) / scale  # voxel units, origin at the front face's top-left corner
    lighter = np.round(top + (255.0 - top) * shade).astype(np.uint8)
    darker = np.round(right * (1.0 - shade)).astype(np.uint8)

    on = (u < W) & (v >= 0) & (v < H)
    out[on] = front[v[on].astype(int), u[on].astype(int)]
    z, x = -v / dv, u + v * du / dv  # the top face (y = 0): v = -z dv, u = x + z du
    on = (v < 0) & (z < D) & (x >= 0) & (x < W)
    out[on] = lighter[z[on].astype(int), x[on].astype(int)]
    z = (u - W) / du  # the right face (x = W): u = W + z du, v = y - z dv
    y = v + z * dv
    on = (u >= W) & (z < D) & (y >= 0) & (y < H)
    out[on] = darker[y[on].astype(int), z[on].astype(int)]

    if edges:
        back = (D * du, -D * dv)
        corners = {"tl": (0.0, 0.0), "tr": (float(W), 0.0), "br": (float(W), float(H)), "bl": (0.0, float(H))}
        far = {k: (cu + back[0], cv + back[1]) for k, (cu, cv) in corners.items()}
        segments = [(corners[a], corners[b]) for a, b in (("tl", "tr"), ("tr", "br"), ("br", "bl"), ("bl", "tl"))]
        segments += [(corners[k], far[k]) for k in ("tl", "tr", "br")]
        segments += [(far["tl"], far["tr"]), (far["tr"], far["br"])]
        for (u0, v0), (u1, v1) in segments:
            n = 2 * int(np.ceil(max(abs(u1 - u0), abs(v1 - v0)) * scale)) + 1  # half-pixel steps leave no gap
            t = np.linspace(0.0, 1.0, n)
            cols = np.clip(np.floor((u0 + t * (u1 - u0)) * scale).astype(int), 0, out.shape[1] - 1)
            rows = np.clip(np.floor((v0 + t * (v1 - v0)) * scale).astype(int) + rise, 0, out.shape[0] - 1)
            out[rows, cols] = 0
    return out


def _cube_scale(shape: tuple[int, ...], depth: float, angle: float, min_side: int) -> int:
    """The smallest integer pixels per voxel giving the drawn cube a long side >= *min_side*."""
    D, H, W = shape
    extent = max(W + D * depth * np.cos(np.radians(angle)), H + D * depth * np.sin(np.radians(angle)))
    return max(1, math.ceil(min_side / extent))


def render_cube(volume: np.ndarray, *, corner: tuple[int, int, int] | None = None,
                min_side: int = PREVIEW_MIN_SIDE, depth: float = CUBE_DEPTH, angle: float = CUBE_ANGLE,
                shade: float = CUBE_SHADE, edges: bool = True) -> np.ndarray:
    """The volume drawn as a cube: its front, top and right faces in an oblique projection.

    Parameters
    ----------
    volume : numpy.ndarray
        ``(Z, Y, X)`` volume, grey levels or phase labels of any real dtype, or an RGB one
        ``(Z, Y, X, 3)`` (then drawn in its colours, :func:`colour8`).
    corner : (int, int, int) or None
        ``(z, y, x)``: draw the block ``volume[z:, y:, :x + 1]``, whose visible faces are the
        slices ``volume[z]``, ``volume[:, y, :]`` and ``volume[:, :, x]``. None: the whole
        volume, faces ``volume[0]``, ``volume[:, 0, :]`` and ``volume[:, :, -1]``.
    min_side : int, default PREVIEW_MIN_SIDE
        Smallest long side of the image; voxels are enlarged by the smallest integer factor
        that reaches it.
    depth : float, default 0.5
        Drawn length of a voxel along z, in voxels (0.5: a cabinet projection), in (0, 2].
    angle : float, default 45.0
        Angle of the z axis above the horizontal, degrees, in (0, 90).
    shade : float, default 0.2
        The top face is blended this far towards white and the right face towards black, so
        that the edges read; 0 draws the faces' grey levels as they are.
    edges : bool, default True
        Draw the cube's nine visible edges in black, one pixel wide.

    Returns
    -------
    numpy.ndarray
        2D uint8 grey image on a white background (``(H, W, 3)`` for an RGB volume). The
        faces share one linear grey scale, their joint minimum black and maximum white.

    Notes
    -----
    The viewer looks along +z from above and to the right, as the views are oriented: the
    front face shows rows y (down) and columns x (right) as the front slice does; the top
    face ``y = 0`` recedes up and to the right with z; the right face ``x = X - 1`` shows
    rows y and, receding to the right, z, as the right slice does. Each pixel samples the
    face its centre falls on (nearest neighbour).
    """
    vol = _check_volume(volume)
    if vol.dtype.kind == "f" and not np.isfinite(vol).all():
        raise InputError("volume contains NaN or infinite values; replace them before drawing")
    c = _check_corner(vol, corner)
    _check_cube_options(depth, angle, shade, min_side)
    faces = grey8(list(_cube_faces(vol, c)))
    block = (vol.shape[0] - c[0], vol.shape[1] - c[1], c[2] + 1)
    return _draw_cube(*faces, _cube_scale(block, depth, angle, min_side), float(depth), float(angle),
                      float(shade), bool(edges))


@dataclass
class Preview:
    """A rendered preview: the grey image, each panel's box ``(x, y, width, height)`` and caption."""

    image: np.ndarray
    boxes: list[tuple[int, int, int, int]]
    captions: list[str]


def render_preview(exemplar: np.ndarray | dict[str, np.ndarray], volume: np.ndarray, *, depths: dict[str, int] | None = None,
                   constrained: Sequence[str] = ("front", "right"), name: str = "exemplar",
                   min_side: int = PREVIEW_MIN_SIDE, cube: bool = True) -> Preview:
    """Lay out the labelled preview of :func:`save_preview` without writing it.

    *name* starts the exemplar's caption; *min_side* is the smallest long side of a panel;
    *cube* adds the last panel, :func:`render_cube` of the block behind the three slices.
    """
    given = exemplar if isinstance(exemplar, dict) else {"": exemplar}
    raw, captions = [], []
    for view, image in given.items():  # one exemplar, or each view's
        ex, vol = _check_inputs(image, volume)
        raw.append(ex)
        captions.append(f"{view + ' ' if view else ''}{name} {ex.shape[0]}x{ex.shape[1]}")
    chosen = _depths(vol, depths)
    for view, axis in DEPTH_AXIS.items():
        raw.append(view_slice(vol, view, chosen[view]))
        mark = ", constrained" if view in constrained else ""
        captions.append(f"{view} {_AXIS_LETTER[axis]}={chosen[view]}{mark}")
    # The cube's faces are the slices shown (cut to the block), so they need no grey scale of their own.
    corner = (chosen["front"], chosen["top"], chosen["right"])
    scaled = grey8(raw + list(_cube_faces(vol, corner)) if cube else raw)
    panels = [enlarge(panel, min_side) for panel in scaled[: len(raw)]]
    if cube:
        block = (vol.shape[0] - corner[0], vol.shape[1] - corner[1], corner[2] + 1)
        scale = _cube_scale(block, CUBE_DEPTH, CUBE_ANGLE, min_side)
        panels.append(_draw_cube(*scaled[len(raw):], scale, CUBE_DEPTH, CUBE_ANGLE, CUBE_SHADE, True))
        captions.append(f"block z>={corner[0]} y>={corner[1]} x<={corner[2]}")
    font = _font()
    measure = ImageDraw.Draw(Image.new("L", (1, 1)))
    widths = [max(panel.shape[1], int(measure.textlength(c, font=font)) + 4) for panel, c in zip(panels, captions)]
    height = CAPTION_HEIGHT + max(panel.shape[0] for panel in panels) + PREVIEW_GAP
    rgb = vol.ndim == 4
    white, black = ((255, 255, 255), (0, 0, 0)) if rgb else (255, 0)
    canvas = Image.new("RGB" if rgb else "L", (sum(widths) + PREVIEW_GAP * (len(panels) + 1), height), white)
    draw = ImageDraw.Draw(canvas)
    boxes, x = [], PREVIEW_GAP
    for panel, caption, width in zip(panels, captions, widths):
        draw.text((x, 4), caption, fill=black, font=font)
        canvas.paste(Image.fromarray(np.ascontiguousarray(panel)), (x, CAPTION_HEIGHT))
        boxes.append((x, CAPTION_HEIGHT, panel.shape[1], panel.shape[0]))
        x += width + PREVIEW_GAP
    return Preview(np.asarray(canvas), boxes, captions)


def save_preview(path: PathLike, exemplar: np.ndarray | dict[str, np.ndarray], volume: np.ndarray, *,
                 depths: dict[str, int] | None = None,
                 constrained: Sequence[str] = ("front", "right")) -> pathlib.Path:
    """Save the exemplar beside a front, right and top slice of the volume, and the block
    behind those slices drawn as a cube, as one labelled PNG.

    Parameters
    ----------
    path : str or os.PathLike
        Output ``.png`` file; parent directories are created, an existing file is replaced.
    exemplar : numpy.ndarray or dict
        2D exemplar, in the same units as the volume; or one per view, ``{view: exemplar}``
        (each then has its own panel).
    volume : numpy.ndarray
        ``(Z, Y, X)`` volume, or ``(Z, Y, X, 3)`` RGB (the exemplar then RGB too: the
        panels show their colours, :func:`colour8`).
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
    Panels, left to right: the exemplar (or each view's), ``volume[z]`` (rows y, columns x),
    ``volume[:, :, x].T`` (rows y, columns z) and ``volume[:, y, :]`` (rows z,
    columns x), all through one grey scale (the joint minimum black, maximum white).
    Each is enlarged by an integer nearest-neighbour factor to a long side of at least
    :data:`PREVIEW_MIN_SIDE` pixels, under a caption naming it and its slice index. The
    last panel is :func:`render_cube` of the block ``volume[z:, y:, :x + 1]`` at those
    slices' indices: its front, top and right faces are (the block's part of) the three
    slices, in the same grey scale, with the top face lighter and the right face darker.
    """
    p = _as_path(path, "path")
    _suffix(p, "path", (".png",))
    preview = render_preview(exemplar, volume, depths=depths, constrained=constrained)
    p.parent.mkdir(parents=True, exist_ok=True)
    with replaced_atomically(p) as tmp:  # a failed write leaves no partial PNG
        Image.fromarray(preview.image).save(tmp, format="PNG")
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
    with replaced_atomically(p) as tmp:
        Image.fromarray(image).save(tmp, format="PNG")
    return p
