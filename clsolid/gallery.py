"""A gallery of exemplars for judging a synthesis method on many kinds of texture.

Every exemplar is made by code from a fixed seed, or taken from the images bundled in
scikit-image's wheel, so the gallery needs no download. Each stands for a kind of
material (see :func:`gallery_info`): binary porous media, sparse inclusions, particulate
composites, thin networks, channels, lamellae, lattice fringes and natural grey textures.

Conventions
-----------
* **Values.** Every exemplar is a ``uint8`` image. A categorical exemplar of n phases
  holds exactly the values ``round(255 i / (n - 1))``, i = 0 .. n - 1 (0/255 when binary,
  0/128/255 for three phases, 0/85/170/255 for four), so it displays as it is and keeps
  its phases under any uniform quantisation. A grey exemplar uses the 0..255 range.
* **Sizes.** ``size`` is the side of the square image, 64 to 256 (the gallery is meant
  at 64 and 128). Every size shows the *same field of view* of the same material at a
  different resolution, as :func:`clsolid.exemplar.builtin_exemplar` does for brick,
  grass and gravel: features are measured in fractions of the field, so they are twice
  as many pixels wide at 128 as at 64. The generated exemplars are defined in continuous
  coordinates (pixel ``(i, j)`` samples the point ``(i / size, j / size)`` of the unit
  square), so the 128 image is the 64 one sampled twice as finely, not a new draw.
  At 64 the features are sized for a 9 x 9 window: pores, particles and grains are a few
  pixels to about 15 pixels wide, fringes repeat every 3.5 pixels, lamellae every 7.
* **Determinism.** Each generated exemplar draws from ``numpy.random.default_rng(seed)``
  with the entry's own fixed ``seed``; the result depends on nothing else. The generated
  images are periodic (they tile), which the synthesis does not need but does not mind.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .errors import InputError
from .exemplar import _area_downscale, _check_int, builtin_exemplar

#: Smallest and largest ``size`` :func:`gallery_exemplar` accepts.
MIN_SIZE, MAX_SIZE = 64, 256
#: The sizes the gallery is meant at (and tested at).
SIZES = (64, 128)
#: Side of the frequency lattice random fields are drawn on (integer cycles per field,
#: -32 .. 31): any ``size >= 64`` samples the same continuous field.
_LATTICE = 64


@dataclass(frozen=True)
class GalleryEntry:
    """What one gallery exemplar is and stands for.

    Attributes
    ----------
    name : str
        Its name in the gallery.
    kind : {"categorical", "grey", "colour"}
        ``"categorical"``: a few phases, each one grey value (see :attr:`phases`);
        ``"grey"``: a continuous grey-level image; ``"colour"``: an RGB photograph
        (:func:`colour_names`).
    description : str
        One line: the material it stands for and what to look for.
    phases : tuple of (int, str)
        For a categorical exemplar, each phase's grey value and what it is, darkest
        first; empty for a grey one.
    seed : int or None
        Seed of the generator; None for an image taken from scikit-image.
    source : str
        How it is made.
    views : {3, 2}
        The views the material calls for: 3 where every section looks alike, 2 for a layered
        or directional one, whose top view should differ (docs/design.md#three-views).
    """

    name: str
    kind: str
    description: str
    phases: tuple[tuple[int, str], ...] = ()
    seed: int | None = None
    source: str = ""
    _make: Callable[[int, np.random.Generator | None], np.ndarray] | None = field(
        default=None, repr=False, compare=False)
    views: int = 3

    @property
    def phase_values(self) -> tuple[int, ...]:
        """The grey values of the phases, darkest first (empty for a grey exemplar)."""
        return tuple(v for v, _ in self.phases)


# --------------------------------------------------------------------------- helpers


def _grid(size: int) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates ``(y, x)`` in the unit square of every pixel: pixel (i, j) is (i, j) / size."""
    c = np.arange(size) / size
    return c[:, None], c[None, :]


def _wrap(d: np.ndarray) -> np.ndarray:
    """Periodic difference in the unit square, in [-0.5, 0.5)."""
    return (d + 0.5) % 1.0 - 0.5


def _random_field(rng: np.random.Generator, size: int,
                  envelope: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> np.ndarray:
    """A periodic Gaussian random field on the unit square, sampled at ``size`` x ``size``.

    Complex Gaussian coefficients are drawn on the integer frequencies -32 .. 31 (cycles
    per field) and shaped by ``envelope(fy, fx)``; the field is the real part of their
    Fourier series. Every size draws the same coefficients, so it samples the same field.
    The result is standardised (mean 0, standard deviation 1).
    """
    f = np.fft.fftfreq(_LATTICE, 1.0 / _LATTICE)
    fy, fx = f[:, None], f[None, :]
    coef = (rng.standard_normal((_LATTICE, _LATTICE)) + 1j * rng.standard_normal((_LATTICE, _LATTICE)))
    return _series(coef * envelope(fy, fx), size)


def _series(coef: np.ndarray, size: int) -> np.ndarray:
    """Real part of the Fourier series with lattice coefficients ``coef``, standardised."""
    f = np.fft.fftfreq(_LATTICE, 1.0 / _LATTICE).astype(int)
    grid = np.zeros((size, size), dtype=np.complex128)
    grid[np.ix_(f % size, f % size)] = coef
    out = np.fft.ifft2(grid).real
    return (out - out.mean()) / out.std()


def _gaussian(sigma_y: float, sigma_x: float | None = None) -> Callable:
    """Gaussian low-pass spectral envelope (standard deviations in cycles per field)."""
    sigma_x = sigma_y if sigma_x is None else sigma_x
    return lambda fy, fx: np.exp(-0.5 * ((fy / sigma_y) ** 2 + (fx / sigma_x) ** 2))


def _threshold(values: np.ndarray, fraction: float) -> np.ndarray:
    """True on the ``fraction`` of pixels with the lowest values (exact up to ties)."""
    return values <= np.quantile(values, fraction)


def _phase_image(labels: np.ndarray, n: int) -> np.ndarray:
    """Phase indices 0 .. n-1 as the gallery's grey values ``round(255 i / (n - 1))``."""
    return np.round(np.arange(n) * 255.0 / (n - 1)).astype(np.uint8)[labels]


def _place(rng: np.random.Generator, radii: np.ndarray, gap: float,
           placed: list[tuple[float, float, float]] | None = None,
           tries: int = 200) -> list[tuple[float, float, float]]:
    """Random sequential addition of non-overlapping discs in the periodic unit square.

    Each disc of radius ``radii[k]`` gets up to ``tries`` uniform positions; it is kept
    at the first one at least ``gap`` away from every disc already placed (``placed``
    included), and dropped if none is. Returns the new discs as ``(y, x, r)``.
    """
    placed = list(placed or [])
    new = []
    for r in radii:
        for _ in range(tries):
            y, x = rng.random(2)
            if all(np.hypot(_wrap(y - py), _wrap(x - px)) >= r + pr + gap for py, px, pr in placed):
                placed.append((y, x, r))
                new.append((y, x, r))
                break
    return new


def _ellipses(size: int, shapes: list[tuple[float, float, float, float, float]]) -> np.ndarray:
    """Mask of periodic ellipses ``(y, x, a, b, angle)``: semi-axes a (along angle) and b."""
    gy, gx = _grid(size)
    mask = np.zeros((size, size), bool)
    for y, x, a, b, t in shapes:
        dy, dx = _wrap(gy - y), _wrap(gx - x)
        u = dx * np.cos(t) + dy * np.sin(t)
        v = -dx * np.sin(t) + dy * np.cos(t)
        mask |= (u / a) ** 2 + (v / b) ** 2 <= 1.0
    return mask


def _discs(size: int, discs: list[tuple[float, float, float]]) -> np.ndarray:
    return _ellipses(size, [(y, x, r, r, 0.0) for y, x, r in discs])


def _voronoi_boundaries(rng: np.random.Generator, size: int, n_cells: int, width: np.ndarray | float,
                        warp: float) -> np.ndarray:
    """Mask of the boundaries of a periodic Voronoi tessellation of ``n_cells`` random seeds.

    A pixel is on a boundary when its distance to the bisector of its two nearest seeds
    is below ``width / 2`` (field units; an array varies it from pixel to pixel). The
    pixel positions are first displaced by a smooth random field of amplitude ``warp``,
    which bends the boundaries.
    """
    seeds = rng.random((n_cells, 2))
    gy, gx = _grid(size)
    wy = warp * _random_field(rng, size, _gaussian(2.0))
    wx = warp * _random_field(rng, size, _gaussian(2.0))
    py, px = gy + wy, gx + wx
    d2 = np.stack([_wrap(py - sy) ** 2 + _wrap(px - sx) ** 2 for sy, sx in seeds])
    order = np.argsort(d2, axis=0)
    first, second = order[0], order[1]
    d1 = np.take_along_axis(d2, order[:1], 0)[0]
    d2nd = np.take_along_axis(d2, order[1:2], 0)[0]
    # Distance from the point to the bisector of seeds a, b: (|p-b|^2 - |p-a|^2) / (2 |a-b|).
    sep = np.hypot(_wrap(seeds[first, 0] - seeds[second, 0]), _wrap(seeds[first, 1] - seeds[second, 1]))
    return (d2nd - d1) / (2.0 * sep) < np.asarray(width) / 2.0


# --------------------------------------------------------------------------- generators


def _porous50(size: int, rng: np.random.Generator) -> np.ndarray:
    field_ = _random_field(rng, size, _gaussian(3.5))
    return _phase_image((~_threshold(field_, 0.5)).astype(int), 2)


def _porous80(size: int, rng: np.random.Generator) -> np.ndarray:
    # Boolean model: overlapping discs (pores) of radius 2..5 px at 64, 20 % expected.
    radii = rng.uniform(2.0, 5.0, size=400) / 64.0
    n = int(round(-np.log(0.8) / (np.pi * np.mean(radii ** 2))))
    centres = rng.random((n, 2))
    pores = _discs(size, [(y, x, r) for (y, x), r in zip(centres, radii[:n])])
    return _phase_image((~pores).astype(int), 2)


def _inclusions(size: int, rng: np.random.Generator) -> np.ndarray:
    shapes = []
    for y, x, r in _place(rng, rng.uniform(1.8, 3.0, size=8) / 64.0, gap=4.0 / 64.0):
        aspect = rng.uniform(1.0, 1.8)
        shapes.append((y, x, r, r / aspect, rng.uniform(0.0, np.pi)))
    return _phase_image(_ellipses(size, shapes).astype(int), 2)


def _composite3(size: int, rng: np.random.Generator) -> np.ndarray:
    big = _place(rng, rng.uniform(4.0, 6.0, size=14) / 64.0, gap=1.5 / 64.0)
    small = _place(rng, rng.uniform(1.5, 2.5, size=45) / 64.0, gap=1.5 / 64.0, placed=big)
    labels = np.zeros((size, size), int)
    labels[_discs(size, big)] = 1
    # The small particles are angular: squares inscribed in their discs, at random angles.
    gy, gx = _grid(size)
    for y, x, r in small:
        t = rng.uniform(0.0, np.pi / 2)
        dy, dx = _wrap(gy - y), _wrap(gx - x)
        u, v = dx * np.cos(t) + dy * np.sin(t), -dx * np.sin(t) + dy * np.cos(t)
        labels[np.maximum(np.abs(u), np.abs(v)) <= r / np.sqrt(2.0)] = 2
    return _phase_image(labels, 3)


def _composite4(size: int, rng: np.random.Generator) -> np.ndarray:
    big = _place(rng, rng.uniform(4.0, 5.5, size=10) / 64.0, gap=1.5 / 64.0)
    rods = []
    for y, x, a in _place(rng, np.full(10, 6.0 / 64.0), gap=1.0 / 64.0, placed=big):
        rods.append((y, x, a, a / 4.0, rng.uniform(0.0, np.pi)))
    small = _place(rng, rng.uniform(1.3, 2.0, size=50) / 64.0, gap=1.5 / 64.0,
                   placed=big + [(y, x, a) for y, x, a, _, _ in rods])
    labels = np.zeros((size, size), int)
    labels[_discs(size, big)] = 1
    labels[_ellipses(size, rods)] = 2
    labels[_discs(size, small)] = 3
    return _phase_image(labels, 4)


def _fibres(size: int, rng: np.random.Generator) -> np.ndarray:
    radii = rng.normal(3.5, 0.3, size=200) / 64.0
    return _phase_image(_discs(size, _place(rng, radii, gap=0.6 / 64.0, tries=60)).astype(int), 2)


def _grains(size: int, rng: np.random.Generator) -> np.ndarray:
    boundaries = _voronoi_boundaries(rng, size, 24, 1.3 / 64.0, warp=0.01)
    return _phase_image((~boundaries).astype(int), 2)


def _cracks(size: int, rng: np.random.Generator) -> np.ndarray:
    width = (1.6 + 0.5 * _random_field(rng, size, _gaussian(3.0))) / 64.0
    cracks = _voronoi_boundaries(rng, size, 9, np.clip(width, 0.7 / 64.0, None), warp=0.035)
    return _phase_image((~cracks).astype(int), 2)


def _channels(size: int, rng: np.random.Generator) -> np.ndarray:
    # Band-pass across the channels (about 8 per field), low-pass along them.
    field_ = _random_field(rng, size, lambda fy, fx: np.exp(-0.5 * (((np.abs(fy) - 8.0) / 3.0) ** 2
                                                                    + (fx / 0.7) ** 2)))
    return _phase_image((~_threshold(field_, 0.3)).astype(int), 2)


def _lamellae(size: int, rng: np.random.Generator) -> np.ndarray:
    """Swift-Hohenberg stripes ``u_t = r u - (1 + lap/k0^2)^2 u - u^3``, thresholded at 0."""
    f = np.fft.fftfreq(_LATTICE, 1.0 / _LATTICE)
    k2 = f[:, None] ** 2 + f[None, :] ** 2
    f0 = _LATTICE / 7.0  # period 7 px at 64
    linear = 0.3 - (1.0 - k2 / f0**2) ** 2
    u = np.fft.ifft2(np.fft.fft2(0.1 * rng.standard_normal((_LATTICE, _LATTICE)))).real
    dt = 0.5
    for _ in range(400):  # semi-implicit Euler on the 64-lattice; converges to curved stripes
        u_hat = (np.fft.fft2(u) - dt * np.fft.fft2(u**3)) / (1.0 - dt * linear)
        u = np.fft.ifft2(u_hat).real
    coef = np.fft.fft2(u)
    coef[np.abs(np.fft.fftfreq(_LATTICE, 1.0 / _LATTICE)) == _LATTICE // 2, :] = 0  # drop the Nyquist
    coef[:, np.abs(np.fft.fftfreq(_LATTICE, 1.0 / _LATTICE)) == _LATTICE // 2] = 0
    return _phase_image((_series(coef, size) > 0).astype(int), 2)


def _hrtem(size: int, rng: np.random.Generator) -> np.ndarray:
    """Stacks of bent fringes at random orientations over band-limited noise.

    Each pixel shows the stack whose envelope is strongest there, so stacks meet
    without moire; where every envelope is weak, only the noise (amorphous carbon) shows.
    """
    gy, gx = _grid(size)
    freq = 64.0 / 3.5  # fringes every 3.5 px at 64
    best = np.zeros((size, size))
    signal = np.zeros((size, size))
    for _ in range(60):
        y, x = rng.random(2)
        half_len, half_wid = rng.uniform(0.06, 0.16), rng.uniform(0.04, 0.08)
        t, bend, phase = rng.uniform(0.0, np.pi), rng.uniform(-5.0, 5.0), rng.uniform(0.0, 2 * np.pi)
        dy, dx = _wrap(gy - y), _wrap(gx - x)
        u = dx * np.cos(t) + dy * np.sin(t)      # along the fringes
        v = -dx * np.sin(t) + dy * np.cos(t)     # across them
        envelope = np.exp(-((u / half_len) ** 4) - ((v / half_wid) ** 4))
        stronger = envelope > best
        best[stronger] = envelope[stronger]
        signal[stronger] = (envelope * np.cos(2 * np.pi * freq * (v + bend * u**2) + phase))[stronger]
    noise = _random_field(rng, size, _gaussian(12.0))
    grey = 128.0 - 70.0 * signal + 16.0 * noise
    return grey_levels(grey)


def grey_levels(values: np.ndarray) -> np.ndarray:
    """*values* (grey, on 0..255) rounded to uint8 as every grey gallery exemplar is."""
    return np.clip(np.round(values), 0, 255).astype(np.uint8)


def _skimage_texture(name: str) -> Callable[[int, np.random.Generator | None], np.ndarray]:
    def make(size: int, rng: np.random.Generator | None) -> np.ndarray:
        return grey_levels(builtin_exemplar(name, size=size))
    return make


#: The tissue exemplar's quarter of scikit-image's 512^2 IHC image: rows 256-512, columns 128-384.
_TISSUE_CROP = (slice(256, 512), slice(128, 384))


def _tissue_grey() -> np.ndarray:
    """The whole 512^2 IHC image in grey (luminance on 0..255), float64."""
    import skimage.color
    import skimage.data

    return skimage.color.rgb2gray(skimage.data.immunohistochemistry()) * 255.0


def _tissue(size: int, rng: np.random.Generator | None) -> np.ndarray:
    grey = _tissue_grey()[_TISSUE_CROP]
    return grey_levels(_area_downscale(grey, size))


#: The colour exemplars' fields: (scikit-image image, rows, columns), each a square of
#: texture-like material, area-averaged to ``size`` (at most the field's side).
_COLOUR_FIELDS = {
    "wood": ("coffee", slice(320, 400), slice(0, 80)),
    "tabletop": ("coffee", slice(0, 128), slice(472, 600)),
    "fur": ("chelsea", slice(0, 80), slice(190, 270)),
    "stained": ("immunohistochemistry", *_TISSUE_CROP),  # the tissue exemplar's field, in colour
}


def _colour_photo(name: str) -> Callable[[int, np.random.Generator | None], np.ndarray]:
    def make(size: int, rng: np.random.Generator | None) -> np.ndarray:
        import skimage.data

        image, rows, cols = _COLOUR_FIELDS[name]
        field = getattr(skimage.data, image)()[rows, cols].astype(np.float64)
        if size > field.shape[0]:
            raise InputError(f"the colour exemplar {name!r} is a {field.shape[0]}² field of its photograph: "
                             f"size={size} would enlarge it; use size <= {field.shape[0]}")
        return grey_levels(np.stack([_area_downscale(field[..., c], size) for c in range(3)], axis=-1))
    return make


# --------------------------------------------------------------------------- registry

_BINARY_PORE = ((0, "pore"), (255, "solid"))
_ENTRIES = (
    GalleryEntry("porous50", "categorical",
                 "bicontinuous porous medium, 50 % pores (sandstone, sintered or spinodal structure)",
                 _BINARY_PORE, 101, "thresholded Gaussian random field at its median", _porous50),
    GalleryEntry("porous80", "categorical",
                 "about 80 % solid and 20 % pores of overlapping discs (porous ceramic, foam)",
                 _BINARY_PORE, 102, "Boolean model of discs, radius 2-5 px at 64", _porous80),
    GalleryEntry("inclusions", "categorical",
                 "sparse inclusions, about 3 % (precipitates, voids or second-phase particles in a matrix)",
                 ((0, "matrix"), (255, "inclusion")), 103,
                 "non-overlapping small ellipses, radius 1.8-3 px at 64", _inclusions),
    GalleryEntry("composite3", "categorical",
                 "3-phase particulate composite: round and angular particles in a matrix (concrete, cermet)",
                 ((0, "matrix"), (128, "round particle"), (255, "angular particle")), 104,
                 "non-overlapping discs and rotated squares", _composite3),
    GalleryEntry("composite4", "categorical",
                 "4-phase composite: large grains, rods and fine particles in a matrix (battery electrode)",
                 ((0, "matrix"), (85, "large grain"), (170, "rod"), (255, "fine particle")), 105,
                 "non-overlapping discs, 4:1 ellipses and small discs", _composite4),
    GalleryEntry("fibres", "categorical",
                 "densely packed fibre cross-sections, about 45 % (unidirectional fibre composite)",
                 ((0, "polymer"), (255, "fibre")), 106,
                 "random sequential addition of discs, radius 3.5 px at 64", _fibres, views=2),
    GalleryEntry("grains", "categorical",
                 "thin connected network of grain boundaries (etched polycrystal)",
                 ((0, "grain boundary"), (255, "grain")), 107,
                 "boundaries of a slightly warped Voronoi tessellation, about 1.3 px wide at 64", _grains),
    GalleryEntry("cracks", "categorical",
                 "connected network of wavy cracks of varying width around large cells (dried mud, glaze)",
                 ((0, "crack"), (255, "solid")), 108,
                 "boundaries of a strongly warped Voronoi tessellation, width 0.7-2.5 px at 64", _cracks),
    GalleryEntry("channels", "categorical",
                 "long anisotropic channels along x, 30 % (wood vessels, directionally frozen porosity)",
                 ((0, "channel"), (255, "solid")), 109,
                 "Gaussian random field, band-pass along y (about 8 per field), low-pass along x, thresholded",
                 _channels, views=2),
    GalleryEntry("lamellae", "categorical",
                 "fingerprint-like curved lamellae with defects (block copolymer, lamellar eutectic)",
                 ((0, "phase A"), (255, "phase B")), 110,
                 "Swift-Hohenberg stripes, period 7 px at 64, thresholded at 0", _lamellae, views=2),
    GalleryEntry("hrtem", "grey",
                 "HRTEM of disordered carbon: stacks of bent, broken lattice fringes at random orientations",
                 (), 111, "fringes every 3.5 px at 64 in bent stacks, over band-limited noise", _hrtem, views=2),
    GalleryEntry("brick", "grey", "brick wall (scikit-image texture, CC0): a regular grid of blocks and joints",
                 (), None, "skimage.data.brick(), top-left 256^2 area-averaged", _skimage_texture("brick"), views=2),
    GalleryEntry("grass", "grey", "grass (scikit-image texture, CC0): thin oriented blades, random",
                 (), None, "skimage.data.grass(), top-left 256^2 area-averaged", _skimage_texture("grass"), views=2),
    GalleryEntry("gravel", "grey", "gravel (scikit-image texture, CC0): packed stones with shading",
                 (), None, "skimage.data.gravel(), top-left 256^2 area-averaged", _skimage_texture("gravel")),
    GalleryEntry("tissue", "grey",
                 "stained colon tissue in grey (scikit-image IHC image): stroma with nuclei around a gland",
                 (), None, "skimage.data.immunohistochemistry(), rows 256-512 and columns 128-384, "
                           "luminance, area-averaged", _tissue),
)
#: The colour gallery: RGB photographs bundled with scikit-image (coffee and chelsea CC0, the
#: IHC image without known copyright restrictions, as scikit-image's data notes say).
_COLOUR_ENTRIES = (
    GalleryEntry("wood", "colour", "scratched light wood (scikit-image coffee, CC0): short streaks, a few knots",
                 (), None, "skimage.data.coffee(), rows 320-400, columns 0-80", _colour_photo("wood")),
    GalleryEntry("tabletop", "colour", "warm wood of a table top (scikit-image coffee, CC0): faint grain, shading",
                 (), None, "skimage.data.coffee(), rows 0-128, columns 472-600", _colour_photo("tabletop")),
    GalleryEntry("fur", "colour", "a cat's forehead fur (scikit-image chelsea, CC0): short tabby hairs and stripes",
                 (), None, "skimage.data.chelsea(), rows 0-80, columns 190-270", _colour_photo("fur")),
    GalleryEntry("stained", "colour",
                 "stained colon tissue (scikit-image IHC image): blue nuclei, brown stain, pale stroma",
                 (), None, "skimage.data.immunohistochemistry(), rows 256-512 and columns 128-384, area-averaged",
                 _colour_photo("stained")),
)
_REGISTRY = {e.name: e for e in _ENTRIES + _COLOUR_ENTRIES}


def gallery_names() -> tuple[str, ...]:
    """Names of the gallery's grey and segmented exemplars, in the order the gallery lists
    them (the colour ones: :func:`colour_names`)."""
    return tuple(e.name for e in _ENTRIES)


def colour_names() -> tuple[str, ...]:
    """Names of the colour gallery's RGB exemplars (at 64, and up to the side of each one's
    field of its photograph)."""
    return tuple(e.name for e in _COLOUR_ENTRIES)


def gallery_info(name: str) -> GalleryEntry:
    """What the exemplar ``name`` is: kind, phases, one-line description, seed and source.

    Raises
    ------
    InputError
        ``name`` is not in the gallery.
    """
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise InputError(f"{name!r} is not a gallery exemplar; use one of {', '.join(_REGISTRY)}") from None


def gallery_exemplar(name: str, size: int = 64) -> np.ndarray:
    """One exemplar of the gallery, as a ``(size, size)`` uint8 image.

    Parameters
    ----------
    name : str
        One of :func:`gallery_names`.
    size : int, default 64
        Side of the image, 64 to 256. Every size shows the same field of view of the same
        material (features grow with ``size``; see the module's notes).

    Returns
    -------
    numpy.ndarray
        ``(size, size)`` uint8. A categorical exemplar holds exactly its phase values
        (:attr:`GalleryEntry.phase_values`); a grey one spans 0..255; a colour one is
        ``(size, size, 3)``. The same name and size always give the same image.

    Raises
    ------
    InputError
        Unknown ``name``, or ``size`` out of range (a colour one's: above its field).
    """
    entry = gallery_info(name)
    size = _check_int(size, "size", MIN_SIZE, MAX_SIZE, f"the gallery is meant at sizes {SIZES}")
    rng = None if entry.seed is None else np.random.default_rng(entry.seed)
    return entry._make(size, rng)


def gallery_photograph(name: str, size: int = 64) -> np.ndarray:
    """The whole photograph a photographed exemplar was cut from, at that exemplar's scale.

    brick, grass and gravel are the top-left 256^2 quarter of a 512^2 scikit-image
    photograph, tissue another 256^2 quarter of one; each is area-averaged to ``size``.
    The whole photograph averaged alike is ``2 size`` square and holds more of the same
    wall, lawn or tissue: its windows show what the material itself scores
    (``tools/photo_windows.py``), the level a synthesis cannot be asked to beat.

    Parameters
    ----------
    name : {"brick", "grass", "gravel", "tissue"}
        A photographed exemplar (``gallery_info(name).seed`` is None).
    size : int, default 64
        The exemplar's side, as for :func:`gallery_exemplar`.

    Returns
    -------
    numpy.ndarray
        ``(2 size, 2 size)`` float64 on 0..255, not rounded; the exemplar, before its
        rounding to uint8, is one quarter of it (top-left for the textures, rows ``size``
        to ``2 size`` and columns ``size / 2`` to ``3 size / 2`` for tissue).

    Raises
    ------
    InputError
        Unknown or generated ``name``, or ``size`` out of range.
    """
    entry = gallery_info(name)
    if entry.seed is not None:
        raise InputError(f"{name!r} is generated, not photographed; gallery_draw gives new pieces of it")
    size = _check_int(size, "size", MIN_SIZE, MAX_SIZE, f"the gallery is meant at sizes {SIZES}")
    if name == "tissue":
        return _area_downscale(_tissue_grey(), 2 * size)
    return builtin_exemplar(name, size=2 * size, region=512)


def gallery_draw(name: str, size: int = 64, draw: int = 1) -> np.ndarray:
    """Another sample of a generated exemplar's material: the same generator, drawn anew.

    A volume's slices should look like new pieces of the material, not like the exemplar
    itself; where the generator is known, new draws show what such pieces score
    (``tools/photo_windows.py``), the level a synthesis cannot be asked to beat.

    Parameters
    ----------
    name : str
        A generated exemplar (``gallery_info(name).seed`` is not None); the photographs
        (brick, grass, gravel, tissue) have no generator.
    size : int, default 64
        As for :func:`gallery_exemplar` (the same field of view, the same feature sizes).
    draw : int, default 1
        Which draw, 1 or more: the generator seeded with ``(seed, draw)``.

    Returns
    -------
    numpy.ndarray
        ``(size, size)`` uint8, as :func:`gallery_exemplar` gives, of another draw.

    Raises
    ------
    InputError
        Unknown or photographed ``name``, ``size`` out of range or ``draw`` below 1.
    """
    entry = gallery_info(name)
    if entry.seed is None:
        raise InputError(f"{name!r} is a photograph ({entry.source}): it has no generator to draw again; "
                         "tools/photo_windows.py takes windows of the whole photograph instead")
    size = _check_int(size, "size", MIN_SIZE, MAX_SIZE, f"the gallery is meant at sizes {SIZES}")
    draw = _check_int(draw, "draw", 1, 2**31 - 1, "draw 1 or more (the exemplar itself is gallery_exemplar)")
    return entry._make(size, np.random.default_rng([entry.seed, draw]))
