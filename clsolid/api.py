"""The public entry points: :func:`synthesize` and :func:`resume`."""

from __future__ import annotations

import logging
import warnings
from functools import partial
from typing import Any, Callable

import numpy as np

from .core.hostmemory import check_host_memory, check_scratch_space, exemplar_terms
from .core.options import names, refuse_unknown
from .core.scratch import Scratch
from .core.slices import seam_ratio
from .core.despeckle import despeckle
from .core.synthesis import SweepInfo, SynthesisResult, check_shape, resolve_seed
from .errors import ExemplarWarning, InputError
from .ml.backends import FOOTPRINT, SCRATCH_FOOTPRINT, BackendOptions, backend_options, is_reference, make_backend
from .ml.params import MLParams
from .phases import is_categorical
from .search import FOOTPRINT as SEARCH_FOOTPRINT
from .search.params import METHODS as SEARCH_METHODS
from .search.params import SearchParams

log = logging.getLogger(__name__)

#: The synthesis methods, each with its parameters class.
METHODS: dict[str, type] = {"ml": MLParams, **{m: SearchParams for m in SEARCH_METHODS}}
#: What :func:`synthesize` returns: the exemplar's own values, or the engine's level indices.
OUTPUTS = ("values", "labels")


def method_params(method: str, params: MLParams | SearchParams | None = None, **options: Any
                  ) -> MLParams | SearchParams:
    """The parameters of *method*: *params* (or the defaults) with *options* in place.

    Parameters
    ----------
    method : {"ml", "wl", "kopf", "chen-wang"}
        The synthesis method.
    params : MLParams or SearchParams, optional
        Parameters to start from (its class must be *method*'s).
    **options
        Fields of *method*'s parameters class; a name it does not have is refused, with the
        closest valid name, or the method that has it.

    Returns
    -------
    MLParams or SearchParams
    """
    if not isinstance(method, str) or method not in METHODS:
        raise InputError(f"method={method!r} is not available; use one of {tuple(METHODS)}")
    cls = METHODS[method]
    valid = tuple(n for n in names(cls) if n != "method")
    for name in set(options) - set(valid):
        owners = [m for m, c in METHODS.items() if c is not cls and name in names(c)]
        if owners:
            raise InputError(f"{name}={options[name]!r} is an option of method {owners[0]!r}, not of {method!r}")
    refuse_unknown(options, valid, f"method={method!r}")
    if params is not None:
        if not isinstance(params, cls) or (cls is SearchParams and params.method != method):
            raise InputError(f"params={params!r} are not method {method!r}'s ({cls.__name__})")
        return _replace(params, options)
    return cls(method=method, **options) if cls is SearchParams else cls(**options)


def _replace(params: Any, options: dict) -> Any:
    from dataclasses import replace

    return replace(params, **options) if options else params


def slice_plan(params: dict) -> MLParams | SearchParams:
    """The parameters a result records (``SynthesisResult.params``, a sidecar's ``params``) as
    its method's parameter class: both say where the ``+in`` (or anchor) slices are
    (:mod:`clsolid.core.slices`)."""
    if params.get("method", "ml") == "ml":
        return MLParams.from_dict(params)
    return SearchParams.from_dict(params)


def inserted_slices(params: dict, shape: tuple[int, int, int]) -> dict[str, np.ndarray]:
    """Depths of the ``+in`` (or anchor) slices of each view of a ``shape`` block grown with
    *params* (as :func:`slice_plan` reads them); an empty array for a view without."""
    from .core.slices import inserted_depths
    from .core.views import VIEW_SETS

    depths = inserted_depths(tuple(shape), slice_plan(params))
    return {view: np.asarray(depths.get(view, ()), dtype=int) for view in VIEW_SETS[3]}


def _check_output(output: Any) -> None:
    if output not in OUTPUTS:
        raise InputError(f"output={output!r} must be one of {', '.join(map(repr, OUTPUTS))}")


def _check_progress(progress: Any) -> None:
    if progress is not None and not callable(progress):
        raise InputError(f"progress={progress!r} must be a function taking a SweepInfo, or None")


