"""What both back ends of the ML method share at one scale: geometry, exemplar tables, bandwidth.

Everything here is plain NumPy and is computed once per scale. The Parzen estimate of
Urs thesis, §4.2.2 (Urs et al., TIP 2014, eqs. 3-9) for voxel s, view v and label lambda is

    f_v(lambda) = sum_p exp(-[(lambda - c_p)^2 + A_p] / 2h^2),
    A_p = sum_r ((1 - t_r) (x_r - y_{p,r}))^2,

over every exemplar site p whose k x k window lies inside the exemplar, with c_p the
site's centre value and y_{p,r} its neighbour r. The constant 1/(n h^d) cancels in
every heuristic and is dropped. With ``distance="mismatch"`` every squared difference
(a - b)^2 above is [a != b] instead, with ``"weighted"`` [a != b] (c_a + c_b)
(:func:`difference`, :func:`phase_costs`), and the bandwidth is taken in those units
(:func:`phase_sigma`). A fall-off weighs each term (:func:`falloff_weights`), the terms along an axis two
views share another weight (:func:`direction_weights`, :func:`term_weights`); with
``parent_weight`` > 0 the sum over r also runs over the coarser scale's 3 x 3 around the
parent, at t = 0, each term times that weight (:func:`parent_tables`, :func:`parent_block`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..exemplar import pooled
from ..phases import phase_costs
from .params import VIEW_AXES, MLParams
from ..core.schedule import colour_set, colour_sets, set_count


def view_offsets(view: str, half: int) -> np.ndarray:
    """``(R, 3)`` (dz, dy, dx) offsets of the neighbours of a voxel in *view*, centre excluded.

    Row r pairs with the exemplar offset (dr, dc) enumerated row-major, so the r-th
    neighbour of a voxel is compared with the r-th neighbour of an exemplar site.
    """
    row_axis, col_axis = VIEW_AXES[view]
    out = []
    for dr in range(-half, half + 1):
        for dc in range(-half, half + 1):
            if dr or dc:
                off = [0, 0, 0]
                off[row_axis], off[col_axis] = dr, dc
                out.append(off)
    return np.array(out, dtype=np.int32)


def wrapped_coords(voxels: np.ndarray, shape, offsets: np.ndarray) -> np.ndarray:
    """Flat indices of ``voxels + offsets`` on the torus: returns an ``(m, R)`` array.

    Each axis has few distinct offsets: they are wrapped once per voxel, then gathered."""
    stride = (shape[1] * shape[2], shape[2], 1)
    flat = np.zeros((np.size(voxels), offsets.shape[0]), np.int64)
    for axis, c in enumerate(np.unravel_index(voxels, shape)):
        values, which = np.unique(offsets[:, axis], return_inverse=True)
        flat += (((c[:, None] + values) % shape[axis]) * stride[axis])[:, which.ravel()]
    return flat


def parent_offsets(view: str) -> np.ndarray:
    """``(9, 3)`` offsets of a voxel's parent square in *view*: the coarser scale's 3 x 3 around
    its parent, row-major, read from the parent block (:func:`parent_block`), where the coarser
    voxel s // 2 + d lies at s + 2 d."""
    return 2 * np.insert(view_offsets(view, 1), 4, 0, axis=0)  # the 3 x 3 window, its centre put back


def parent_block(coarse: np.ndarray, shape: tuple[int, int, int], out: np.ndarray | None = None) -> np.ndarray:
    """The coarser scale's volume repeated twice along each axis and cut to this scale's
    *shape* (float32, as the state; into *out*, such as a scratch file's, if given): the
    block the parent terms read (:func:`parent_offsets`)."""
    out = np.empty(shape, np.float32) if out is None else out
    for dz, dy, dx in np.ndindex(2, 2, 2):  # eight strided copies: no repeated block in memory
        part = out[dz::2, dy::2, dx::2]
        part[...] = coarse[: part.shape[0], : part.shape[1], : part.shape[2]]
    return out


