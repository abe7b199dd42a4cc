"""The public entry point: :func:`synthesize`."""

from __future__ import annotations

import logging
from functools import partial
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from .errors import InputError
from .ml.params import MLParams
from .core.hostmemory import check_host_memory, check_scratch_space, exemplar_terms
from .core.scratch import Scratch
from .core.slices import seam_ratio
from .ml.driver import SweepInfo, SynthesisResult, check_shape, resolve_seed, run_ml

if TYPE_CHECKING:
    from .search.params import SearchParams

log = logging.getLogger(__name__)

METHODS = ("ml", "wl", "kopf", "chen-wang")
#: What :func:`synthesize` returns: the exemplar's own values, or the engine's level indices.
OUTPUTS = ("values", "labels")
#: Options of the search methods (clsolid.search.params.SearchParams).
_SEARCH_OPTIONS = ("iterations", "inner", "parent", "parent_weight", "init", "rule", "order", "causal", "histogram",
                   "candidates", "specify", "search", "exact_passes", "seed_components", "coherence_levels",
                   "index_histogram",
                   "balance", "insert_spacing", "distance")
#: Options of the search methods that are not parameters of the method (what to report).
_SEARCH_REPORTS = ("site_map",)
#: The neighbourhood side each method uses when none is given (ML: 11, measured on the gallery; the
#: thesis case is 9; the search methods: ch5_np_common's 7).
DEFAULT_NEIGHBORHOOD = {"ml": MLParams().neighborhood, "wl": 7, "kopf": 7, "chen-wang": 7}
_ML_OPTIONS = ("pyramid", "xi", "stop_fraction", "max_sweeps", "upsampling", "inherited", "insert_slices",
               "insert_spacing", "insert_piece", "seam_gap",
               "slice_layout", "initial_temperature", "bandwidth", "bandwidth_factor", "relaxation",
               "anneal_start", "anneal_cooling", "sweeps", "balance", "likelihood", "distance",
               "prune_similar", "prune_sample", "prune_min_weight", "prune_projected",
               "prune_projected_k", "prune_projected_probe", "prune_projected_sweeps", "falloff", "shared_weight",
               "shared_profile", "parent_weight",
               "parent_min_side", "region")
_BACKEND_OPTIONS = ("vector_width", "voxels_per_item", "local_size", "max_batch", "tile", "client", "scratch")
#: Options of a likelihood run that are not parameters of the method (where to save it).
_RUN_OPTIONS = ("checkpoint", "checkpoint_every")


def is_reference(device) -> bool:
    """Whether *device* asks for the slow float64 NumPy back end."""
    return isinstance(device, str) and device.lower() == "reference"


def slice_plan(params: dict) -> "MLParams | SearchParams":
    """The parameters a result records (``SynthesisResult.params``, a sidecar's ``params``) as
    its method's parameter class (:class:`~clsolid.ml.params.MLParams` or
    :class:`~clsolid.search.params.SearchParams`): both say where the ``+in`` (or anchor)
    slices are (:mod:`clsolid.core.slices`)."""
    if params.get("method", "ml") == "ml":
        return MLParams.from_dict(params)
    from .search.params import SearchParams

    return SearchParams.from_dict(params)


def inserted_slices(params: dict, shape: tuple[int, int, int]) -> dict[str, np.ndarray]:
    """Depths of the ``+in`` (or anchor) slices of each view of a ``shape`` block grown with
    *params* (as :func:`slice_plan` reads them); an empty array for a view without."""
    from .core.slices import inserted_depths
    from .metrics import VIEWS

    depths = inserted_depths(tuple(shape), slice_plan(params))
    return {view: np.asarray(depths.get(view, ()), dtype=int) for view in VIEWS}


def _check_output(output) -> None:
    if output not in OUTPUTS:
        raise InputError(f"output={output!r} must be one of {', '.join(map(repr, OUTPUTS))}")


def _load(exemplar, levels, rng, options: dict):
    """The exemplar image, its level map and the seed, as every method takes them."""
    from .exemplar import level_map, load_exemplar

    image = load_exemplar(exemplar, builtin_size=options.get("builtin_size", 64))
    return image, level_map(image, levels), resolve_seed(rng)


