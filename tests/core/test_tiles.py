"""Tiles (docs/design.md#tiles): the tile geometry, and a tiled run that gives the one-piece run's
volume voxel for voxel, with its memory checked per tile."""

import os

import numpy as np
import pytest
from conftest import slow_except

import clsolid
from clsolid.cli import EXIT_USAGE, main
from clsolid.core.hostmemory import ENV, SCRATCH_BYTES_PER_VOXEL, check_scratch_space, exemplar_terms
from clsolid import api as api_module
from clsolid.core import checkpoint as checkpoint_module, scratch as scratch_module
from clsolid.core.scratch import Scratch
from clsolid.core.tiles import Tiling, gather, split_axis
from clsolid.errors import DeviceMemoryError, HostMemoryError, InputError
from clsolid.exemplar import builtin_exemplar, quantise
from clsolid.ml import tiled
from clsolid.ml.backends import FOOTPRINT
from clsolid.ml.driver import run_ml
from clsolid.ml.model import build_scale
from clsolid.ml.opencl import CLBackend
from clsolid.ml.params import MLParams
from clsolid.ml.tiled import LocalTiles, TiledBackend, check_tile, halo_width, largest_tile

#: gravel at 16^2, for whole runs small enough to repeat.
GRAVEL16 = builtin_exemplar("gravel", size=16)

SHAPE = (20, 16, 18)  # no two axes alike; tiles of 8: 7, 7, 6 by 8, 8 by 6, 6, 6


@pytest.fixture(scope="module")
def labels(brick_labels):
    """A 16x16 corner of the brick at 8 levels: runs at 20^3 take a second."""
    return quantise(brick_labels[:16, :16], 8)


# -- geometry ------------------------------------------------------------------------


@pytest.mark.parametrize("size, edge, lengths", [(20, 8, [7, 7, 6]), (16, 8, [8, 8]), (5, 8, [5]), (7, 1, [1] * 7)])
def test_split_axis_is_even_and_covers_the_axis(size, edge, lengths):
    cuts = split_axis(size, edge)
    assert [n for _, n in cuts] == lengths
    assert [s for s, _ in cuts] == list(np.cumsum([0] + lengths[:-1]))


@pytest.mark.parametrize("shape, edge, halo", [((20, 18, 22), 8, 2), ((9, 16, 5), 4, 3), ((6, 6, 6), 6, 2),
                                               ((12, 7, 10), 5, 4)])
def test_tiles_gather_with_wrap_and_give_their_cores_back(shape, edge, halo):
    a = np.random.default_rng(0).random((2,) + shape)  # a leading axis (views) comes along
    tiling = Tiling(shape, edge, halo)
    cover = np.zeros(shape, int)
    out = np.zeros_like(a)
    padded = np.pad(a, [(0, 0)] + [(halo, halo)] * 3, mode="wrap")
    for tile in tiling.tiles:
        cover[tile.core()] += 1
        block = gather(a, tile)
        assert block.shape == (2,) + tile.block_shape
        for axis, (s, n, lead, b, size) in enumerate(zip(tile.start, tile.size, tile.lead, tile.block_shape, shape)):
            if b == size:  # the whole axis, as the block has it: the tile's wrap is the block's
                assert lead == s and tile.origin[axis] == 0
            else:  # the core with a halo on both sides, wrapped round the block's edges
                assert lead == halo and b == n + 2 * halo < size
        whole = tuple(slice(None) if b == n else slice(s, s + b)
                      for s, b, n in zip(tile.start, tile.block_shape, shape))
        if all(b < n for b, n in zip(tile.block_shape, shape)):
            np.testing.assert_array_equal(block, padded[(...,) + whole])
        np.testing.assert_array_equal(block[(...,) + tile.inner()], a[(...,) + tile.core()])
        out[(...,) + tile.core()] = block[(...,) + tile.inner()]
        core = np.ravel_multi_index(np.indices(tile.size).reshape(3, -1) + np.array(tile.start)[:, None], shape)
        np.testing.assert_array_equal(block[0].ravel()[tile.local(core)], a[0].ravel()[core])
    assert (cover == 1).all()  # the cores partition the block
    np.testing.assert_array_equal(out, a)
    assert tiling.largest_block == tuple(max(t.block_shape[i] for t in tiling.tiles) for i in range(3))