def parent_tables(coarse_exemplar: np.ndarray, shape: tuple[int, int], half: int) -> np.ndarray:
    """``(9, n)``: the parent square of every valid site (as :func:`exemplar_tables` orders
    them) of an exemplar of *shape* whose coarser scale is *coarse_exemplar*: the coarser
    exemplar at (the site's centre // 2) + d, as a voxel's (:func:`parent_offsets`). Where that
    leaves the coarser exemplar (windows narrower than 5, at the edge) its edge pixel stands in."""
    rows = np.arange(half, shape[0] - half) // 2
    cols = np.arange(half, shape[1] - half) // 2
    out = []
    for dr in (-1, 0, 1):
        r = np.clip(rows + dr, 0, coarse_exemplar.shape[0] - 1)
        for dc in (-1, 0, 1):
            c = np.clip(cols + dc, 0, coarse_exemplar.shape[1] - 1)
            out.append(coarse_exemplar[np.ix_(r, c)].ravel())
    return np.array(out, np.float64)


def exemplar_tables(exemplar: np.ndarray, half: int) -> tuple[np.ndarray, np.ndarray]:
    """Centre values ``(n,)`` and neighbour values ``(R, n)`` of every valid exemplar site.

    Valid sites are those whose window lies inside the exemplar (no wrap-around, Urs thesis, eq. 4.5);
    they are enumerated row-major by window position.
    """
    k = 2 * half + 1
    h, w = exemplar.shape
    windows = np.lib.stride_tricks.sliding_window_view(exemplar, (k, k))  # (h-k+1, w-k+1, k, k)
    flat = windows.reshape(-1, k * k).astype(np.float64)
    centre = k * k // 2
    return flat[:, centre].copy(), np.delete(flat, centre, axis=1).T.copy()


def difference(a: np.ndarray, b: np.ndarray, mismatch: bool, costs: np.ndarray | None = None,
               palette: np.ndarray | None = None) -> np.ndarray:
    """The per-value distance of the Parzen estimate, float64: ``(a - b)^2``, or ``[a != b]``
    with *mismatch*, or with *costs* (labels 0..L-1) ``[a != b] (costs[a] + costs[b])``, or
    with a colour *palette* ``(L, C)`` (labels 0..L-1) the squared distance between the two
    labels' colours ``|palette[a] - palette[b]|^2`` (broadcast like ``a - b``)."""
    if palette is not None and not mismatch:
        pa = palette[np.asarray(a).astype(np.intp)]
        pb = palette[np.asarray(b).astype(np.intp)]
        return np.sum((pa - pb) ** 2, axis=-1)
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    if costs is not None:
        c = np.asarray(costs, np.float64)
        return np.where(a != b, c[a.astype(np.intp)] + c[b.astype(np.intp)], 0.0)
    return (a != b).astype(np.float64) if mismatch else (a - b) ** 2


def phase_sigma(image: np.ndarray, costs: np.ndarray | None = None) -> float:
    """The standard deviation that plays sigma's part for mismatch counts: ``sqrt(m / 2)``,
    m the mean distance between two pixels drawn at random (plain mismatches: 1 - sum_i f_i^2,
    the chance that they differ; f_i the label fractions), as 2 sigma^2 is the mean squared
    difference of two grey levels. On two labels 0 and 1 it is their standard deviation, so
    both distances give the same bandwidth; with *costs* (:func:`phase_costs`) the weighted one."""
    values, counts = np.unique(image, return_counts=True)
    f = counts / image.size
    if costs is None:
        return float(np.sqrt((1.0 - np.sum(f * f)) / 2.0))
    d = difference(values[:, None], values[None, :], True, costs)
    return float(np.sqrt(f @ d @ f / 2.0))


def falloff_weights(offsets: np.ndarray, sigma: float) -> np.ndarray | None:
    """``(R,)`` weight of each neighbour of a view's *offsets* ``(R, 3)``: a Gaussian of its
    distance from the centre with this *sigma* (pixels), scaled to a mean of 1 so that the
    distances, and with them Silverman's bandwidth, keep their size; None for sigma 0. A sigma
    so small that every weight underflows gives the limit: the nearest neighbours alone."""
    if not sigma:
        return None
    d2 = np.sum(offsets.astype(np.float64) ** 2, axis=1)
    with np.errstate(divide="ignore", under="ignore"):
        g = np.exp(-d2 / (2.0 * sigma**2))
    if not g.sum() > 0:
        g = (d2 == d2.min()).astype(np.float64)
    return g / g.mean()


def shared_terms(offsets: np.ndarray) -> np.ndarray:
    """``(R,)`` whether each term of the first view's window, in *offsets* ``(V, R, 3)``, is a
    voxel that another view's window holds too: the line along the axis two views share (y
    for front and right; with three views every view's centre row and column). Each view's
    terms pair alike (row-major (dr, dc)), so the same terms are shared in every view."""
    others = {tuple(o) for v in offsets[1:] for o in v}
    return np.array([tuple(o) in others for o in offsets[0]], dtype=bool)