def make_backend(device, backend_options: dict):
    """The reference back end for ``device="reference"``, else an OpenCL one, tiled if
    *backend_options* give a ``tile`` (see :mod:`clsolid.ml.tiled`), its tiles run on the
    workers of a Dask ``client`` if they give one (see :mod:`clsolid.ml.distributed`)."""
    options = dict(backend_options)
    tile, client, scratch = options.pop("tile", None), options.pop("client", None), options.pop("scratch", None)
    if scratch is not None and tile is None:
        raise InputError(f"scratch={scratch!r} keeps a tiled run's state on disk: give tile=N too (--tile N); "
                         "a block in one piece lives on the device")
    if is_reference(device):
        for name, value in (("tile", tile), ("client", client), ("scratch", scratch)):
            if value is not None:
                raise InputError(f"{name}={value!r} is for OpenCL devices: the reference back end holds the whole "
                                 f"volume on the host; drop {name}")
        from .ml.reference import ReferenceBackend

        return ReferenceBackend()
    from .ml.tiled import TiledBackend, check_edge

    store = None if scratch is None else Scratch(scratch)  # checked now; its folder made when first used

    if client is not None:
        if tile is None:
            raise InputError("client= runs the tiles of every conflict-free set on Dask workers: give tile=N too "
                             "(--tile N), tiles large enough that their compute outweighs shipping them")
        from .ml.distributed import DaskTiles

        check_edge(tile)  # before asking the workers anything
        return TiledBackend(DaskTiles(client, device, **options), tile, store)
    from .ml.opencl import CLBackend
    from .core.device import select_device

    engine = CLBackend(select_device(device), **options)
    return engine if tile is None else TiledBackend(engine, tile, store)