def _load(exemplar: Any, levels: int | None, rng: Any, channel_axis: int | None = None):
    """The exemplar image (or one per view, a dict), its level map and the seed, as every method takes them."""
    from .exemplar import level_map, load_exemplars

    image = load_exemplars(exemplar, channel_axis=channel_axis)
    levels_of = level_map(image, levels)
    if levels_of.n_labels < 2:
        warnings.warn(f"the exemplar is constant (every pixel {levels_of.values[0].tolist()!r}): the volume will be "
                      "too", ExemplarWarning, stacklevel=3)
    if isinstance(image, dict) and is_categorical(levels_of.n_labels, levels_of.exact):
        for view, labels in levels_of.labels.items():  # one phase set: a phase a view lacks could never be drawn
            missing = np.setdiff1d(np.arange(levels_of.n_labels), labels)
            if missing.size:
                names = ", ".join(repr(v.tolist()) for v in levels_of.values[missing])
                raise InputError(f"the {view} exemplar lacks phase {names}, which the other views' exemplars hold: "
                                 "the exemplars of a segmented material must share one phase set")
    return image, levels_of, resolve_seed(rng)


def _per_view(image: Any, run_params: MLParams | SearchParams, given: bool):
    """*run_params* with the views of an exemplar per view (*image* a dict by view); refused where
    the views were *given* (as an option, or in parameters passed whole) and name others."""
    if not isinstance(image, dict):
        return run_params
    from .core.views import view_set, views_value

    names = tuple(image)
    if given and view_set(run_params.views) != names:
        raise InputError(f"views={run_params.views!r} but the exemplars are for {' and '.join(names)}: "
                         "leave views out, and the views with an exemplar are the ones constrained")
    return _replace(run_params, {"views": views_value(names)})


def _seam(image: Any) -> float:
    """The largest seam ratio of the exemplar or exemplars (:func:`clsolid.core.slices.seam_ratio`)."""
    from .colour import luminance
    from .exemplar import each

    return max(seam_ratio(luminance(im) if im.ndim == 3 else im) for im in each(image))


def _described(image: Any) -> str:
    """The exemplar's shape for a log line: ``a (64, 64) exemplar``, or each view's."""
    if isinstance(image, dict):
        return "exemplars " + ", ".join(f"{v} {im.shape}" for v, im in image.items())
    return f"a {image.shape} exemplar"


def _shape_of(image: Any) -> tuple[int, int]:
    """The exemplar's shape; with one per view, the largest's."""
    return max((im.shape[:2] for im in image.values()), key=np.prod) if isinstance(image, dict) else image.shape[:2]