def shared_axes(offsets: np.ndarray) -> list[int]:
    """The volume axes that two or more views' windows, *offsets* ``(V, R, 3)``, run along
    (y for front and right; every axis with three views)."""
    return [a for a in range(3) if np.sum(np.any(offsets[:, :, a] != 0, axis=1)) >= 2]


def direction_weights(offsets: np.ndarray, shared: float) -> np.ndarray:
    """``(R,)`` weight of each term of a view's window by its direction: ``1 - (1 - shared)
    cos^2(theta)``, theta the angle between its offset and an axis another view's window
    runs along too (a product over such axes of the view). A term on that axis weighs
    *shared*, one across it 1, and one between them in between: near that axis the two
    views' windows say nearly the same (a feature's neighbours straight above and just
    beside it differ little), so that direction would count about twice. Every view's
    terms pair alike (row-major (dr, dc)), so one vector serves them all."""
    axes, weights = shared_axes(offsets), []
    for view in offsets:
        o = view.astype(np.float64)
        length2 = np.sum(o**2, axis=1)
        w = np.ones(o.shape[0])
        for axis in axes:
            w *= 1.0 - (1.0 - shared) * o[:, axis] ** 2 / length2
        weights.append(w)
    if not all(np.allclose(w, weights[0]) for w in weights[1:]):  # VIEW_AXES keeps front, right, top alike
        raise InputError("shared_weight < 1 weighs the views' windows differently for this pair of views (their "
                         "shared axis runs along rows in one and columns in the other), and the kernels hold "
                         "one weight table: leave shared_weight at 1 for these views")
    return weights[0]


def term_weights(offsets: np.ndarray, sigma: float, shared: float, profile: str = "direction") -> np.ndarray | None:
    """``(R,)`` weight of each window term: the fall-off's (:func:`falloff_weights`), times,
    for *shared* < 1, its direction's (*profile* ``"direction"``: :func:`direction_weights`) or
    *shared* on the terms another view's window holds too (``"line"``: :func:`shared_terms`),
    scaled to a mean of 1; None when every term weighs 1."""
    g = falloff_weights(offsets[0], sigma)
    if shared == 1.0:
        return g
    if profile == "direction":
        by = direction_weights(offsets, shared)
    else:
        by = np.where(shared_terms(offsets), shared, 1.0)
    w = (np.ones(offsets.shape[1]) if g is None else g) * by
    return w / w.mean()


def silverman(sigma: float, n: int, d: int) -> float:
    """Silverman's bandwidth ``sigma * (4 / (n (d + 2)))^(1 / (d + 4))`` (Urs et al., TIP 2014, eq. 6)."""
    return float(sigma * (4.0 / (n * (d + 2))) ** (1.0 / (d + 4)))


def _binomial_halve(image: np.ndarray) -> np.ndarray:
    """Smooth with [1 2 1]/4 along both axes (edges repeated), then keep the even pixels."""
    p = np.pad(image, 1, mode="edge")
    rows = (p[:-2] + 2.0 * p[1:-1] + p[2:]) / 4.0  # along y; still padded along x
    return ((rows[:, :-2] + 2.0 * rows[:, 1:-1] + rows[:, 2:]) / 4.0)[::2, ::2]


