"""Every OpenCL kernel of clsolid on a small case, for a run under the Oclgrind simulator.

``oclgrind --data-races --uniform-writes python tests/oclgrind_cases.py CASE`` runs one case
on Oclgrind's device and compares what the kernels computed with the float64 NumPy
references, as the fast tests do on the CPU runtimes, while Oclgrind reports on stderr
every invalid memory access and data race of every work-item. Every buffer the case
allocates without contents holds poison until something writes it (:func:`poison_new_buffers`).
``tests/test_oclgrind.py`` runs each case so, in the lanes docs/design.md#kernels-under-a-simulator
describes, and asserts that the case passed and that Oclgrind reported nothing. The cases
are small: the simulator interprets every work-item and checks every access.

The device is opened here, not by :func:`clsolid.select_device`, whose probe would run the
methods' smoke tests in child processes (their reports lost); the vector width it would
find, 16, is given instead. Oclgrind's device reports every device type, GPU and CPU alike,
so clsolid takes its CPU launch shapes on it (work-groups of 4 for the kernels with
per-item arrays, 8 queries a work-item in the best match); ``--gpu-shaped`` takes a GPU's.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from functools import partial
from typing import Callable

import numpy as np

from clsolid.core.platforms import Device, devices_of, platforms

#: Sites per vector in the kernels: the widest, what the probe finds on Oclgrind.
VECTOR_WIDTH = 16
#: What a buffer holds before anything is written to it: NaN as a float32, 2143289343 as an int32.
POISON = 0x7FBFFFFF
#: The cases by name, each run with the device.
CASES: dict[str, Callable[[Device], None]] = {}


@dataclass
class GPUShapedDevice(Device):
    """A device that clsolid treats as a GPU whatever type it reports (the launch shapes a GPU gets)."""

    @property
    def is_cpu(self) -> bool:
        return False


def oclgrind_device(gpu_shaped: bool = False) -> Device:
    """Oclgrind's simulated device, with a context and an in-order queue; every buffer
    allocated on it from now on is poisoned (:func:`poison_new_buffers`)."""
    import pyopencl as cl

    found = [d for p in platforms() if p.name.strip() == "Oclgrind" for d in devices_of(p)]
    if not found:
        raise SystemExit("no Oclgrind platform: run this script under `oclgrind python ...`")
    ctx = cl.Context(found[:1])
    queue = cl.CommandQueue(ctx)
    poison_new_buffers(queue)
    return (GPUShapedDevice if gpu_shaped else Device)(found[0], ctx, queue)


def poison_new_buffers(queue) -> None:
    """Fill every buffer created without contents from now on with :data:`POISON`.

    The check of uninitialised reads from global memory: a kernel that reads what no one
    wrote gets NaN as a float (which spoils the result the case compares) or an index
    far out of range as an int (which Oclgrind reports as an invalid access), where a
    fresh allocation's zeros could pass for data. (Oclgrind's own ``--uninitialized``
    cannot check these kernels: docs/design.md#kernels-under-a-simulator.)
    """
    import pyopencl as cl

    class PoisonedBuffer(cl.Buffer):
        def __init__(self, context, flags, size=0, hostbuf=None):
            super().__init__(context, flags, size, hostbuf)
            if hostbuf is None:
                cl.enqueue_fill_buffer(queue, self, np.uint32(POISON), 0, self.size)

    cl.Buffer = PoisonedBuffer


def case(function: Callable[[Device], None]) -> Callable[[Device], None]:
    """Register *function* as the case named after it (underscores as hyphens)."""
    CASES[function.__name__.replace("_", "-")] = function
    return function


# -- the likelihood method (kernels/core/init.cl, kernels/ml/*.cl) ------------------------------

def _labels(side: int = 12, levels: int = 8) -> np.ndarray:
    """A corner of the built-in brick, quantised: a small exemplar with every kind of window."""
    from clsolid.exemplar import builtin_exemplar, quantise

    return quantise(builtin_exemplar("brick")[:side, :side], levels)


def _ml_state(model, seed: int, sources: bool = False):
    """A random volume, temperatures (some 0), sources ``(views, voxels)`` if asked, and the
    parent block where the model has parent terms."""
    from clsolid.ml.model import parent_block

    rng = np.random.default_rng(seed)
    vol = rng.choice(model.labels, size=model.shape)
    temp = rng.random(model.shape)
    temp[temp < 0.3] = 0.0
    src = rng.integers(0, model.n_sites, (model.offsets.shape[0], vol.size)).astype(np.int32) if sources else None
    parent = None
    if model.parent_rows:
        coarse = rng.choice(model.labels, size=tuple(-(-n // 2) for n in model.shape))
        parent = parent_block(coarse, model.shape)
    return vol, temp, src, parent


def _ml_backends(device: Device, shape, seed: int = 0, sources: bool = False, per_view: bool = False,
                 colour: bool = False, **options):
    """The OpenCL and the reference back end started on one scale of *options*' model, one
    state; with *per_view*, each view its own exemplar, of its own size; with *colour*, the
    labels an 8-colour palette's (each neighbour's three channels compared)."""
    from clsolid.ml.model import build_scale
    from clsolid.ml.opencl import CLBackend
    from clsolid.ml.params import MLParams
    from clsolid.ml.reference import ReferenceBackend

    params = MLParams(**{"scales": 1, **options})
    labels = _labels()
    if per_view:
        labels = {"front": labels, "right": labels.T[:10, :11].copy(), "top": labels[1:10, 2:11].copy()}
    palette = np.random.default_rng(5).uniform(0.0, 100.0, (int(labels.max()) + 1, 3)) if colour else None
    model = build_scale(labels, shape, params, 0, palette)
    vol, temp, src, parent = _ml_state(model, seed, sources)
    backends = CLBackend(device, vector_width=VECTOR_WIDTH), ReferenceBackend()
    for b in backends:
        b.start_scale(model, vol, temp, params, sources=src, parent=parent)
    return model, backends, (model.with_parent(vol, parent), model.with_parent(temp, np.zeros(temp.shape)))


def _assert_lcpdfs_agree(device: Device, shape, sources: bool = False, per_view: bool = False,
                         colour: bool = False, **options) -> None:
    """The normalised log LCPDFs of one conflict-free set, kernels against the reference (the
    fast tests' tolerance), and the sources recorded on the way: sites as near as the
    reference's (on a tie, another site may be the one recorded)."""
    from clsolid.ml.reference import site_distances

    model, (cl_b, ref), (vol, temp) = _ml_backends(device, shape, sources=sources, per_view=per_view, colour=colour,
                                                   **options)
    voxels = np.flatnonzero(model.colour.ravel() == 0)
    got, want = cl_b.lcpdf(voxels), ref.lcpdf(voxels)
    np.testing.assert_allclose(got, want, atol=2e-3 * max(1.0, np.abs(want).max() / 100))
    rows = np.arange(voxels.size)
    if model.per_view:  # sources serve the pruned sum, which takes one exemplar: in range is enough
        assert np.all((cl_b.sources()[:, voxels] >= 0) & (cl_b.sources()[:, voxels] < model.n_sites))
        return
    for view in range(model.offsets.shape[0]):
        a = site_distances(model, vol, temp, voxels, view)
        np.testing.assert_allclose(a[rows, cl_b.sources()[view, voxels]], a[rows, ref.sources()[view, voxels]],
                                   rtol=1e-5, atol=1e-4)


@case
def init(device: Device) -> None:
    """init_random: the random start, bit for bit the reference's, drawn in runs of voxels
    (the last one short), each from its own first voxel."""
    from clsolid.ml.opencl import CLBackend
    from clsolid.ml.reference import ReferenceBackend

    pixels = np.arange(7, dtype=np.float32) * 3
    shape, run = (5, 6, 7), 64
    backend, got = CLBackend(device, vector_width=VECTOR_WIDTH), np.empty(210, np.float32)
    for first in range(0, got.size, run):
        backend.init_part(shape, 9, pixels, first, got[first: first + run])
    np.testing.assert_array_equal(got.reshape(shape), ReferenceBackend().init_volume(shape, 9, pixels))


@case
def exact(device: Device) -> None:
    """parzen_groups and lcpdf: squared differences, phase mismatches and weighted ones, a
    fall-off, parent terms, an exemplar per view (each view its own run of chunks), colours
    (each neighbour's channels, with parent terms)."""
    shape = (5, 6, 7)
    _assert_lcpdfs_agree(device, shape, neighborhood=5, views=3)
    _assert_lcpdfs_agree(device, shape, neighborhood=3, distance="mismatch", falloff=1.0)
    _assert_lcpdfs_agree(device, shape, neighborhood=3, views=3, distance="weighted")
    _assert_lcpdfs_agree(device, shape, neighborhood=3, scales=2, parent_weight=4.0, parent_min_side=0)
    _assert_lcpdfs_agree(device, shape, per_view=True, neighborhood=3, views=3)
    _assert_lcpdfs_agree(device, shape, colour=True, neighborhood=3, views=3, scales=2, parent_weight=2.0,
                         parent_min_side=0)


@case
def pruned(device: Device) -> None:
    """parzen_candidates (with and without a sample, and on colours), projected_nearest (every
    site, and lists of sites) and prune_flags (hot and sourceless voxels sent to the exact sum)."""
    shape = (5, 6, 7)
    common = dict(neighborhood=3, likelihood="pruned", sources=True)
    _assert_lcpdfs_agree(device, shape, prune_similar=4, prune_sample=9, distance="weighted", **common)
    _assert_lcpdfs_agree(device, shape, views=3, prune_similar=4, prune_sample=5, colour=True, **common)
    _assert_lcpdfs_agree(device, shape, views=3, prune_similar=4, prune_sample=0, prune_projected=4,
                         prune_projected_k=6, **common)
    _assert_lcpdfs_agree(device, shape, prune_similar=2, prune_sample=5, prune_projected=4, prune_projected_k=6,
                         prune_projected_probe=2, **common)
    model, (cl_b, ref), _ = _ml_backends(device, shape, likelihood="pruned", neighborhood=3, prune_min_weight=0.6,
                                      prune_sample=0)  # no sources yet and hot neighbours: the exact sum
    voxels = np.flatnonzero(model.colour.ravel() == 1)
    np.testing.assert_allclose(cl_b.lcpdf(voxels), ref.lcpdf(voxels), atol=2e-3)
    assert 0 < cl_b.exact_visits == voxels.size


@case
def decide(device: Device) -> None:
    """decide (every relaxation, h2 and h1 heuristics, the balance's scores) and pack_state:
    one step of every conflict-free set against the reference's."""
    from clsolid.core.philox import relax_tag

    for relaxation, heuristic in (("icm", "h2-product"), ("gibbs", "h1-mean"), ("annealing", "h2-min"),
                                  ("gibbs", "h1-lowest")):
        model, (cl_b, ref), _ = _ml_backends(device, (6, 6, 7), seed=2, neighborhood=3, views=3, heuristic=heuristic,
                                          relaxation=relaxation)
        bias = np.linspace(-0.5, 0.5, model.labels.size)
        for b in (cl_b, ref):
            b.start_sweep(5, relax_tag(0, 3), 0.7, bias)
        for colour in np.unique(model.colour):
            voxels = np.flatnonzero(model.colour.ravel() == colour)
            for b in (cl_b, ref):
                b.update(voxels)
        agree = np.mean(cl_b.volume() == ref.volume())
        assert agree >= 0.98, f"{relaxation}, {heuristic}: {agree:.1%} of the voxels agree"
        np.testing.assert_allclose(cl_b.temperature(), ref.temperature(), atol=1e-6)
        rows = np.flatnonzero(ref.scores().any(axis=1))
        np.testing.assert_allclose(cl_b.scores()[rows], ref.scores()[rows], rtol=1e-4, atol=2e-3)
        voxels = np.arange(0, cl_b.volume().size, 5)
        values, temps, sources = cl_b.read_voxels(voxels)
        np.testing.assert_array_equal(values, cl_b.volume().ravel()[voxels])
        np.testing.assert_array_equal(temps, cl_b.temperature().ravel()[voxels])
        np.testing.assert_array_equal(sources, cl_b.sources()[:, voxels])


def _ml_run(backend, **options):
    """A tiny two-scale run (the balance off: its fit turns float32's last bits into other biases)."""
    from clsolid.ml.driver import run_ml
    from clsolid.ml.params import MLParams

    params = MLParams(**{"neighborhood": 3, "scales": 2, "insert_slices": 1, "balance": 0.0, **options})
    return run_ml(_labels(), (8, 8, 8), params, 11, backend)[0]


@case
def ml_run(device: Device) -> None:
    """A whole run, every kernel of the method in the driver's order: against the reference's
    volume (as the fast tests ask: 99 % of the voxels alike), and tiled, the same volume."""
    from clsolid.ml.opencl import CLBackend
    from clsolid.ml.reference import ReferenceBackend
    from clsolid.ml.tiled import LocalTiles, TiledBackend

    got = _ml_run(CLBackend(device, vector_width=VECTOR_WIDTH))
    agree = np.mean(got == _ml_run(ReferenceBackend()))
    assert agree >= 0.99, f"{agree:.1%} of the voxels agree with the reference's"
    tiled = _ml_run(TiledBackend(LocalTiles(CLBackend(device, vector_width=VECTOR_WIDTH)), 4))
    np.testing.assert_array_equal(tiled, got)


@case
def ml_pruned_run(device: Device) -> None:
    """A whole pruned run with projected candidates and Gibbs draws, against the reference's."""
    from clsolid.ml.opencl import CLBackend
    from clsolid.ml.reference import ReferenceBackend

    options = dict(likelihood="pruned", prune_similar=4, prune_sample=5, prune_projected=4, prune_projected_k=4,
                   relaxation="gibbs")
    got = _ml_run(CLBackend(device, vector_width=VECTOR_WIDTH), **options)
    agree = np.mean(got == _ml_run(ReferenceBackend(), **options))
    assert agree >= 0.97, f"{agree:.1%} of the voxels agree with the reference's"


# -- the search methods (kernels/search/*.cl) --------------------------------------------------

def _grey(shape=(12, 13), seed: int = 1) -> np.ndarray:
    """Integer grey levels: every float32 distance is exact, so device and reference agree exactly."""
    return np.random.default_rng(seed).integers(0, 32, shape).astype(np.float64)


def _matcher(device: Device, table, mismatch: int = 0, max_batch: int = 64):
    """The device's matcher, with launches of a few queries: Oclgrind's checks take a time
    that grows with the buffers a kernel is given, however little of them it reads."""
    from clsolid.search.match import CLMatcher

    return CLMatcher(device, table, max_batch=max_batch, mismatch=mismatch, vector_width=VECTOR_WIDTH)


@case
def match(device: Device) -> None:
    """k_nearest (the best match and lists of 5, unit and general weights, phase codes, a
    ragged last launch) and candidate_distances (with absent candidates), exactly the reference's."""
    from clsolid.search.match import ReferenceMatcher, exemplar_table

    rng = np.random.default_rng(4)
    table, _ = exemplar_table(_grey(), 3)
    queries = np.clip(table[rng.integers(0, table.shape[0], 37)] + rng.integers(-3, 4, (37, 9)), 0, 31)
    general = rng.choice(np.array([0.0, 0.5, 1.0, 2.0], np.float32), 9)
    candidates = rng.integers(-1, table.shape[0], (37, 5))
    for mismatch in (0, 4):
        device_side = _matcher(device, table, mismatch, max_batch=16)
        reference = ReferenceMatcher(table, mismatch=mismatch)
        for weights in (None, general):
            for count in (1, 5):
                for got, want in zip(device_side.nearest(queries, count, weights), reference.nearest(queries, count)):
                    np.testing.assert_array_equal(got, want.astype(got.dtype))
            np.testing.assert_array_equal(device_side.distances(queries, candidates),
                                          reference.distances(queries, candidates).astype(np.float32))
            reference = ReferenceMatcher(table, general, mismatch)


@case
def tensor(device: Device) -> None:
    """convolve (mirrored and wrapped, plain and odd taps), products, tensor_features,
    tensor_std and tensor_best for every metric (a causal weight of 0 included), against
    the float64 references to float32 rounding."""
    from clsolid.tensor import METRICS, neighbourhood_dissimilarity, structure_tensor
    from clsolid.tensor.opencl import TensorMatcher
    from clsolid.tensor.opencl import structure_tensor as device_structure_tensor

    image = _grey((9, 11))
    for boundary in ("reflect", "wrap"):
        ref = structure_tensor(image, 1.0, 1.0, boundary)
        got = device_structure_tensor(device, image, 1.0, 1.0, boundary)
        assert np.abs(got - ref).max() <= 1e-5 * np.abs(ref).max(), boundary
    flat = ref.reshape(-1, 3)
    rng = np.random.default_rng(5)
    table, queries = flat[rng.choice(len(flat), (13, 4))], flat[rng.choice(len(flat), (5, 4))]
    weights = np.array([1.0, 0.0, 2.0, 1.0])
    for metric in METRICS:
        matcher = TensorMatcher(device, table, metric, alpha=0.5, eps=1.0, weights=weights)
        want = neighbourhood_dissimilarity(queries[:, None], table[None], metric, 0.5, 1.0, weights)
        got = matcher.distances(queries)
        assert np.abs(got - want).max() <= 1e-5 * np.abs(want).max(), metric
        site, _ = matcher.best(queries)
        assert np.all(want[np.arange(5), site] <= want.min(axis=1) + 1e-5 * np.abs(want).max()), metric


@case
def gather(device: Device) -> None:
    """voxel_queries (with and without a parent level, every view, wrapping squares) and
    project_queries: the device's gathers against NumPy's."""
    from clsolid.search.block import DeviceBlock
    from clsolid.search.features import centre_weights, exemplar_features, voxel_features
    from clsolid.search.projection import Projection
    from clsolid.search.pyramid import gaussian_pyramid

    rng = np.random.default_rng(5)
    pyr = gaussian_pyramid(_grey((12, 14)), 2)
    k, shape = 3, (5, 6, 7)
    vol = np.round(rng.random(shape) * 31)
    voxels = rng.permutation(vol.size)[:100]
    for parent in (None, np.round(rng.random((3, 3, 4)) * 31)):
        table, _ = exemplar_features(pyr[0], None if parent is None else pyr[1], k)
        matcher = _matcher(device, table, max_batch=40)  # several launches
        w = centre_weights(k, parent is not None, centre=False)
        for view in ("front", "right", "top"):
            got = DeviceBlock(matcher).best(view, voxels, vol, parent, k, w)
            want = matcher.best(voxel_features(vol, parent, voxels, view, k), w)
            for a, b in zip(got, want):
                np.testing.assert_array_equal(a, b)
        proj = Projection(matcher.table, w, 4)
        site, dist = DeviceBlock(matcher).best_projected("right", voxels, vol, parent, k, proj)
        want_site, want_dist = proj.best_reference(voxel_features(vol, parent, voxels, "right", k))
        same = site == want_site
        assert same.mean() >= 0.95, f"{same.mean():.1%} of the projected matches agree"
        np.testing.assert_allclose(dist[same], want_dist[same], rtol=1e-5)


@case
def coherence(device: Device) -> None:
    """coherence_best (without and with the index histogram's ranking, a parent level, views
    with nothing known), against Coherence.best on NumPy's gathers."""
    from clsolid.core.schedule import colour_sets
    from clsolid.search.coherence import SIMILAR, Coherence
    from clsolid.search.features import centre_weights, exemplar_features, valid_sites, voxel_features
    from clsolid.search.match import candidate_sets
    from clsolid.search.pyramid import gaussian_pyramid

    rng = np.random.default_rng(3)
    pyr = gaussian_pyramid(_grey((12, 14)), 2)
    k, shape, views = 3, (5, 6, 6), ("front", "right", "top")
    for coarse, spread_eps in ((None, None), (np.round(rng.random((3, 3, 3)) * 31), 0.3)):
        parent = coarse is not None
        table, _ = exemplar_features(pyr[0], pyr[1] if parent else None, k)
        rows, cols = valid_sites(pyr[0].shape, pyr[1].shape if parent else None, k)
        matcher = _matcher(device, table)
        similar = candidate_sets(matcher, table, SIMILAR, centre_weights(k, parent, centre=True))
        twins = [Coherence(rows, cols, pyr[0].shape, similar, shape, views, spread_eps) for _ in range(2)]
        known = rng.integers(-rows.size // 3, rows.size, (len(views), int(np.prod(shape)))) // 4
        for twin in twins:
            twin.matched[...] = np.maximum(known, -1)
            twin.matched[0] = -1  # nothing known in the front view: every voxel searched exhaustively
            twin.count_usage()
        vol = np.round(rng.random(shape) * 31)
        colour = colour_sets(shape, k // 2)[0].ravel()
        w = centre_weights(k, parent, centre=False)
        for voxels in (np.flatnonzero(colour == colour[0]), np.arange(vol.size)):
            for i, view in enumerate(views):
                got = twins[0].search(matcher, i, voxels, vol, coarse, k, w)
                want = twins[1].best(matcher, i, voxels, voxel_features(vol, coarse, voxels, view, k), w)
                for a, b in zip(got, want):
                    np.testing.assert_array_equal(a, b)
                np.testing.assert_array_equal(twins[0].matched, twins[1].matched)


@case
def search_runs(device: Device) -> None:
    """Whole runs of wl, kopf and chen-wang (exact and coherence searches, one scale of integer
    grey levels), each exactly the reference's block."""
    from clsolid.search.driver import run_search
    from clsolid.search.match import ReferenceMatcher
    from clsolid.search.params import SearchParams

    exemplar = _grey((14, 14), seed=2)
    for method, search in (("wl", "exact"), ("kopf", "coherence"), ("chen-wang", "coherence")):
        params = SearchParams(method=method, neighborhood=3, scales=2, iterations=1, search=search, specify=False)
        got = run_search(exemplar, (6, 6, 7), params, 3, partial(_matcher, device)).volume
        want = run_search(exemplar, (6, 6, 7), params, 3, ReferenceMatcher).volume
        agree = np.mean(np.isclose(got, want, rtol=0, atol=1e-3))  # kopf's means: float32's last bits
        assert agree >= 0.99, f"{method}: {agree:.1%} of the voxels agree with the reference's"


# -- the harness's own check -------------------------------------------------------------------

#: A kernel with a fault on each line from 6 to 11 (each named there), which the checks must report.
CANARY = """__kernel void canary(__global const float *a, __global const int *unwritten, __global const float *fresh,
                     __global float *out, __global float *copy, __local float *shared)
{
    int i = get_global_id(0), l = get_local_id(0);
    float unset[2];
    shared[l] = a[i];                                   /* 6: raced by the read on line 9 */
    float past = a[i + 1];                              /* 7: past the buffer's end at i = 7 */
    float poisoned = a[unwritten[i]];                   /* 8: an index no one wrote */
    out[i] = past + poisoned + shared[(l + 1) % 4]      /* 9: another work-item's, unsynchronised */
             + unset[i % 2];                            /* 10: an uninitialised private value */
    copy[i] = fresh[i];                                 /* 11: a float no one wrote */
}
"""


@case
def canary(device: Device) -> None:
    """:data:`CANARY`, built unoptimised (so that the compiler keeps its unset read): Oclgrind
    must report lines 6 to 10 (``tests/test_oclgrind.py`` asserts it does), and the float no
    one wrote (line 11) arrives poisoned."""
    import pyopencl as cl

    mf, ctx = cl.mem_flags, device.context
    a = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.arange(8, dtype=np.float32))
    unwritten, fresh = cl.Buffer(ctx, mf.READ_ONLY, 32), cl.Buffer(ctx, mf.READ_ONLY, 32)
    out, copy = cl.Buffer(ctx, mf.WRITE_ONLY, 32), cl.Buffer(ctx, mf.WRITE_ONLY, 32)
    program = cl.Program(ctx, CANARY).build(options=["-cl-opt-disable"])
    program.canary(device.queue, (8,), (4,), a, unwritten, fresh, out, copy, cl.LocalMemory(16))
    got = np.empty(8, np.float32)
    cl.enqueue_copy(device.queue, got, copy)
    assert np.isnan(got).all(), f"a fresh buffer read {got}, not the poison"


def main(argv: list[str] | None = None) -> int:
    """Run one case on Oclgrind's device; print its time. A result unlike the reference's
    raises (exit status 1)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", choices=sorted(CASES))
    parser.add_argument("--gpu-shaped", action="store_true", help="take the launch shapes a GPU gets")
    args = parser.parse_args(argv)
    device = oclgrind_device(args.gpu_shaped)
    start = time.perf_counter()
    CASES[args.case](device)
    print(f"{args.case}: passed in {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