def synthesize(
    exemplar,
    shape,
    *,
    method: str = "ml",
    heuristic: str | None = None,
    neighborhood: int | None = None,
    scales: int = 3,
    views: int = 2,
    levels: int | None = 32,
    rng=None,
    device=None,
    progress: Callable[[SweepInfo], None] | None = None,
    output: str = "values",
    full_output: bool = False,
    **options,
):
    """Grow a solid texture whose slices look like a 2D exemplar.

    The NP-MRF maximum-likelihood method of Urs, Da Costa & Germain (IEEE TIP 2014):
    every voxel takes the grey level that maximises its local conditional probability,
    estimated with a Gaussian Parzen window over every neighbourhood of the exemplar,
    on 2 or 3 orthogonal slices through the voxel; relaxed coarse to fine with per-voxel
    temperatures by a Gibbs sampler (the default), by ICM (the thesis) or by simulated
    annealing (TIP14). Voxels are updated in conflict-free sets, so the result is that of
    a sequential relaxation visiting the sets in a seeded order.

    The defaults depart from the published method where the gallery of exemplars
    (``tools/gallery.py``) showed it fails: Gibbs draws instead of ICM's argmax, a
    label-histogram balance, dense, staggered ``+in`` slices and, on categorical
    exemplars, phase mismatches instead of squared differences and no window terms on
    the axis the views share. ``relaxation="icm", balance=0, slice_layout="aligned",
    insert_slices=4, distance="squared", falloff=0, seam_gap=0, parent_weight=0,
    shared_weight=1`` (with ``bandwidth_factor=1, pyramid="decimate"``) is the thesis's
    form (the likelihood presets of ``clsolid.presets`` use it). See docs/choices.md.

    Parameters
    ----------
    exemplar : ndarray, str or path
        2D grey image (uint8, uint16 or float), a ``.png``/``.tif``/``.npy`` path, or a
        built-in name (``"brick"``, ``"grass"``, ``"gravel"``: scikit-image's 512x512
        textures, top-left 256x256 area-averaged to 64x64; option ``builtin_size``).
    shape : tuple of 3 ints
        ``(Z, Y, X)`` size of the block. Output is toroidal (tileable); any sizes work.
    method : {"ml", "wl", "kopf", "chen-wang"}
        ``"ml"``: the maximum-likelihood method (default). ``"wl"``: Wei-Levoy extended
        to 2D->3D (thesis_spec §1.6.1): every view's exact best match, averaged, over a
        Gaussian pyramid. ``"kopf"``: the same matches combined with Kopf et al.'s robust
        weights and grey-level histogram re-weighting (§1.6.2; a phase, never a blend, on
        an exemplar of at most 8 values). ``"chen-wang"``: each view's choice among its best
        match's candidate set (option ``candidates``, default 15) under the index
        histogram, Kopf's weights under the position histogram, and a discrete solver that
        copies one exemplar pixel (§1.6.3): only exemplar values, and
        ``SynthesisResult.source`` says which pixel each voxel copies. Their options are ``iterations`` (passes per scale, default 10),
        ``inner`` (most searches per voxel and pass, default 4), ``parent`` (the coarser
        scale's 3x3 in every neighbourhood, default True), ``parent_weight`` (each of its
        terms' weight against 1 for the square's; default 4 for ``kopf``, 1 for the others),
        ``distance`` (``"weighted"``: the finest scale's squares compare a categorical
        exemplar's phases as names, by weighted mismatches; ``"squared"``: by their grey
        values; ``"auto"``, default: weighted on 3 to 8 phases for ``kopf``), ``init`` (``"upsample"``,
        default, or ``"noise"``) and, for ``kopf``, ``rule`` (``"centres"``, the thesis's:
        each view's matched centre; ``"overlap"``, Kopf et al.'s: every overlapping matched
        square proposes a value), ``order`` (``"sets"``, default: conflict-free sets in
        parallel; ``"lexicographic"``, ``"random"``, ``"morton"`` or ``"hilbert"``: one voxel
        at a time, for small blocks), ``causal`` (the L-shaped neighbourhood instead of the
        full square; default False), for ``kopf`` ``histogram`` (``"global"``, default, or
        ``"slice"``: the re-weighting against the histogram of the voxel's slice), for ``wl``
        and ``kopf`` ``specify`` (after every pass, the block's grey levels mapped rank for
        rank onto the exemplar's histogram; default True for ``kopf``, False for ``wl``), for
        ``kopf`` ``balance`` (categorical exemplars: each set's vote biased toward the
        exemplar's phase fractions, as the likelihood method's balance; default 1, 0 = the
        thesis), ``search``
        (``"exact"``: every exemplar site, the reference; ``"coherence"``: the k-coherence
        candidates of the voxel's neighbours' matches, several times faster; default
        ``"coherence"`` for ``kopf``, ``"exact"`` for ``wl`` and ``chen-wang``),
        ``exact_passes`` (with ``"coherence"``: the first passes of every level search every
        site and seed the candidates of the rest; default 1 for ``kopf`` on a grey exemplar,
        else 0), ``seed_components`` (with ``"coherence"``: those passes compare the sites
        on this many leading principal components, the site found then measured on every
        term; 0: every term; default 16 for ``kopf``, else 0), ``coherence_levels`` (with
        ``"coherence"``: how many of the finest levels search among the candidates, the
        coarser ones every site; default 1 for ``kopf``, every level for the others),
        ``index_histogram`` (with ``"coherence"``, ``wl`` and ``kopf``: the candidates ranked
        by Chen & Wang's index histogram too, so that no part of the exemplar is matched far
        beyond its share; default True for ``wl``, and for ``kopf`` on grey exemplars), and
        ``site_map=True`` (with ``full_output``) adds the position
        histogram, ``SynthesisResult.site_use``; they return float64 volumes of exemplar values or their means, and
        ``output="labels"`` is refused. The ML-only arguments and options (``heuristic``,
        ``relaxation`` ...) are refused with it, and the other way round.
    heuristic : str, optional
        ``"ml"`` only: how the per-view LCPDFs are combined (default ``"h2-product"``):

        ============ ============================================== ========== =======
        name         rule                                           thesis     paper
        ============ ============================================== ========== =======
        h1-lowest    best label per view; keep the least probable   NP_ML_H1a  ML_H1a
        h1-highest   best label per view; keep the most probable    NP_ML_H1b  --
        h1-mean      best label per view; their mean (rounded)      NP_ML_H1c  ML_H1b
        h2-min       argmax over labels of the smallest view LCPDF  NP_ML_H2a  ML_H2a
        h2-max       argmax over labels of the largest view LCPDF   NP_ML_H2b  --
        h2-product   argmax over labels of the product of LCPDFs    NP_ML_H2c  ML_H2b
        ============ ============================================== ========== =======

        Thesis and paper tags are accepted as aliases (case-insensitive).
    neighborhood : int, optional
        Odd side of the full-square window in each view (3 to 31; thesis 7, 9 or 11).
        Default: 11 for ``"ml"`` (measured on the gallery; the thesis case is 9), 7 for the
        search methods (``ch5_np_common``).
    scales : int
        Number of decimation scales (each halves the exemplar and the block).
    views : {2, 3}
        2: front (y, x) and right (y, z) planes, which share the y axis; 3: also top (z, x).
        Exemplar rows map to y in front and right, to z in top.
    levels : int or None
        Most grey levels (default 32). An exemplar with at most this many distinct
        values (binary, segmented) keeps exactly those values; any other is quantised
        uniformly over its own range into this many levels. ``None`` keeps all 256
        levels of an 8-bit exemplar.
    rng : int, numpy.random.Generator or None
        Seed. The same seed gives the same volume on the same device.
    device : str, Device or None
        OpenCL device (see :func:`clsolid.select_device`), or ``"reference"`` for the
        slow float64 NumPy back end.
    progress : callable, optional
        Called with a :class:`SweepInfo` after every sweep (``info.volume()`` gives the
        current block, for evaluation during the run).
    output : {"values", "labels"}
        What the returned array holds: the exemplar's own values and dtype (default),
        or the level indices the engine works on.
    full_output : bool
        Return a :class:`SynthesisResult` (both arrays, parameters, seed, timings)
        instead of one array.
    **options
        ``pyramid`` (how coarser scales' exemplars are made: ``"binomial"``, the default,
        smooths with [1 2 1]/4 before each 2:1 decimation; ``"decimate"`` keeps every other
        pixel unfiltered, as the thesis does: see the README, Quality), ``xi`` (cooling,
        default -3), ``stop_fraction`` (0.95: a scale stops when the global
        temperature has fallen by this fraction, or reaches 0), ``max_sweeps`` (30 per scale),
        ``upsampling`` (``"1/8"`` or ``"8/8"``; default 1/8, and 8/8 under annealing as in
        TIP14), ``inherited`` (``"resynthesize"`` with t held at 0, or ``"fixed"``),
        ``insert_spacing`` (the thesis's ``+in``: the exemplar is tiled onto one slice of
        each constrained view about every this many voxels of its depth axis, on
        multiples of 2^(scales-1), and trusted (t = 0) at the start of every scale;
        default 5 for categorical exemplars, 6 for grey ones, docs/choices.md),
        ``insert_slices`` (a number of such slices per view instead; 0 gives the ``-in``
        start, which collapses to the majority), ``slice_layout`` (``"staggered"``,
        the default: each view's slices between the other's, each with its own seeded
        shift of the exemplar; ``"aligned"``: the same depths and tiling in every view, as
        the thesis, which makes the block nearly its own x<->z mirror image),
        ``insert_piece`` (0, the default: each ``+in`` slice one exemplar window, as the
        thesis; N: a mosaic of N x N pieces, each from its own seeded window, N a multiple
        of 2^(scales-1), so that no slice starts as a copy of one window; docs/choices.md),
        ``seam_gap`` (where a ``+in`` slice tiles the exemplar across its edge, as a
        staggered shift or a slice longer than the exemplar does, this many pixels on each
        side of the seam are not written and are grown instead; 0 writes the seam; default
        2 where the exemplar's seam shows, ``clsolid.core.slices.seam_ratio`` above 2, as
        in photographs of coarse textures, else 0; docs/choices.md),
        ``initial_temperature`` (1),
        ``bandwidth`` (Parzen h, one value or one per scale finest first; default
        ``bandwidth_factor`` x Silverman's rule per scale), ``bandwidth_factor`` (multiplies
        Silverman's h; one value or one per scale finest first; default 0.2, where the
        thesis uses 1: see the README, Quality), ``falloff`` (the sigma, in pixels of each
        scale, of a Gaussian weight on each neighbourhood term by its distance from the
        centre; default 3 for grey exemplars, 0 for categorical ones; 0 = every term alike,
        the thesis: docs/choices.md), ``shared_weight`` (the weight of the window terms on
        the axis the constrained views share, the voxels above and below a voxel, which both
        views' windows hold; default 0 for categorical exemplars with 2 views, else 1; 1 =
        every term alike, the thesis: docs/choices.md), ``shared_profile`` (which terms a
        ``shared_weight`` W < 1 weighs: ``"direction"``, the default, every term 1 - (1 - W)
        cos^2 of its angle to the shared axis; ``"line"`` the terms on that axis alone),
        ``parent_weight`` (each of the coarser scale's 3 x 3 parent terms, added to every
        neighbourhood of the scales whose coarser exemplar is at least ``parent_min_side``
        pixels on its shorter side (default 64), weighs this against 1 for a term of the
        window; default 4 for categorical exemplars, 0 for grey ones; 0 = none, the thesis: docs/choices.md),
        ``builtin_size``, and OpenCL tuning: ``vector_width``,
        ``voxels_per_item``, ``local_size``, ``max_batch``.

        Tiles (issue 12): ``tile`` (default None: the block in one piece) synthesises the block
        a tile of at most this many voxels on a side at a time, each with a halo of the
        neighbourhood's half-width; the device holds one tile's state, the host the whole
        block's (``clsolid.ml.tiled``). The volume is the one-piece run's, voxel for voxel; it
        costs moving each tile between host and device for every conflict-free set. A block
        whose buffers do not fit the device in one piece is refused with a
        ``DeviceMemoryError`` that names the largest tile that fits. ``client`` (a
        ``dask.distributed.Client``; needs ``tile``) runs the tiles of every conflict-free set at
        once as tasks on its workers, each opening ``device`` (a spec string; None: each
        worker's best) for itself (``clsolid.ml.distributed``; ``pip install "clsolid[dask]"``).
        The volume is again the one-piece run's; every set ships each tile's state to a worker
        and back, so it pays for tiles large enough that compute dominates. ``scratch`` (a
        folder; needs ``tile``) keeps the whole block's state in memory-mapped files in a
        folder made there and removed at the end (``clsolid.core.scratch``), for blocks larger
        than the host's memory: the same volume, a few bytes a voxel in memory and about 40 on
        that disk, which is checked for room first. The result's arrays are then
        ``numpy.memmap`` files there too, nameless (they go when the arrays do), so a result
        larger than memory is returned, and :func:`clsolid.volumeio.save_volume` writes it a
        plane at a time. ``region`` (0, the default: each sweep visits the conflict-free sets
        over the whole block) visits the block region by region instead, cubes of at most
        that many voxels a side, every set of one region before the next: another visiting
        order (another volume: alike on the categorical gallery, worse on tissue, through
        the balance; README, Using it), whose sweep reads
        each region's state once where a set-by-set sweep reads the whole state once a set,
        for a scratch folder larger than the page cache (``region`` = ``tile``).

        Relaxation (thesis_spec §2.3): ``relaxation`` is ``"gibbs"`` (default: each visited
        voxel draws its label from the combined, normalised LCPDF; per-voxel temperatures,
        neighbour weights and stop rule as ICM), ``"icm"`` (the thesis: it takes the argmax) or
        ``"annealing"`` (TIP14 Fig. 1: no voxel temperatures, every neighbour counts fully and
        every voxel is visited each sweep, trusted ``+in`` and inherited ones included unless
        ``inherited="fixed"``; a uniformly drawn label lambda replaces x_s if
        p = P(lambda)/P(x_s) > 1 or p * t_in > q, q ~ U[0, 1), with P the heuristic's combined
        score). The global temperature t_in starts every scale at ``anneal_start`` (default 1:
        Metropolis sampling of the LCPDF) and is multiplied by ``anneal_cooling`` (0.8) after each
        sweep; the scale stops when it has fallen by ``stop_fraction`` (14 sweeps with the
        defaults) or after ``max_sweeps``. ``sweeps`` fixes the number of sweeps per scale
        instead, for any relaxation (default None: the stop rule). The h1 heuristics combine
        per-view solutions: each view's argmax, its own draw, or the proposal where that view
        alone accepts it. ``balance`` (beta in [0, 1], default 1; 0 = off) keeps the
        exemplar's label fractions (a departure, as Kopf et al.'s histogram re-weighting):
        after every conflict-free set, a per-label bias on the log score is fitted to the
        scores that set left, so that the voxels still to visit bring the whole volume to
        the exemplar's fractions at that scale (``clsolid.ml.balance``); beta < 1 aims that
        far from the unbiased fractions. Exact in expectation for Gibbs draws; ICM and
        annealing decide otherwise than by a draw, and keep the fractions less closely.

        Likelihood (issue 12): ``likelihood="exact"`` sums the Parzen window over every
        exemplar site; ``"pruned"`` over k-coherence candidates (the sources, nearest
        sites at the last visit, of the voxel and its 8 in-slice neighbours, shifted, and the
        ``prune_similar`` windows most like each (None, the default: 1 with projected
        candidates, else 8); identical windows count by their number), plus an unbiased
        estimate of the rest from ``prune_sample`` sites drawn systematically (None, the
        default: 32 with projected candidates, else 64); with ``prune_projected=D`` (0: off)
        also each voxel's ``prune_projected_k`` (32) sites nearest by the distance projected
        on the exemplar windows' first D principal axes (squared differences only;
        docs/performance.md), searched in the ``prune_projected_probe`` (8) lists of sites (about
        sqrt(sites) lists, by k-means) whose centres are nearest (0: every site), in the first
        ``prune_projected_sweeps`` (1) sweeps of each scale (0: every sweep); a neighbourhood whose
        mean (1 - t)^2 is below ``prune_min_weight`` (default 0: none) gets the exact sum
        (``clsolid.ml.pruned``). ``"auto"`` (default) prunes categorical exemplars (binary or
        segmented: their own values kept, at most 8 of them) and grey ones with at least
        10,000 sites (about 110² pixels at 11×11), those with ``prune_projected=24``
        (``None``, the default, decides so), and sums smaller grey ones exactly, where the
        pruned sum missed fine fringes and saved little (docs/performance.md); the result's
        ``params`` say what it took.

        Distance: ``distance="squared"`` compares neighbourhoods and centre values by squared
        grey-level differences (the thesis); ``"mismatch"`` counts the neighbours whose levels
        differ (each weighted (1 - t)^2), so that phases are names, not numbers;
        ``"weighted"`` costs a mismatch between phases a and b 1/(2 f_a) + 1/(2 f_b) (f: the
        exemplar's fractions; the chi-square distance), so that a rare phase's shapes count as
        much as the matrix's. The bandwidth is taken in each distance's units
        (``clsolid.ml.model.phase_sigma``). ``"auto"`` (default) takes ``"weighted"`` on the
        exemplars the pruned sum takes (categorical, at most 8 values; ``"mismatch"`` on two,
        the same distance) and ``"squared"`` on grey ones; on two levels all three are the same.

    Returns
    -------
    ndarray or SynthesisResult
        ``(Z, Y, X)``. With ``output="values"``, in the exemplar's units and dtype: a
        binary or segmented exemplar's own values (at most ``levels`` distinct values),
        else the mean exemplar value of each of the ``levels`` levels. A search method's
        block comes back so where every voxel is one of those values (``chen-wang``;
        ``kopf`` on a categorical exemplar, or with ``specify``); where it holds blends
        (``wl``; ``kopf`` with ``specify=False`` on a grey exemplar), as float64 means of
        them. With ``output="labels"``, level indices (uint8, uint16 above 256 levels).

    Raises
    ------
    InputError
        A bad parameter or exemplar; the message names it.
    NoDeviceError, DeviceMemoryError, KernelBuildError
        No OpenCL device; buffers too large for the device (checked before allocating);
        a kernel failed to build.
    """
    if method not in METHODS:
        raise InputError(f"method={method!r} is not available; use one of {METHODS}")
    _check_output(output)
    valid = (_ML_OPTIONS + _BACKEND_OPTIONS + _RUN_OPTIONS if method == "ml"
             else _SEARCH_OPTIONS + _SEARCH_REPORTS) + ("builtin_size",)
    unknown = set(options) - set(valid)
    if unknown:
        raise InputError(f"unknown option(s) {sorted(unknown)} for method={method!r}; valid: {', '.join(valid)}")
    if neighborhood is None:
        neighborhood = DEFAULT_NEIGHBORHOOD[method]
    shape = check_shape(shape)
    if method != "ml":
        if heuristic is not None:
            raise InputError(f"heuristic={heuristic!r} is for method='ml' ({method} combines the views' matches)")
        return _synthesize_search(exemplar, shape, method, neighborhood, scales, views, levels, rng, device,
                                  progress, output, full_output, options)
    params = MLParams(neighborhood=neighborhood, scales=scales, views=views, levels=levels,
                      heuristic="h2-product" if heuristic is None else heuristic, **{k: options[k] for k in _ML_OPTIONS if k in options})
    image, levels_of, seed = _load(exemplar, levels, rng, options)
    params = params.for_exemplar(levels_of.values.size, levels_of.exact, seam_ratio(image), image.shape[:2])
    backend = make_backend(device, {k: options[k] for k in _BACKEND_OPTIONS if k in options})
    hook = None
    if options.get("checkpoint") is not None:
        from .ml.checkpoints import Checkpointer, check_every

        meta = {"method": method, "params": params.to_dict(), "shape": list(shape), "seed": seed,
                "device": backend.name}
        hook = Checkpointer(options["checkpoint"], check_every(options.get("checkpoint_every", 0.0)), meta, image)
    log.info("synthesising %s from a %s exemplar on %s, seed %d", shape, image.shape, backend.name, seed)
    return _run_ml(levels_of, shape, params, seed, backend, progress, output, full_output, hook, None)