def nearest_label(values: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Each value replaced by the closest of the sorted *labels* (the lower one on a tie)."""
    hi = np.minimum(np.searchsorted(labels, values), labels.size - 1)
    lo = np.maximum(hi - 1, 0)
    return np.where(values - labels[lo] <= labels[hi] - values, labels[lo], labels[hi])


def scale_exemplar(labels_img: np.ndarray, level: int, pyramid: str = "binomial", phases: bool = False,
                   palette: np.ndarray | None = None) -> np.ndarray:
    """The exemplar of scale *level*, ``ceil(H / 2^level) x ceil(W / 2^level)``
    (Urs thesis, §4.2.4, §4.3.1).

    ``"decimate"`` keeps the even pixels. ``"binomial"`` smooths with [1 2 1]/4 before each
    halving, so thin features survive as fainter ones instead of vanishing where they fall
    on odd pixels; the result is rounded to the nearest grey level of *labels_img*, because
    the engine only ever writes those levels. With *phases* (the levels are names, as for
    ``distance="mismatch"`` and ``"weighted"``) each level's indicator is smoothed instead, and each pixel
    takes the level of the largest (the lowest on a tie): averaging phases' values would
    invent a phase where two others meet (matrix 0 beside particle 2 is not phase 1). On
    two levels both round alike. With a colour *palette* ``(L, C)`` (and not *phases*) each
    of the labels' colour channels is smoothed, and each pixel takes the label of the nearest
    palette colour, as a grey pixel the nearest level.
    """
    if pyramid == "decimate" or level == 0:
        return labels_img[:: 2**level, :: 2**level]
    if palette is not None and not phases:
        channels = [palette[labels_img.astype(np.intp), c] for c in range(palette.shape[1])]
        for _ in range(level):
            channels = [_binomial_halve(ch) for ch in channels]
        smooth = np.stack(channels, axis=-1)
        d = np.sum((smooth[:, :, None, :] - palette[None, None, :, :]) ** 2, axis=-1)
        return np.argmin(d, axis=-1).astype(labels_img.dtype)
    if phases:
        values = np.unique(labels_img)
        share = []
        for v in values:
            indicator = (labels_img == v).astype(np.float64)
            for _ in range(level):
                indicator = _binomial_halve(indicator)
            share.append(indicator)
        return values[np.argmax(np.stack(share), axis=0)].astype(labels_img.dtype)
    image = labels_img.astype(np.float64)
    for _ in range(level):
        image = _binomial_halve(image)
    return nearest_label(image, np.unique(labels_img).astype(np.float64)).astype(labels_img.dtype)


def scale_shape(shape: tuple[int, int, int], level: int) -> tuple[int, int, int]:
    """Shape of the block decimated *level* times (keeps even coordinates: ceil(N / 2^level))."""
    s = 2**level
    return tuple(-(-n // s) for n in shape)


@dataclass
class ScaleModel:
    """The tables of one scale. ``level`` 0 is full resolution."""

    level: int
    shape: tuple[int, int, int]
    exemplar: np.ndarray | dict[str, np.ndarray]  # the scale's exemplar, or each view's (per_view)
    half: int
    offsets: np.ndarray  # (views, R, 3)
    union_offsets: np.ndarray  # (U, 3): neighbours in any constrained view
    centres: np.ndarray  # (n,)
    patches: np.ndarray  # (R, n)
    bandwidth: float
    labels: np.ndarray  # the grey levels Lambda, ascending
    n_sets: int  # conflict-free colour sets
    mismatch: bool = False  # distance="mismatch" or "weighted": [a != b] for (a - b)^2 (see difference)
    costs: np.ndarray | None = None  # distance="weighted": each label's half-cost (phase_costs)
    term_weight: np.ndarray | None = None  # (R,) each term's weight: the fall-off's, the parent_weight
    parent_rows: int = 0  # the last rows of offsets and patches: the parent square's (parent_offsets), or none
    view_sites: tuple[int, ...] | None = None  # per-view exemplars: view v's sites are [v_sites[v], v_sites[v+1])
    palette: np.ndarray | None = None  # (L, C) a colour exemplar's labels in CIELAB, with the squared distance

    @property
    def channels(self) -> int:
        """Values compared per neighbour: a colour's channels (:attr:`palette`), else 1."""
        return 1 if self.palette is None or self.mismatch else self.palette.shape[1]

    def distance(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """The distance between labels (or values) *a* and *b* this scale sums (:func:`difference`)."""
        return difference(a, b, self.mismatch, self.costs, self.palette)

    @property
    def per_view(self) -> bool:
        """Whether each view has its own exemplar (then :attr:`exemplar` is a dict by view)."""
        return self.view_sites is not None

    def sites_of(self, view: int) -> slice:
        """The sites (columns of :attr:`patches`, entries of :attr:`centres`) *view* sums over."""
        if self.view_sites is None:
            return slice(0, self.n_sites)
        return slice(self.view_sites[view], self.view_sites[view + 1])

    @property
    def pixels(self) -> np.ndarray:
        """Every exemplar pixel of this scale, the views' pooled (:func:`clsolid.exemplar.pooled`)."""
        return pooled(self.exemplar)

    def coded(self, values: np.ndarray) -> np.ndarray:
        """Label *values* as the kernels compare them: themselves, or with :attr:`costs` their
        costs (float32), so that a mismatch's cost is the sum of the two codes. Colour
        (:attr:`channels` > 1): terms ``(R, n)`` become ``(R * C, n)``, term r's channel c in
        row ``r * C + c``, so that a squared distance over rows is the colours' distance."""
        if self.channels > 1:
            rgb = self.palette[np.asarray(values).astype(np.intp)]  # (R, n, C)
            return np.moveaxis(rgb, -1, 1).reshape(-1, rgb.shape[1])
        if self.costs is None:
            return values
        return self.costs[np.asarray(values).astype(np.intp)]

    def neighbour_coords(self, voxels: np.ndarray, view: int) -> np.ndarray:
        """``(m, R)`` flat indices of the terms of *voxels* in *view*, into the state
        :meth:`with_parent` extends: a parent row's index is past the volume's voxels."""
        flat = wrapped_coords(voxels, self.shape, self.offsets[view])
        if self.parent_rows:
            flat[:, -self.parent_rows:] += int(np.prod(self.shape))
        return flat

    @property
    def state_blocks(self) -> int:
        """How many blocks a state buffer holds: the block's, then its parent's (:meth:`with_parent`)."""
        return 2 if self.parent_rows else 1

    def with_parent(self, values: np.ndarray, parent: np.ndarray | None) -> np.ndarray:
        """*values* (a volume or its temperatures), flat, followed by the *parent* block's
        (:func:`parent_block`; for temperatures zeros: the parent terms are trusted) where the
        model has parent rows; else *values* flat."""
        if not self.parent_rows:
            return np.ravel(values)
        return np.concatenate([np.ravel(values), np.ravel(parent).astype(np.asarray(values).dtype)])

    @property
    def n_sites(self) -> int:
        return self.centres.size

    @property
    def colour(self) -> np.ndarray:
        """The set of each voxel, ``(Z, Y, X)`` (made on request: the drivers use :meth:`set_voxels`)."""
        return colour_sets(self.shape, self.half)[0]

    def set_voxels(self, c: int, active: np.ndarray | None = None, box=None) -> np.ndarray:
        """Flat indices, ascending, of the (*active*) voxels of colour set *c* (in *box*, a
        region of :func:`clsolid.core.schedule.regions`, if given)."""
        return colour_set(self.shape, self.n_sets, c, active, box)


def check_exemplar_fits(exemplar_shape: tuple[int, int] | dict[str, tuple[int, int]], params: MLParams) -> None:
    """Refuse an exemplar (each view's, given a dict of shapes) too small for the window at the coarsest scale."""
    if isinstance(exemplar_shape, dict):
        for view, one in exemplar_shape.items():
            try:
                check_exemplar_fits(one, params)
            except InputError as err:
                raise InputError(f"the {view} {err}") from None
        return
    coarse = scale_shape((1,) + tuple(exemplar_shape), params.scales - 1)[1:]
    if min(coarse) < params.neighborhood:
        raise InputError(
            f"exemplar of shape {tuple(exemplar_shape)} is too small: at the coarsest of "
            f"scales={params.scales} it is {coarse[0]}x{coarse[1]}, smaller than the "
            f"neighborhood={params.neighborhood} window; use fewer scales, a smaller "
            "neighborhood or a larger exemplar"
        )


def view_exemplars(labels_img: np.ndarray | dict[str, np.ndarray], views: tuple[str, ...]) -> list[np.ndarray]:
    """The exemplar each of *views* is constrained by: the one exemplar, or each view's own."""
    if not isinstance(labels_img, dict):
        return [labels_img] * len(views)
    if set(labels_img) != set(views):
        raise InputError(f"exemplars are given for views {sorted(labels_img)} but the run constrains {list(views)}")
    return [labels_img[v] for v in views]


#: The Parzen bandwidths the kernels hold: their ``1 / (2 h^2)`` is a normal float32.
BANDWIDTH_RANGE = (1e-18, 1e18)


def _check_bandwidth(h: float, params: MLParams, level: int) -> None:
    """Refuse a bandwidth outside :data:`BANDWIDTH_RANGE` (``1 / (2 h^2)`` would overflow or vanish)."""
    lo, hi = BANDWIDTH_RANGE
    if lo <= h <= hi:
        return
    given = (f"bandwidth={params.bandwidth!r}" if params.bandwidth is not None
             else f"bandwidth_factor={params.bandwidth_factor!r}")
    raise InputError(f"{given} gives a Parzen bandwidth of {h:.3g} at scale {params.scales - level} of "
                     f"{params.scales}, outside [{lo:g}, {hi:g}], the range the kernels hold; choose a bandwidth near "
                     "the exemplar's grey-level spread (bandwidth_factor near 1)")


def build_scale(
    labels_img: np.ndarray | dict[str, np.ndarray], shape: tuple[int, int, int], params: MLParams, level: int,
    palette: np.ndarray | None = None,
) -> ScaleModel:
    """Tables of scale *level* from the full-resolution exemplar labels (one image, or one per
    view: their tables are then stacked view after view, :attr:`ScaleModel.view_sites`); a
    colour exemplar's labels with its *palette* ``(L, C)`` (``LevelMap.features``)."""
    half = params.neighborhood // 2
    mismatch = params.distance in ("mismatch", "weighted")  # "auto" unresolved (params.for_exemplar): squared
    per_view = isinstance(labels_img, dict)
    images = view_exemplars(labels_img, params.view_names)
    pool = pooled(labels_img)
    costs = None
    if params.distance == "weighted":
        values = np.unique(pool)
        if not np.array_equal(values, np.arange(values.size)):
            raise InputError("distance='weighted' needs the labels 0..L-1 (as synthesize makes them)")
        costs = phase_costs(pool)
    own = images[:1] if not per_view else images  # each distinct exemplar once
    scaled = [scale_exemplar(im, level, params.pyramid, phases=mismatch, palette=palette) for im in own]
    tables = [exemplar_tables(ex, half) for ex in scaled]
    coarse = [None] * len(own)
    if params.parent_weight and level < params.scales - 1:  # the coarsest scale has no parent
        coarse = [scale_exemplar(im, level + 1, params.pyramid, phases=mismatch, palette=palette) for im in own]
    # a small coarser exemplar's result is not to be trusted (params.PARENT_MIN_SIDE)
    with_parents = all(c is not None and min(c.shape) >= params.parent_min_side for c in coarse)
    if with_parents:
        tables = [(c, np.concatenate([p, parent_tables(cx, ex.shape, half)]))
                  for (c, p), cx, ex in zip(tables, coarse, scaled)]
    counts = [c.size for c, _ in tables]
    centres = np.concatenate([c for c, _ in tables])
    patches = np.concatenate([p for _, p in tables], axis=1)
    if params.bandwidth is not None:
        h = params.bandwidth[level]
    else:
        ex_pool = pooled(dict(enumerate(scaled))) if per_view else scaled[0]
        channels = 1
        if mismatch:
            sigma = phase_sigma(ex_pool, costs)
        elif palette is not None:  # a colour's spread: the root of its channels' mean variance
            channels = palette.shape[1]
            sigma = float(np.sqrt(np.mean(np.var(palette[ex_pool.astype(np.intp)].reshape(-1, channels), axis=0))))
        else:
            sigma = float(ex_pool.std())
        # A constant exemplar has sigma = 0; any bandwidth gives the same (constant) result.
        factor = params.bandwidth_factor[level]
        # per view: each view's sum runs over its own sites, so n is their mean count; a colour
        # window has C values a pixel, so C k^2 dimensions
        n_mean = int(round(np.mean(counts)))
        h = silverman(sigma, n_mean, channels * params.neighborhood**2) * factor if sigma > 0 else 1.0
    _check_bandwidth(h, params, level)
    offsets = np.stack([view_offsets(v, half) for v in params.view_names])
    union = np.unique(offsets.reshape(-1, 3), axis=0)  # the temperatures' neighbours: no parent terms
    sshape = scale_shape(shape, level)
    weight = term_weights(offsets, params.falloff or 0.0,  # every view's rows pair alike
                          1.0 if params.shared_weight is None else float(params.shared_weight), params.shared_profile)
    parents = 0
    if with_parents:
        parents = 9
        weight = np.concatenate([np.ones(offsets.shape[1]) if weight is None else weight,
                                 np.full(parents, float(params.parent_weight))])
        offsets = np.concatenate([offsets, np.stack([parent_offsets(v) for v in params.view_names])], axis=1)
    return ScaleModel(
        level=level,
        shape=sshape,
        exemplar=dict(zip(params.view_names, scaled)) if per_view else scaled[0],
        half=half,
        offsets=offsets,
        union_offsets=union,
        centres=centres,
        patches=patches,
        bandwidth=h,
        labels=np.unique(pool).astype(np.float64),
        n_sets=set_count(sshape, half),
        mismatch=mismatch,
        costs=costs,
        term_weight=weight,
        parent_rows=parents,
        view_sites=tuple(int(n) for n in np.cumsum([0] + counts)) if per_view else None,
        palette=None if palette is None else np.asarray(palette, np.float64),
    )