def test_group_finds_each_voxels_tile():
    tiling = Tiling(SHAPE, 8, 2)
    voxels = np.random.default_rng(1).choice(np.prod(SHAPE), 500, replace=False)
    seen = []
    for tile, part in tiling.group(voxels):
        coords = np.unravel_index(part, SHAPE)
        assert all(((c >= s) & (c < s + n)).all() for c, s, n in zip(coords, tile.start, tile.size))
        seen.extend(part)
    assert sorted(seen) == sorted(voxels)


def test_halo_is_the_farthest_read(labels):
    for k, views, half in ((5, 2, 2), (3, 3, 1), (9, 3, 4)):
        model = build_scale(labels, SHAPE, MLParams(neighborhood=k, views=views, scales=1), 0)
        assert halo_width(model) == half == np.abs(model.union_offsets).max()


# -- a tiled run is the one-piece run ------------------------------------------------------------

CASES = [  # each relaxation with 2 and 3 views, exact and pruned; balance on (the default); polish sweeps
    dict(relaxation="icm", views=2, likelihood="exact", tile=8),
    dict(relaxation="icm", views=3, likelihood="pruned", tile=10),  # the coarse scale in one tile
    dict(relaxation="gibbs", views=2, likelihood="pruned", tile=8),
    dict(relaxation="gibbs", views=3, likelihood="exact", tile=10),
    dict(relaxation="annealing", views=2, likelihood="exact", tile=7),
    dict(relaxation="annealing", views=3, likelihood="pruned", tile=8),
    dict(relaxation="gibbs", views=2, likelihood="pruned", distance="weighted", tile=8),
    dict(relaxation="gibbs", views=3, likelihood="exact", distance="mismatch", tile=10),
    dict(relaxation="gibbs", views=2, likelihood="pruned", polish_sweeps=1, tile=8),
    dict(relaxation="annealing", views=2, likelihood="exact", polish_sweeps=1, tile=7),
]


def _params(case):
    return MLParams(neighborhood=5, scales=2, sweeps=2,
                    **{k: v for k, v in case.items() if k != "tile"})


@pytest.mark.parametrize("case", slow_except(CASES, 3, 9), ids=lambda c: "-".join(str(v) for v in c.values()))
def test_tiled_run_is_the_one_piece_run(device, labels, case):
    params = _params(case)
    whole = CLBackend(device)
    tiles = TiledBackend(LocalTiles(CLBackend(device)), case["tile"])
    a = run_ml(labels, SHAPE, params, 7, whole)[0]
    b = run_ml(labels, SHAPE, params, 7, tiles)[0]
    assert len(tiles.tiling.tiles) > 1
    np.testing.assert_array_equal(a, b)
    assert (whole.exact_visits, whole.pruned_visits) == (tiles.exact_visits, tiles.pruned_visits)


@pytest.mark.slow
def test_a_halo_too_narrow_changes_the_volume(device, labels, monkeypatch):
    """The equality above is no accident of the tiles: one voxel less of halo and it is gone."""
    params = _params(CASES[2])
    a = run_ml(labels, SHAPE, params, 7, CLBackend(device))[0]
    narrow = halo_width
    monkeypatch.setattr(tiled, "halo_width", lambda model: narrow(model) - 1)
    b = run_ml(labels, SHAPE, params, 7, TiledBackend(LocalTiles(CLBackend(device)), 8))[0]
    assert (a != b).mean() > 0.05


def test_random_start_in_runs_is_the_same(device, monkeypatch):
    pixels = np.arange(40.0).reshape(5, 8)
    whole = CLBackend(device).init_volume(SHAPE, 3, pixels)
    monkeypatch.setattr(type(device), "max_alloc", property(lambda self: 1000))  # 250 voxels a run
    np.testing.assert_array_equal(CLBackend(device).init_volume(SHAPE, 3, pixels), whole)


# -- memory, options, CLI, checkpoints ----------------------------------------------------------