def _run_ml(levels_of, shape, params, seed, backend, progress, output, full_output, hook, state):
    """Run (or, from *state*, go on with) a likelihood synthesis and shape its result."""
    scratch = getattr(backend, "scratch", None)
    on_disk = scratch is not None and scratch.on_disk
    check_host_memory(shape, "ml-scratch" if on_disk else "ml", exemplar_terms(levels_of.labels.shape,
                                                                                 params.neighborhood))
    if on_disk:
        check_scratch_space(shape, scratch.root)
    try:
        vol, timings, bandwidths = run_ml(levels_of.labels, shape, params, seed, backend, progress,
                                          checkpoint=hook, resume=state)
        # a run of planes at a time: no whole temporary (host memory); with the state on disk
        # the result is there too, in files that go when its arrays do
        store = scratch if on_disk else Scratch()
        labels = store.apply(np.rint, np.uint8 if levels_of.values.size <= 256 else np.uint16, vol, kept=True)
        values = None
        if full_output or output != "labels":
            values = store.apply(levels_of.to_values, levels_of.values.dtype, labels, kept=True)
    finally:
        if scratch is not None:
            scratch.close()
    if not full_output:
        return labels if output == "labels" else values
    effective = {"method": "ml", **params.to_dict(), "bandwidth_effective": bandwidths, "shape": list(shape)}
    return SynthesisResult(volume=values, labels=labels,
                           exemplar=levels_of.to_values(levels_of.labels), exemplar_labels=levels_of.labels,
                           level_values=levels_of.values, values_exact=levels_of.exact,
                           seed=seed, params=effective, device=backend.name, timings=timings)