def synthesize(
    exemplar: Any,
    shape: tuple[int, int, int],
    *,
    method: str = "ml",
    rng: Any = None,
    device: Any = None,
    backend: BackendOptions | dict | None = None,
    progress: Callable[[SweepInfo], None] | None = None,
    output: str = "values",
    full_output: bool = False,
    site_map: bool = False,
    params: MLParams | SearchParams | None = None,
    channel_axis: int | None = None,
    **options: Any,
):
    """Grow a solid texture whose slices look like a 2D exemplar.

    Parameters
    ----------
    exemplar : ndarray, str, path or dict
        A 2D grey or segmented image (uint8, uint16 or float), a ``.png``, ``.tif`` or
        ``.npy`` file, or a built-in name (``"brick"``, ``"grass"``, ``"gravel"``; other
        sizes: :func:`clsolid.exemplar.builtin_exemplar`). Or one exemplar per view, a dict
        of two or three of ``"front"`` (the (y, x) plane), ``"right"`` ((y, z)) and ``"top"``
        ((z, x)), each any of the above: each view then matches its own, a view without
        one is free, and ``views`` follows the keys. They may differ in size; grey ones are
        quantised on one shared set of levels, and segmented ones must share one phase set.
        ``"ml"`` sums over them exactly (``likelihood="exact"``), ``"kopf"`` and ``"wl"``
        search them whole (``search="exact"``); ``"chen-wang"`` takes one exemplar.
        A colour PNG or TIFF, or an array with *channel_axis*, is an RGB exemplar (every method).
    shape : tuple of 3 ints
        ``(Z, Y, X)`` size of the block. The block is toroidal (it tiles).
    method : {"ml", "wl", "kopf", "chen-wang"}
        ``"ml"``: NP-MRF maximum likelihood (Urs et al., TIP 2014), options in
        :class:`~clsolid.ml.params.MLParams`. ``"kopf"``: Kopf et al.'s optimisation,
        ``"wl"``: Wei-Levoy, ``"chen-wang"``: Chen & Wang's k-coherence and histograms,
        each extended to 2D->3D (Urs thesis ch. 5), options in
        :class:`~clsolid.search.params.SearchParams`.
    rng : int, numpy.random.Generator or None
        The seed. None: a fresh one (``SynthesisResult.seed`` records it).
    device : str, Device or None
        OpenCL device (:func:`clsolid.select_device` syntax: ``"0:1"``, a name, ``"gpu"``),
        or ``"reference"`` for the float64 NumPy back end (``"ml"`` only, small blocks).
        None: ``$CLSOLID_DEVICE``, ``$PYOPENCL_CTX``, else the best device.
    backend : BackendOptions or dict, optional
        ``"ml"`` only: tiles, a Dask client, a scratch folder, checkpoints, kernel tuning
        (:class:`~clsolid.ml.backends.BackendOptions`). They never change the volume.
    progress : callable, optional
        Called with a :class:`~clsolid.SweepInfo` after every sweep (pass, for the search methods).
    output : {"values", "labels"}
        ``"values"``: the exemplar's own values and dtype (a segmented image's phases stay its
        phases; a grey image's levels are each level's mean). ``"labels"``: level indices
        (``"ml"`` only).
    full_output : bool
        Return a :class:`~clsolid.SynthesisResult` (volume, labels, seed, effective
        parameters, device, timings) instead of the volume alone.
    site_map : bool
        Search methods, with *full_output*: also how often each exemplar pixel is matched
        (``SynthesisResult.site_use``).
    params : MLParams or SearchParams, optional
        The method's parameters as an object; *options* then change some of them.
    channel_axis : int or None
        The axis of an array exemplar's RGB channels, as in scikit-image (None: grey). The
        channels are one joint feature: the label set is a palette of at most ``levels``
        colours (k-means in CIELAB where the exemplar has more), and the volume is
        ``(Z, Y, X, 3)`` in the exemplar's dtype, every voxel a palette colour.
    **options
        The method's parameters by name. The ones to know first:

        - ``neighborhood`` (odd window side; 11 for ``"ml"``, 7 for the others),
        - ``scales`` (multi-scale levels, 3), ``views`` (3: all three, the default; 2: front and
          right only, for layered or directional materials),
        - ``levels`` (most grey levels, 32; an image with at most that many values keeps them),
        - ``"ml"``: ``heuristic``, ``relaxation`` (``"gibbs"``, ``"icm"``, ``"annealing"``),
          ``likelihood``, ``balance``;
        - search methods: ``iterations``, ``search`` (``"exact"``, ``"coherence"``).

        Every option, with its values and default, is in the parameters class's docstring
        and in the option reference of the documentation. A misspelt name is refused with
        the closest valid one.

    Returns
    -------
    ndarray or SynthesisResult
        ``(Z, Y, X)``, or the full result with *full_output*. A search method's block holds
        exemplar values where every voxel is one (``chen-wang``; ``kopf`` on a segmented
        exemplar, or with ``specify``), else float64 means of them (``wl``).

    Raises
    ------
    InputError
        A bad parameter or exemplar; the message names it and what it may be.
    NoDeviceError, DeviceMemoryError, HostMemoryError, KernelBuildError
        No OpenCL device; buffers or a block too large (checked before allocating); a kernel
        that failed to build.

    Examples
    --------
    >>> import clsolid
    >>> volume = clsolid.synthesize("brick", (32, 32, 32), rng=1)          # doctest: +SKIP
    >>> volume = clsolid.synthesize("my.tif", (64, 64, 64), method="kopf")  # doctest: +SKIP
    """
    run_params = method_params(method, params, **options)
    _check_output(output)
    _check_progress(progress)
    shape = check_shape(shape)
    if not isinstance(site_map, bool):
        raise InputError(f"site_map={site_map!r} must be True or False")
    if method != "ml":
        if backend is not None:
            raise InputError(f"backend= is the likelihood method's (tiles, Dask, scratch, checkpoints); {method} "
                             "runs in one piece on one device")
        given = set(options) | ({"search", "views"} if params is not None else set())
        return _synthesize_search(exemplar, shape, run_params, rng, device, progress, output, full_output, site_map,
                                  channel_axis, given=given)
    if site_map:
        raise InputError("site_map=True is the search methods' position histogram; method 'ml' has none")
    run = backend_options(backend)
    image, levels_of, seed = _load(exemplar, run_params.levels, rng, channel_axis)
    run_params = _per_view(image, run_params, "views" in options or params is not None)
    run_params = run_params.for_exemplar(levels_of.n_labels, levels_of.exact, _seam(image), _shape_of(image),
                                         per_view=isinstance(image, dict), colour=levels_of.colour)
    engine = make_backend(device, run)
    hook = None
    if run.checkpoint is not None:
        from .ml.checkpoints import Checkpointer, check_every

        meta = {"method": method, "params": run_params.to_dict(), "shape": list(shape), "seed": seed,
                "device": engine.name}
        hook = Checkpointer(run.checkpoint, check_every(run.checkpoint_every), meta, image)
    log.info("synthesising %s from %s on %s, seed %d", shape, _described(image), engine.name, seed)
    return _run_ml(levels_of, shape, run_params, seed, engine, progress, output, full_output, hook, None)