@pytest.mark.slow
def test_memory_is_checked_per_tile(device, monkeypatch):
    """One piece does not fit a 1 MiB buffer limit: the error names the largest tile that does."""
    binary = (np.random.default_rng(2).random((16, 16)) > 0.5).astype(np.uint8)
    monkeypatch.setattr(type(device), "max_alloc", property(lambda self: 1 << 20))
    kw = dict(neighborhood=5, scales=2, rng=1, device=device, levels=2)
    with pytest.raises(DeviceMemoryError, match=r"tile=(\d+) \(--tile \1\) is the largest that fits") as info:
        clsolid.synthesize(binary, (64, 64, 64), **kw)
    edge = int(str(info.value).split("tile=")[1].split(" ")[0])
    params = MLParams(neighborhood=5, scales=2, levels=2).for_exemplar(2, True, 0.0, binary.shape)
    models = [build_scale(binary, (64, 64, 64), params, level) for level in (1, 0)]
    engine = CLBackend(device)
    assert largest_tile(engine, models, params) == edge  # the pruned sum's tables counted
    check_tile(engine, models, edge, params)  # fits
    with pytest.raises(DeviceMemoryError, match=f"tile={edge + 1} the device holds"):
        check_tile(engine, models, edge + 1, params)
    with pytest.raises(DeviceMemoryError, match="with tile=64 the device holds .* use a smaller tile"):
        clsolid.synthesize(binary, (64, 64, 64), backend={"tile": 64}, **kw)


def test_tile_option_is_checked(device):
    with pytest.raises(InputError, match="tile=0 must be a positive integer"):
        clsolid.synthesize("gravel", (8, 8, 8), backend={"tile": 0}, device=device)
    with pytest.raises(InputError, match="tile=4 is for OpenCL devices"):
        clsolid.synthesize("gravel", (8, 8, 8), backend={"tile": 4}, device="reference")


@pytest.mark.slow
def test_cli_tile_flag(tmp_path, device):
    args = ["--shape", "12", "10", "14", "--neighborhood", "5", "--scales", "2", "--seed", "4", "--builtin-size",
            "16", "--max-sweeps", "3", "-q"]
    assert main(["synth", "gravel", "-o", str(tmp_path / "a.npy"), *args]) == 0
    assert main(["synth", "gravel", "-o", str(tmp_path / "b.npy"), *args, "--tile", "5"]) == 0
    np.testing.assert_array_equal(np.load(tmp_path / "a.npy"), np.load(tmp_path / "b.npy"))
    assert main(["synth", "gravel", "-o", str(tmp_path / "c.npy"), *args, "--tile", "0"]) == EXIT_USAGE
    assert main(["synth", "gravel", "-o", str(tmp_path / "d.npy"), "--method", "wl", "--tile", "5", "-q"]) == EXIT_USAGE


@pytest.mark.slow
def test_tiled_checkpoint_resumes_identically(tmp_path, device, monkeypatch):
    """A tiled run's checkpoint holds the whole arrays: it resumes, tiled, to the one-piece volume."""
    kw = dict(neighborhood=5, scales=2, rng=4, sweeps=3, likelihood="pruned", device=device)
    whole = clsolid.synthesize(GRAVEL16, (12, 10, 14), **kw)
    seen = []

    class Stop(Exception):
        pass

    def stop(info):
        seen.append(info.sweep)
        if len(seen) == 4:  # the second sweep of the finest scale
            raise Stop

    (tmp_path / "scratch").mkdir()  # the state on disk, checkpointed from there
    with pytest.raises(Stop):
        clsolid.synthesize(GRAVEL16, (12, 10, 14), progress=stop, backend={"tile": 5, "checkpoint": tmp_path / "run",
                           "scratch": tmp_path / "scratch"}, **kw)
    assert list((tmp_path / "scratch").iterdir()) == []  # removed on the way out
    read = []  # the checkpoint's arrays go to the scratch folder as they are read (a small block: all of them)
    monkeypatch.setattr(api_module, "_SCRATCH_LEAST", 0)
    monkeypatch.setattr(checkpoint_module, "_read_member",
                        lambda *a, real=checkpoint_module._read_member: read.append(real(*a)) or read[-1])
    np.testing.assert_array_equal(clsolid.resume(tmp_path / "run", device=device,
                                                 backend={"tile": 6, "scratch": tmp_path / "scratch"}),
                                  whole)
    assert read and all(isinstance(a, np.memmap) for a in read)
    assert list((tmp_path / "scratch").iterdir()) == []


