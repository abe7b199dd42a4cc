"""Checkpoint and resume: a resumed run gives the identical volume, and a
bad checkpoint gets a clear error, never a silent restart."""

import hashlib
import json
import zipfile

import numpy as np
import pytest
from conftest import slow_except

import clsolid
from clsolid.cli import EXIT_USAGE, main
from clsolid.core import checkpoint as checkpoint_module
from clsolid.core.checkpoint import META, STATE, CheckpointError, read_checkpoint, write_checkpoint
from clsolid.errors import InputError

KW = dict(neighborhood=5, scales=2, rng=4, views=2)  # two views: enough sweeps to stop between
SHAPE = (12, 12, 12)


class Stop(Exception):
    pass


def _interrupted(tmp_path, device, after: int, **kw) -> tuple[np.ndarray, object]:
    """Run with checkpoints and stop it in the progress hook after *after* sweeps."""
    seen = []

    def stop(info):
        seen.append(info.sweep)
        if len(seen) == after:
            raise Stop

    with pytest.raises(Stop):
        clsolid.synthesize("gravel", SHAPE, backend={"checkpoint": tmp_path / "ck"}, progress=stop, device=device, **KW,
                           **kw)
    return tmp_path / "ck"


@pytest.mark.parametrize("after", slow_except([1, 3, 6], 2))
def test_resumed_run_is_identical_to_the_uninterrupted_one(tmp_path, device, after):
    whole = clsolid.synthesize("gravel", SHAPE, device=device, **KW)
    folder = _interrupted(tmp_path, device, after)
    meta = json.loads((folder / META).read_text())
    assert meta["seed"] == 4 and sum(len(s["temperatures"]) for s in meta["timings"]["scales"]) == after
    res = clsolid.resume(folder, device=device, full_output=True)
    np.testing.assert_array_equal(res.volume, whole)
    assert res.seed == 4 and res.params["neighborhood"] == 5
    done = json.loads((folder / META).read_text())["timings"]["scales"]
    assert len(done) == 2 and len(res.timings["scales"]) == 2  # it went on checkpointing to the end
    np.testing.assert_array_equal(clsolid.resume(folder, device=device), whole)  # a finished run: its volume


@pytest.mark.parametrize("relaxation", slow_except(["icm", "annealing"], 0))
def test_every_relaxation_resumes_identically(tmp_path, device, relaxation):
    whole = clsolid.synthesize("gravel", SHAPE, device=device, relaxation=relaxation, **KW)
    folder = _interrupted(tmp_path, device, 2, relaxation=relaxation)
    np.testing.assert_array_equal(clsolid.resume(folder, device=device), whole)


def test_a_run_resumed_midway_through_its_polish_sweeps_is_identical(tmp_path, device):
    """The checkpoint says where the relaxation ended: a run stopped after the first of two
    polish sweeps polishes once more, as the uninterrupted run did."""
    whole = clsolid.synthesize("gravel", SHAPE, device=device, full_output=True, polish_sweeps=2, **KW)
    folder = _interrupted(tmp_path, device, sum(s["sweeps"] for s in whole.timings["scales"]) - 1, polish_sweeps=2)
    arrays = read_checkpoint(folder)[1]
    (scale, sweep, done), (relaxed,) = arrays["position"], arrays["relaxed"]
    assert scale == 1 and not done and sweep == relaxed + 1  # midway through the polish
    res = clsolid.resume(folder, device=device, full_output=True)
    np.testing.assert_array_equal(res.volume, whole.volume)
    assert res.timings["scales"][1]["visited"] == whole.timings["scales"][1]["visited"]


@pytest.mark.slow
def test_a_run_with_parent_terms_resumes_identically_midway_through_a_finer_scale(tmp_path, device):
    """The checkpoint keeps the scale's parent block (the coarser result repeated): a run
    stopped after the finest scale's first sweep goes on to the uninterrupted run's volume."""
    kw = dict(parent_weight=4.0, parent_min_side=0)
    whole = clsolid.synthesize("gravel", SHAPE, device=device, full_output=True, **KW, **kw)
    folder = _interrupted(tmp_path, device, len(whole.timings["scales"][0]["temperatures"]) + 1, **kw)
    arrays = read_checkpoint(folder)[1]
    scale, _, done = arrays["position"]
    assert scale == 1 and not done and arrays["parent"].shape == SHAPE  # midway, the parent kept
    np.testing.assert_array_equal(clsolid.resume(folder, device=device), whole.volume)


@pytest.mark.slow
def test_reference_back_end_resumes_identically(tmp_path):
    kw = dict(KW, scales=1, max_sweeps=3)
    whole = clsolid.synthesize("gravel", (6, 6, 6), device="reference", **kw)
    seen = []

    def stop(info):
        seen.append(1)
        if len(seen) == 1:
            raise Stop

    with pytest.raises(Stop):
        clsolid.synthesize("gravel", (6, 6, 6), device="reference", backend={"checkpoint": tmp_path}, progress=stop,
                           **kw)
    np.testing.assert_array_equal(clsolid.resume(tmp_path, device="reference"), whole)