def _run_ml(levels_of, shape, params, seed, backend, progress, output, full_output, hook, state):
    """Run (or, from *state*, go on with) a likelihood synthesis and shape its result."""
    from .exemplar import each
    from .ml.driver import run_ml

    scratch = backend.scratch
    on_disk = scratch is not None and scratch.on_disk
    labels = levels_of.labels
    check_host_memory(shape, SCRATCH_FOOTPRINT if on_disk else FOOTPRINT,
                      sum(exemplar_terms(im.shape, params.neighborhood) for im in each(labels)))
    if on_disk:
        check_scratch_space(shape, scratch.root)
    try:
        vol, timings, bandwidths = run_ml(levels_of.labels, shape, params, seed, backend, progress,
                                          checkpoint=hook, resume=state, palette=levels_of.features)
        # a run of planes at a time: no whole temporary (host memory); with the state on disk
        # the result is there too, in files that go when its arrays do
        store = scratch if on_disk else Scratch()
        labels = store.apply(np.rint, levels_of.label_dtype, vol, kept=True)
        if params.despeckle and is_categorical(levels_of.n_labels, levels_of.exact):
            timings["despeckled"] = despeckle(labels)
        values = None
        if full_output or output != "labels":
            values = store.apply(levels_of.to_values, levels_of.values.dtype, labels, kept=True,
                                 trailing=levels_of.values.shape[1:])
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