@pytest.mark.slow
def test_region_order_is_a_visiting_order_the_tiles_keep(device, tmp_path, monkeypatch):
    """region=N visits each region's sets before the next region's: another sequential order, so
    another volume than the set-by-set sweep, but the same one in tiles (of any edge), on disk,
    and resumed from a checkpoint. With tiles of the regions' edge a tile's state stays on the
    device from one set to the next: it is sent once a region and sweep, not once a set."""
    kw = dict(neighborhood=5, scales=2, rng=4, sweeps=2, device=device, region=6)
    one = clsolid.synthesize(GRAVEL16, (12, 10, 14), **kw)
    assert not np.array_equal(one, clsolid.synthesize(GRAVEL16, (12, 10, 14), **{**kw, "region": 0}))
    loads, real = [], CLBackend.load_state
    monkeypatch.setattr(CLBackend, "load_state", lambda self, *a, **k: loads.append(1) or real(self, *a, **k))
    np.testing.assert_array_equal(clsolid.synthesize(GRAVEL16, (12, 10, 14), backend={"tile": 6}, **kw), one)
    held, loads[:] = len(loads), []
    np.testing.assert_array_equal(clsolid.synthesize(GRAVEL16, (12, 10, 14), backend={"tile": 5, "scratch": tmp_path}, **kw), one)
    assert held * 4 < len(loads)  # tiles of 5 cut the regions of 6: sent again for every set

    class Stop(Exception):
        pass

    def stop(info):
        if info.scale == 2 and info.sweep == 1:
            raise Stop

    with pytest.raises(Stop):
        clsolid.synthesize(GRAVEL16, (12, 10, 14), progress=stop, backend={"tile": 6, "checkpoint": tmp_path / "run"}, **kw)
    np.testing.assert_array_equal(clsolid.resume(tmp_path / "run", device=device), one)


# -- the state on disk (scratch) -----------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("case", [CASES[1], CASES[4]], ids=["icm-pruned-3views", "annealing-exact"])
def test_state_on_disk_gives_the_same_volume(device, labels, case, tmp_path):
    """The whole-block arrays as memory-mapped files: the one-piece run's volume, and the
    files are removed when the run ends."""
    params = _params(case)
    a = run_ml(labels, SHAPE, params, 7, CLBackend(device))[0]
    with Scratch(tmp_path) as scratch:
        tiles = TiledBackend(LocalTiles(CLBackend(device)), case["tile"], scratch)
        b = run_ml(labels, SHAPE, params, 7, tiles)[0]
        assert isinstance(tiles.volume(), np.memmap) and isinstance(tiles.temperature(), np.memmap)
        assert isinstance(tiles._src, np.memmap) and os.path.dirname(tiles.volume().filename) == scratch.folder
        np.testing.assert_array_equal(a, b)
        # freed as they went: the finest scale's state, and its random start gone
        assert sorted(os.listdir(scratch.folder)) == sorted(os.path.basename(x.filename)
                                                             for x in (tiles._vol, tiles._temp, tiles._src))
    assert os.listdir(tmp_path) == []


