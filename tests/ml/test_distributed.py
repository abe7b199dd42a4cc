"""Dask: the tiles of every set as tasks on two worker processes give the volume of
the one-process tiled run and of the one-piece run, voxel for voxel."""

import numpy as np
import pytest

import clsolid
from clsolid.cli import EXIT_USAGE, main
from clsolid.errors import DeviceMemoryError, InputError
from clsolid.exemplar import builtin_exemplar, quantise
from clsolid.ml.driver import run_ml
from clsolid.ml.opencl import CLBackend
from clsolid.ml.params import MLParams
from clsolid.ml.tiled import LocalTiles, TiledBackend

distributed = pytest.importorskip("distributed", reason='Dask is an optional extra: pip install "clsolid[dask]"')

from clsolid.ml import distributed as distributed_module  # noqa: E402 (needs distributed)
from clsolid.ml.distributed import DaskTiles, device_spec  # noqa: E402 (needs distributed)

SHAPE = (16, 18, 20)


@pytest.fixture(scope="module")
def client():
    """Two worker processes of one thread each, for the whole module."""
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as c:
        yield c


@pytest.fixture(scope="module")
def labels(brick_labels):
    return quantise(brick_labels[:16, :16], 8)


# Whole runs on the workers are slow-only: each worker builds its kernels anew. The default run
# keeps what is cheap there: the random start drawn on the workers, the options, a worker's error.
@pytest.mark.slow
@pytest.mark.parametrize("likelihood, polish", [("exact", 0), ("pruned", 1)])
def test_distributed_run_is_the_one_process_run(device, client, labels, likelihood, polish):
    """Gibbs with the balance (the defaults), exact and pruned: the sources go to the workers and
    back; a polish sweep's relaxation too."""
    params = MLParams(neighborhood=5, scales=2, sweeps=2, likelihood=likelihood, polish_sweeps=polish)
    whole = CLBackend(device)
    local = TiledBackend(LocalTiles(CLBackend(device)), 8)
    dask = TiledBackend(DaskTiles(client, device), 8)
    a = run_ml(labels, SHAPE, params, 5, whole)[0]
    b = run_ml(labels, SHAPE, params, 5, local)[0]
    c = run_ml(labels, SHAPE, params, 5, dask)[0]
    assert len(dask.tiling.tiles) > 2
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, c)
    np.testing.assert_array_equal(local.scores(), dask.scores())
    assert (whole.exact_visits, whole.pruned_visits) == (dask.exact_visits, dask.pruned_visits)
    assert dask.name == device.name  # the workers open the host's device
    used = client.run(lambda: list(__import__("clsolid.ml.distributed").ml.distributed._ENGINES))
    assert all(dask.runner.token in tokens for tokens in used.values())  # both workers ran tiles of the last scale


def test_the_workers_draw_the_random_start_a_run_at_a_time(device, client, monkeypatch):
    """In runs of 1000 voxels (16 of them, a few in flight), into a given array: the one-process start."""
    monkeypatch.setattr(distributed_module, "_INIT_RUN", 1000)
    pixels = np.arange(7, dtype=np.float32)
    out = np.full(SHAPE, -1, np.float32)
    drawn = DaskTiles(client, device).init_volume(SHAPE, 3, pixels, out)
    assert drawn is out
    np.testing.assert_array_equal(out, CLBackend(device).init_volume(SHAPE, 3, pixels))


@pytest.mark.slow
def test_synthesize_with_a_client(device, client):
    kw = dict(neighborhood=5, scales=2, rng=3, sweeps=1, device=device)
    gravel = builtin_exemplar("gravel", size=16)
    whole = clsolid.synthesize(gravel, SHAPE, **kw)
    result = clsolid.synthesize(gravel, SHAPE, backend={"tile": 9, "client": client}, full_output=True, **kw)
    np.testing.assert_array_equal(result.volume, whole)
    assert result.device == device.name


def test_client_options_are_checked(device, client):
    with pytest.raises(InputError, match=r"client= runs the tiles .* give tile=N too"):
        clsolid.synthesize("gravel", SHAPE, backend={"client": client}, device=device)
    with pytest.raises(InputError, match="tile=0 must be a positive integer"):
        clsolid.synthesize("gravel", SHAPE, backend={"client": client, "tile": 0}, device=device)
    with pytest.raises(InputError, match="is for OpenCL devices"):
        clsolid.synthesize("gravel", SHAPE, backend={"client": client, "tile": 4}, device="reference")
    with pytest.raises(InputError, match="must be a device spec string"):
        device_spec(3)