def resume(checkpoint, *, device: Any = None, backend: BackendOptions | dict | None = None,
           progress: Callable[[SweepInfo], None] | None = None, output: str = "values", full_output: bool = False):
    """Go on with a likelihood synthesis from its checkpoint folder, and keep checkpointing there.

    Parameters
    ----------
    checkpoint : str or path
        The folder a run of :func:`synthesize` wrote with ``backend={"checkpoint": ...}``.
    device, progress, output, full_output
        As for :func:`synthesize`. Everything else (exemplar, shape, parameters, seed) is
        the checkpoint's.
    backend : BackendOptions or dict, optional
        How to go on: ``checkpoint_every`` (seconds between the checkpoints written from
        now on), ``tile``, ``client``, ``scratch`` (whether or not the run began in tiles:
        the volume is the same). Its ``checkpoint`` must be unset: the run goes on in its own.

    Returns
    -------
    ndarray or SynthesisResult
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
    _check_progress(progress)
    run = backend_options(backend)
    if run.checkpoint is not None:
        raise InputError(f"checkpoint={run.checkpoint!r}: a resumed run goes on checkpointing in its own folder "
                         f"({checkpoint}); drop it")
    engine = make_backend(device, run)
    store = engine.scratch
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
    if engine.name != meta.get("device"):
        log.warning("resuming on %s a run begun on %s: the volume will differ from the uninterrupted one",
                    engine.name, meta.get("device"))
    run_meta = {k: v for k, v in meta.items() if k != "timings"}  # the Checkpointer adds each sweep's
    hook = Checkpointer(checkpoint, check_every(run.checkpoint_every), run_meta, image)
    log.info("resuming %s at scale %d, after sweep %d", checkpoint, state.scale + 1, state.sweep)
    return _run_ml(levels_of, shape, params, int(meta["seed"]), engine, progress, output, full_output, hook, state)


#: Elements from which a resumed checkpoint's array is read into the scratch folder.
_SCRATCH_LEAST = 1 << 16


def _large_on(store: Scratch) -> Callable[[tuple, Any], np.ndarray]:
    """``empty(shape, dtype)`` that puts whole-block arrays on *store* and small ones in memory."""
    return lambda shape, dtype: (store.empty(shape, dtype) if int(np.prod(shape)) >= _SCRATCH_LEAST
                                 else np.empty(shape, dtype))


def _synthesize_search(exemplar, shape, params: SearchParams, rng, device, progress, output, full_output,
                       site_map: bool, channel_axis: int | None = None, given: set[str] = frozenset()):
    """:func:`synthesize` for the fixed-neighbourhood search methods (``"wl"``, ``"kopf"``, ``"chen-wang"``)."""
    from .exemplar import pooled
    from .search.driver import check_per_view, run_search
    from .search.match import CLMatcher, ReferenceMatcher

    method = params.method
    if output != "values":
        raise InputError(f"method={method!r} combines exemplar values, so it has no level indices: "
                         "use output='values'")
    if site_map and not full_output:
        raise InputError("site_map=True needs full_output=True (the map is SynthesisResult.site_use)")
    image, levels_of, seed = _load(exemplar, params.levels, rng, channel_axis)
    if levels_of.colour and params.specify and "specify" in given:
        raise InputError("specify=True maps grey levels onto the exemplar's histogram; a colour exemplar has none "
                         "(leave specify out)")
    check_host_memory(shape, SEARCH_FOOTPRINT)
    # a colour exemplar is searched as its palette's labels (clsolid.search.palette)
    values = levels_of.labels if levels_of.colour else levels_of.to_values(levels_of.labels)
    if isinstance(image, dict):  # each view searches its own exemplar, whole (check_per_view)
        params = _per_view(image, params, "views" in given)
        if params.search == "coherence" and "search" not in given:
            params = _replace(params, {"search": "exact", "seed_components": None, "coherence_levels": None})
        check_per_view(params, site_map)
        grey = {v: im.astype(np.float64) for v, im in values.items()}
    else:
        grey = values.astype(np.float64)
    n_values = np.unique(pooled(grey)).size
    categorical = is_categorical(n_values, levels_of.exact)
    params = params.for_exemplar(n_values, categorical, colour=levels_of.colour)
    if is_reference(device):
        name, make_matcher = "reference (NumPy float64)", ReferenceMatcher
    else:
        from .core.device import select_device

        dev = select_device(device)
        name, make_matcher = dev.name, partial(CLMatcher, dev)
    log.info("synthesising %s from %s with %s on %s, seed %d", shape, _described(image), method, name, seed)
    vol, timings, use, source = run_search(grey, shape, params, seed, make_matcher, progress, count_sites=site_map,
                                           categorical=categorical, palette=levels_of.features)
    if levels_of.colour or params.keeps_exemplar_values(categorical):  # exact: each voxel is one of the values
        vol = vol.astype(levels_of.label_dtype if levels_of.colour else levels_of.values.dtype)  # colour: labels
        if params.despeckle and categorical and method != "chen-wang":  # chen-wang's voxels stay copies (its map)
            timings["despeckled"] = despeckle(vol)
    labels = None
    if levels_of.colour:
        labels, vol, grey = vol, levels_of.to_values(vol), levels_of.to_values(levels_of.labels)
    if not full_output:
        return vol
    effective = {**params.to_dict(), "shape": list(shape)}
    return SynthesisResult(volume=vol, labels=labels, exemplar=grey, exemplar_labels=levels_of.labels,
                           level_values=levels_of.values, values_exact=levels_of.exact, seed=seed,
                           params=effective, device=name, timings=timings, site_use=use, source=source)