def resume(checkpoint, *, device=None, progress: Callable[[SweepInfo], None] | None = None,
           output: str = "values", full_output: bool = False, checkpoint_every: float = 0.0,
           tile: int | None = None, client=None, scratch=None):
    """Go on with a likelihood synthesis from its checkpoint folder, and keep checkpointing there.

    Parameters
    ----------
    checkpoint : str or path
        The folder a run of :func:`synthesize` wrote with ``checkpoint=``.
    device, progress, output, full_output
        As for :func:`synthesize`. Everything else (exemplar, shape, parameters, seed) is
        the checkpoint's.
    checkpoint_every : float
        Seconds between the checkpoints written from now on (0: after every sweep).
    tile : int, optional
        Go on in tiles of at most this many voxels on a side (as :func:`synthesize`'s
        ``tile``), whether or not the run began in tiles: the volume is the same.
    client : distributed.Client, optional
        Run those tiles on its Dask workers (as :func:`synthesize`'s ``client``).
    scratch : str or path, optional
        Keep those tiles' state in files in this folder (as :func:`synthesize`'s ``scratch``).

    Returns
    -------
    As :func:`synthesize`. On the device that began the run, the volume is identical to
    the one the run would have made without stopping; another device grows an equally
    valid but different one (its floats differ in the last bits), with a warning.

    Raises
    ------
    clsolid.core.checkpoint.CheckpointError
        No checkpoint in the folder, a corrupt one, or one whose state does not fit its
        own parameters.
    """
    from .core.checkpoint import CheckpointError
    from .exemplar import level_map
    from .ml.checkpoints import Checkpointer, check_every, load_run
    from .ml.model import scale_shape

    _check_output(output)
    backend = make_backend(device, {k: v for k, v in (("tile", tile), ("client", client), ("scratch", scratch))
                                    if v is not None})
    store = getattr(backend, "scratch", None)
    try:  # with a scratch folder, the checkpoint's whole-block arrays are read into its files
        meta, params, image, state = load_run(checkpoint, np.empty if store is None else _large_on(store))
        shape = check_shape(tuple(meta["shape"]))
        level = params.scales - 1 - state.scale
        expected = scale_shape(shape, level) if 0 <= level < params.scales else None
        if expected is None or state.volume.size != int(np.prod(expected)):
            raise CheckpointError(f"{checkpoint}: the saved volume ({state.volume.size} voxels) does not fit scale "
                                  f"{state.scale + 1} of a {shape} run: the checkpoint is corrupt")
    except BaseException:
        if store is not None:
            store.close()
        raise
    levels_of = level_map(image, params.levels)
    if backend.name != meta.get("device"):
        log.warning("resuming on %s a run begun on %s: the volume will differ from the uninterrupted one",
                    backend.name, meta.get("device"))
    run_meta = {k: v for k, v in meta.items() if k != "timings"}  # the Checkpointer adds each sweep's
    hook = Checkpointer(checkpoint, check_every(checkpoint_every), run_meta, image)
    log.info("resuming %s at scale %d, after sweep %d", checkpoint, state.scale + 1, state.sweep)
    return _run_ml(levels_of, shape, params, int(meta["seed"]), backend, progress, output, full_output, hook, state)