def test_a_workers_memory_error_reaches_the_host(device, client, labels):
    """Each worker checks the tiles against its own device; its error comes back whole."""

    def squeeze():  # a 1 MiB buffer limit on the worker's devices
        from clsolid.core import device as d

        d._real_max_alloc = d.Device.__dict__["max_alloc"]
        d.Device.max_alloc = property(lambda self: 1 << 20)

    def release():
        from clsolid.core import device as d

        d.Device.max_alloc = d._real_max_alloc

    params = MLParams(neighborhood=5, scales=2, sweeps=1)
    client.run(squeeze)
    try:
        with pytest.raises(DeviceMemoryError, match="with tile=64 the device holds .* use a smaller tile"):
            run_ml(labels, (64, 64, 64), params, 5, TiledBackend(DaskTiles(client, device), 64))
    finally:
        client.run(release)


def test_missing_dask_is_explained(monkeypatch):
    import builtins

    from clsolid.ml.distributed import require_distributed

    real = builtins.__import__

    def no_distributed(name, *args, **kwargs):
        if name == "distributed":
            raise ImportError("No module named 'distributed'")
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_distributed)
    with pytest.raises(InputError, match=r'pip install "clsolid\[dask\]"'):
        require_distributed()


@pytest.mark.slow
def test_cli_workers_flag(tmp_path, device):
    args = ["--shape", "12", "10", "14", "--neighborhood", "5", "--scales", "2", "--seed", "4", "--builtin-size",
            "16", "--max-sweeps", "3", "--device", device_spec(device), "-q"]
    assert main(["synth", "gravel", "-o", str(tmp_path / "a.npy"), *args]) == 0
    assert main(["synth", "gravel", "-o", str(tmp_path / "b.npy"), *args, "--tile", "5", "--workers", "2"]) == 0
    np.testing.assert_array_equal(np.load(tmp_path / "a.npy"), np.load(tmp_path / "b.npy"))
    assert main(["synth", "gravel", "-o", str(tmp_path / "c.npy"), *args, "--workers", "2"]) == EXIT_USAGE
    assert main(["synth", "gravel", "-o", str(tmp_path / "d.npy"), *args, "--tile", "5", "--workers", "2",
                 "--scheduler", "tcp://127.0.0.1:1"]) == EXIT_USAGE


@pytest.mark.slow  # three runs of a 64² exemplar; the tool's table is what tests/test_tools.py checks
def test_bench_scale_compares_the_workers_run(capsys, device, client, tool):
    import argparse

    args = argparse.Namespace(cases=["64:8"], names=["porous50"], likelihoods=["pruned"], budget=900.0,
                              device=device_spec(device), tile=5, workers=2, tiled_only=False, verbose=False,
                              scratch=None, region=0)
    tool("bench_scale").table(args, client)
    out = capsys.readouterr().out
    assert "the tiles on 2 Dask workers" in out and "| porous50 | 64² → 8³ | pruned |" in out
    assert out.count("| yes |") == 2  # tiled is one piece, and the workers' run is the tiled one


@pytest.mark.slow
def test_a_run_that_loses_a_worker_gives_the_uninterrupted_volume(device):
    """A worker process killed (``os._exit``) at a random moment of a sweep, as it runs tile
    tasks: Dask runs them again on the other worker (or the one its nanny starts), and the
    volume is the uninterrupted run's. Its own cluster: the module's keeps its workers."""
    import os
    import threading
    import time

    kw = dict(neighborhood=5, scales=2, rng=3, sweeps=1, device=device)
    gravel = builtin_exemplar("gravel", size=16)
    whole = clsolid.synthesize(gravel, SHAPE, **kw)
    # After the first scale: within the second's sweep, whose sets' tasks take seconds in all.
    delay = float(np.random.default_rng(48).uniform(0.5, 3.0))
    done, killed = threading.Event(), []
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as client:
        victim = sorted(client.scheduler_info()["workers"])[0]

        async def die():  # client.run waits for nothing only from a coroutine function
            os._exit(1)

        def kill():
            deadline = time.monotonic() + 10
            while not client.processing([victim])[victim] and time.monotonic() < deadline and not done.is_set():
                time.sleep(0.005)  # between two sets: wait for the next one's tasks
            killed.append((not done.is_set(), len(client.processing([victim])[victim])))
            client.run(die, workers=[victim], wait=False)

        def kill_later(info):
            if info.scale == 1:
                threading.Timer(delay, kill).start()

        result = clsolid.synthesize(gravel, SHAPE, backend={"tile": 12, "client": client}, progress=kill_later, **kw)
        done.set()
        [(going, tasks)] = killed
        assert going and tasks > 0  # killed while the run went on, with tasks of it
        assert victim not in client.scheduler_info()["workers"]  # its process is gone
    np.testing.assert_array_equal(result, whole)
