"""The host-memory check (clsolid.core.hostmemory): a block the host cannot hold is refused
before anything is allocated, through the API and the command line."""

import pickle
import tracemalloc

import numpy as np
import pytest

import clsolid
from clsolid.cli import EXIT_MEMORY, main
from clsolid.core import scratch as scratch_module
from clsolid.core.hostmemory import ENV, available_bytes, check_host_memory, exemplar_terms, parse_bytes
from clsolid.ml.backends import FOOTPRINT as ML, SCRATCH_FOOTPRINT as ML_SCRATCH
from clsolid.search import FOOTPRINT as SEARCH
from clsolid.errors import HostMemoryError, InputError
from clsolid.gallery import gallery_exemplar
from clsolid import balance as ml_balance
from clsolid.ml import driver as ml_driver


@pytest.mark.parametrize("text, want", [("1024", 1024), ("64G", 64 * 2**30), ("1.5M", int(1.5 * 2**20)),
                                        ("2GiB", 2 * 2**30), (" 3k ", 3072), ("1T", 2**40)])
def test_sizes_are_read_with_binary_suffixes(text, want):
    assert parse_bytes(text) == want


@pytest.mark.parametrize("text", ["", "lots", "-5G", "nanG", "G"])
def test_a_bad_size_is_refused_naming_the_variable(text):
    with pytest.raises(InputError, match=ENV):
        parse_bytes(text)


def test_the_system_figure_is_known_here(monkeypatch):
    monkeypatch.delenv(ENV, raising=False)
    have = available_bytes()
    assert have is not None and have > 2**26  # this Linux machine reports MemAvailable


def test_a_block_over_the_available_memory_is_refused_with_what_to_do(monkeypatch):
    side = 128
    monkeypatch.setenv(ENV, str(side**3 * ML.per_voxel))
    check_host_memory((side, side, side), ML)  # fits exactly
    with pytest.raises(HostMemoryError) as info:
        check_host_memory((side, side, side + 1), ML)
    msg = str(info.value)
    assert f"{side}x{side}x{side + 1}" in msg and "GiB" in msg and "smaller block" in msg and ENV in msg
    assert isinstance(info.value, MemoryError) and "--scratch DIR" in msg  # the likelihood's way out
    again = pickle.loads(pickle.dumps(info.value))  # it crosses processes (Dask) whole
    assert str(again) == msg
    with pytest.raises(HostMemoryError):  # the search methods keep more a voxel
        check_host_memory((side, side, side), SEARCH)
    assert SEARCH.per_voxel > ML.per_voxel


@pytest.mark.parametrize("shape", [(2**40, 2**40, 2**40), (2**21, 2**21, 2**21)])
def test_a_block_whose_voxels_overflow_int64_is_refused(shape):
    # 2^120 voxels wrapped to 0 in int64 (and 2^63 to a negative count): the check passed and
    # the run went on, building its colour sets for ever
    with pytest.raises(HostMemoryError):
        check_host_memory(shape, ML)
    with pytest.raises(HostMemoryError):
        clsolid.synthesize(np.eye(8, dtype=np.uint8), shape, device="reference", rng=1, scales=1, neighborhood=3)


def test_the_exemplar_windows_are_counted(monkeypatch):
    assert exemplar_terms((64, 80), 11) == 54 * 70 * 120
    assert exemplar_terms((9, 9), 11) == 0
    terms = exemplar_terms((1024, 1024), 11)
    exemplar = terms * ML.per_exemplar_term
    assert 6.2e9 < exemplar < 8e9  # a 1024^2 exemplar peaked at 6.19 GB, whatever the block
    monkeypatch.setenv(ENV, str(16**3 * ML.per_voxel + exemplar))
    check_host_memory((16, 16, 16), ML, terms)  # fits exactly
    with pytest.raises(HostMemoryError, match="exemplar's windows") as info:
        check_host_memory((16, 16, 17), ML, terms)
    assert info.value.exemplar == exemplar
    assert str(pickle.loads(pickle.dumps(info.value))) == str(info.value)


def test_synthesize_refuses_a_large_exemplar_for_a_small_block(monkeypatch):
    """24^3 alone fits, with a 128^2 exemplar's windows it does not: refused before anything is built."""
    monkeypatch.setenv(ENV, str(24**3 * ML.per_voxel + 2**20))
    with pytest.raises(HostMemoryError, match="exemplar's windows"):
        clsolid.synthesize(gallery_exemplar("porous50", 128), (24, 24, 24), device="reference", rng=1)


@pytest.mark.parametrize("method", ["ml", "kopf"])
def test_synthesize_refuses_before_growing_anything(monkeypatch, method):
    monkeypatch.setenv(ENV, "1M")
    with pytest.raises(HostMemoryError, match="64x64x64"):
        clsolid.synthesize("brick", (64, 64, 64), method=method, device="reference", rng=1)


def test_the_command_line_exits_with_the_memory_code(monkeypatch, tmp_path, capsys):
    monkeypatch.setenv(ENV, "1M")
    out = tmp_path / "v.npy"
    assert main(["synth", "brick", "-o", str(out), "--shape", "64", "64", "64", "--device", "reference"]) == EXIT_MEMORY
    assert "host memory" in capsys.readouterr().err and not out.exists()


def _traced_peak(side: int, device, options: dict) -> int:
    """Peak of the host allocations NumPy and Python trace (device buffers excluded)."""
    tracemalloc.start()
    try:
        backend = {k: options[k] for k in ("tile", "scratch") if k in options}
        method = {k: v for k, v in options.items() if k not in backend}
        clsolid.synthesize(gallery_exemplar("composite3", 64), (side,) * 3, rng=1, device=device,
                           backend=backend or None, **method)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.slow
@pytest.mark.parametrize("options, most", [
    ({"likelihood": "exact", "sweeps": 1}, 28),
    ({"likelihood": "exact", "sweeps": 1, "tile": 20}, 30),
    ({"likelihood": "pruned", "sweeps": 1, "tile": 20, "scratch": "a folder"}, ML_SCRATCH.per_voxel - 2),
    ({"method": "kopf", "search": "coherence", "iterations": 1}, 40),
])
def test_the_drivers_hold_few_bytes_a_voxel(device, options, most, tmp_path, monkeypatch):
    """The growth of the traced peak from 32^3 to 56^3, per voxel (the exemplar's tables
    cancel out): the scale's start state and the output, and no whole-block index arrays
    (the conflict-free sets listed at once, a float64 copy of the state kept beside the back
    end's, int64 matches; docs/design.md#host-memory). The buffers bounded in size (runs of
    planes, the balance's sampled scores) are held small here, so that what they hold at
    these sizes does not pass for a cost per voxel."""
    monkeypatch.setattr(scratch_module, "_RUN_ELEMENTS", 1 << 12)
    monkeypatch.setattr(ml_driver, "_INDEX_RUN", 1 << 12)
    monkeypatch.setattr(ml_balance, "SCORE_SAMPLES", 1 << 10)
    if "scratch" in options:  # the state and the result in files, which the system pages out
        options = {**options, "scratch": tmp_path}
    small, large = 32, 56  # the growth per voxel is the same as from 40^3 to 64^3, in less time
    _traced_peak(16, device, options)  # the first run in a process traces one-time allocations too (builds)
    growth = (_traced_peak(large, device, options) - _traced_peak(small, device, options)) / (large**3 - small**3)
    assert growth < most