def test_bad_checkpoints_are_refused(tmp_path, device):
    with pytest.raises(CheckpointError, match="holds no checkpoint"):
        clsolid.resume(tmp_path / "nothing")
    folder = _interrupted(tmp_path, device, 1)
    data = bytearray((folder / STATE).read_bytes())
    data[len(data) // 2] ^= 0xFF
    (folder / STATE).write_bytes(bytes(data))
    with pytest.raises(CheckpointError, match="corrupt"):
        clsolid.resume(folder)
    write_checkpoint(tmp_path / "other", {"method": "kopf"}, {"a": np.zeros(2)})
    with pytest.raises(CheckpointError, match="only 'ml'"):
        clsolid.resume(tmp_path / "other")
    meta = json.loads((tmp_path / "other" / META).read_text())
    (tmp_path / "other" / META).write_text(json.dumps({**meta, "format": 99}))
    with pytest.raises(CheckpointError, match="format 99"):
        read_checkpoint(tmp_path / "other")
    with pytest.raises(InputError, match="checkpoint_every"):
        clsolid.synthesize("gravel", (8, 8, 8), backend={"checkpoint": tmp_path / "x", "checkpoint_every": -1},
                           device=device)
    assert isinstance(CheckpointError("x"), clsolid.InputError)


def test_arrays_are_read_into_what_the_caller_gives(tmp_path, monkeypatch):
    """read_checkpoint reads each array a block at a time into ``empty(shape, dtype)`` (a
    scratch file's, when a large block resumes); a truncated array is a corrupt checkpoint."""
    arrays = {"volume": np.arange(60, dtype=np.float32).reshape(3, 4, 5), "mask": np.arange(7) % 2 == 0,
              "bias": np.array([0.5, -1.0])}
    write_checkpoint(tmp_path / "c", {"method": "ml"}, arrays)
    made = []

    def empty(shape, dtype):
        made.append((shape, dtype))
        return np.memmap(tmp_path / f"a{len(made)}.dat", dtype=dtype, mode="w+", shape=shape)

    monkeypatch.setattr(checkpoint_module, "_READ_BLOCK", 16)  # several blocks an array
    meta, back = read_checkpoint(tmp_path / "c", empty)
    assert meta == {"method": "ml"} and sorted(made) == sorted((a.shape, a.dtype) for a in arrays.values())
    for name, a in arrays.items():
        assert isinstance(back[name], np.memmap) and back[name].dtype == a.dtype
        np.testing.assert_array_equal(back[name], a)
    short = tmp_path / "short"  # an array cut short, with a digest that matches it
    short.mkdir()
    with zipfile.ZipFile(tmp_path / "c" / STATE) as z, zipfile.ZipFile(short / STATE, "w") as out:
        out.writestr("volume.npy", z.read("volume.npy")[:-8])
    meta_text = json.loads((tmp_path / "c" / META).read_text())
    meta_text["state_sha256"] = hashlib.sha256((short / STATE).read_bytes()).hexdigest()
    (short / META).write_text(json.dumps(meta_text))
    with pytest.raises(CheckpointError, match="ends early"):
        read_checkpoint(short)


def test_cli_checkpoint_and_resume(tmp_path, device):
    args = ["--shape", "12", "12", "12", "--neighborhood", "5", "--scales", "2", "--seed", "4", "-q"]
    assert main(["synth", "gravel", "-o", str(tmp_path / "a.npy"), *args, "--checkpoint", str(tmp_path / "ck")]) == 0
    assert (tmp_path / "ck" / META).is_file()
    assert main(["synth", "-o", str(tmp_path / "b.npy"), "--resume", str(tmp_path / "ck"), "-q"]) == 0
    np.testing.assert_array_equal(np.load(tmp_path / "a.npy"), np.load(tmp_path / "b.npy"))
    meta = json.loads((tmp_path / "b.json").read_text())
    assert meta["seed"] == 4 and meta["resumed_from"] == str(tmp_path / "ck")
    assert main(["synth", "-o", str(tmp_path / "c.npy"), "--resume", str(tmp_path / "ck"), "--seed", "5"]) == EXIT_USAGE


def test_cli_ctrl_c_names_the_checkpoint(tmp_path, capsys, monkeypatch, device):
    import clsolid.api

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(clsolid.api, "synthesize", interrupted)
    assert main(["synth", "gravel", "-o", str(tmp_path / "a.npy"), "--checkpoint", str(tmp_path / "ck")]) == 130
    assert f"--resume {tmp_path / 'ck'}" in capsys.readouterr().err