#: Elements from which a resumed checkpoint's array is read into the scratch folder.
_SCRATCH_LEAST = 1 << 16


def _large_on(store: Scratch) -> Callable[[tuple, Any], np.ndarray]:
    """``empty(shape, dtype)`` that puts whole-block arrays on *store* and small ones in memory."""
    return lambda shape, dtype: (store.empty(shape, dtype) if int(np.prod(shape)) >= _SCRATCH_LEAST
                                 else np.empty(shape, dtype))


def _synthesize_search(exemplar, shape, method, neighborhood, scales, views, levels, rng, device, progress,
                       output, full_output, options):
    """:func:`synthesize` for the fixed-neighbourhood search methods (``"wl"``, ``"kopf"``, ``"chen-wang"``)."""
    from .search.match import CLMatcher, ReferenceMatcher
    from .search.params import SearchParams
    from .search.driver import run_search

    if output != "values":
        raise InputError(f"method={method!r} combines exemplar values, so it has no level indices: "
                         "use output='values'")
    params = SearchParams(method=method, neighborhood=neighborhood, scales=scales, views=views,
                          **{k: options[k] for k in _SEARCH_OPTIONS if k in options})
    site_map = options.get("site_map", False)
    if not isinstance(site_map, bool):
        raise InputError(f"site_map={site_map!r} must be True or False")
    if site_map and not full_output:
        raise InputError("site_map=True needs full_output=True (the map is SynthesisResult.site_use)")
    image, levels_of, seed = _load(exemplar, levels, rng, options)
    check_host_memory(shape, "search")
    grey = levels_of.to_values(levels_of.labels).astype(np.float64)
    n_values = np.unique(grey).size
    params = params.for_exemplar(n_values)
    if is_reference(device):
        name, make_matcher = "reference (NumPy float64)", ReferenceMatcher
    else:
        from .core.device import select_device

        dev = select_device(device)
        name, make_matcher = dev.name, partial(CLMatcher, dev)
    log.info("synthesising %s from a %s exemplar with %s on %s, seed %d", shape, image.shape, method, name, seed)
    vol, timings, use, source = run_search(grey, shape, params, seed, make_matcher, progress, count_sites=site_map)
    if params.keeps_exemplar_values(n_values):  # exact: each voxel is one of the values
        vol = vol.astype(levels_of.values.dtype)
    if not full_output:
        return vol
    effective = {**params.to_dict(), "levels": levels, "shape": list(shape)}
    return SynthesisResult(volume=vol, labels=None, exemplar=grey, exemplar_labels=levels_of.labels,
                           level_values=levels_of.values, values_exact=levels_of.exact, seed=seed,
                           params=effective, device=name, timings=timings, site_use=use, source=source)