@pytest.mark.slow
def test_scratch_through_the_api_and_the_cli(device, tmp_path):
    kw = dict(neighborhood=5, scales=2, rng=4, sweeps=2, device=device)
    whole = clsolid.synthesize(GRAVEL16, (12, 10, 14), **kw)
    on_disk = clsolid.synthesize(GRAVEL16, (12, 10, 14), backend={"tile": 5, "scratch": tmp_path}, full_output=True, **kw)
    assert isinstance(on_disk.volume, np.memmap) and isinstance(on_disk.labels, np.memmap)  # the result there too
    np.testing.assert_array_equal(on_disk.volume, whole)
    assert os.listdir(tmp_path) == []  # its folder removed, the result's files nameless
    with pytest.raises(InputError, match="give tile=N too"):
        clsolid.synthesize(GRAVEL16, (12, 10, 14), backend={"scratch": tmp_path}, **kw)
    with pytest.raises(InputError, match="does not exist"):
        clsolid.synthesize(GRAVEL16, (12, 10, 14), backend={"tile": 5, "scratch": tmp_path / "nowhere"}, **kw)
    with pytest.raises(InputError, match="is for OpenCL devices"):
        clsolid.synthesize(GRAVEL16, (12, 10, 14), backend={"tile": 5, "scratch": tmp_path}, **{**kw, "device": "reference"})
    args = ["--shape", "12", "10", "14", "--neighborhood", "5", "--scales", "2", "--seed", "4", "--builtin-size",
            "16", "--sweeps", "2", "-q"]
    out = tmp_path / "out"
    out.mkdir()
    assert main(["synth", "gravel", "-o", str(out / "a.npy"), *args]) == 0
    assert main(["synth", "gravel", "-o", str(out / "b.npy"), *args, "--tile", "5", "--scratch", str(tmp_path)]) == 0
    np.testing.assert_array_equal(np.load(out / "a.npy"), np.load(out / "b.npy"))
    assert main(["synth", "gravel", "-o", str(out / "c.npy"), *args, "--scratch", str(tmp_path)]) == EXIT_USAGE
    assert sorted(os.listdir(tmp_path)) == ["out"]


def test_scratch_space_is_checked_first(device, tmp_path, monkeypatch):
    import shutil

    usage = shutil.disk_usage(tmp_path)
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage._replace(free=64**3 * SCRATCH_BYTES_PER_VOXEL - 1))
    with pytest.raises(InputError, match=r"64x64x64 block keeps about .* GiB free; free space there"):
        clsolid.synthesize("gravel", (64, 64, 64), backend={"tile": 16, "scratch": tmp_path}, device=device)
    assert list(tmp_path.iterdir()) == []  # refused before anything was allocated: no folder left
    check_scratch_space((63, 64, 64), str(tmp_path))  # fits


def test_scratch_arrays(tmp_path, monkeypatch):
    monkeypatch.setattr(scratch_module, "_RUN_ELEMENTS", 35)  # apply: a plane of 5 x 7 at a time
    with Scratch() as ram:
        assert not ram.on_disk and type(ram.empty((2, 3), np.int32)) is np.ndarray
    source = np.arange(24, dtype=np.float64).reshape(2, 3, 4) + 0.25
    with Scratch(tmp_path) as disk:
        copied = disk.copy(source, np.float32)
        np.testing.assert_array_equal(copied, source.astype(np.float32))
        filled = disk.full((5,), -1, np.int32)
        assert isinstance(filled, np.memmap) and (filled == -1).all() and len(os.listdir(disk.folder)) == 2
        t = np.linspace(-1, 1, 3 * 5 * 7).reshape(3, 5, 7)
        applied = disk.apply(lambda a, b: (a > 0) | b, bool, t, t < -0.5)
        np.testing.assert_array_equal(applied, (t > 0) | (t < -0.5))
        disk.free(applied)
        disk.free(copied)
        disk.free(source)  # not its own: nothing happens
        assert os.listdir(disk.folder) == [os.path.basename(filled.filename)]
    assert os.listdir(tmp_path) == []


@pytest.mark.slow
def test_the_host_check_counts_what_stays_in_memory(device, tmp_path, monkeypatch):
    kw = dict(neighborhood=5, scales=2, rng=4, sweeps=1, device=device)
    shape = (12, 10, 14)
    exemplar = exemplar_terms((16, 16), 5) * FOOTPRINT.per_exemplar_term
    monkeypatch.setenv(ENV, str(exemplar + int(np.prod(shape)) * 20))  # 20 bytes a voxel
    with pytest.raises(HostMemoryError, match="--scratch DIR"):
        clsolid.synthesize(GRAVEL16, shape, backend={"tile": 5}, **kw)
    assert clsolid.synthesize(GRAVEL16, shape, backend={"tile": 5, "scratch": tmp_path}, **kw).shape == shape  # 4 in memory
