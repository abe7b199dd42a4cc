"""Checkpoint and resume: a resumed run gives the identical volume, and a
bad checkpoint gets a clear error, never a silent restart."""

import hashlib
import json
import os
import zipfile

import numpy as np
import pytest
from conftest import slow_except

import clsolid
from clsolid.cli import EXIT_USAGE, main
from clsolid.core import checkpoint as checkpoint_module
from clsolid.core.checkpoint import META, CheckpointError, read_checkpoint, state_file, write_checkpoint
from clsolid.errors import InputError

KW = dict(neighborhood=5, scales=2, rng=4, views=2)  # two views: enough sweeps to stop between
SHAPE = (12, 12, 12)


class Stop(Exception):
    pass


def _interrupted(tmp_path, device, after: int, exemplar="gravel", **kw) -> tuple[np.ndarray, object]:
    """Run with checkpoints and stop it in the progress hook after *after* sweeps."""
    seen = []

    def stop(info):
        seen.append(info.sweep)
        if len(seen) == after:
            raise Stop

    with pytest.raises(Stop):
        clsolid.synthesize(exemplar, SHAPE, backend={"checkpoint": tmp_path / "ck"}, progress=stop, device=device, **KW,
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


def test_a_colour_run_resumes_identically(tmp_path, device):
    from skimage import data

    coffee = np.ascontiguousarray(data.coffee()[180:212, 300:332])
    kw = dict(channel_axis=-1, levels=12)
    whole = clsolid.synthesize(coffee, SHAPE, device=device, **KW, **kw)
    folder = _interrupted(tmp_path, device, 2, exemplar=coffee, **kw)
    resumed = clsolid.resume(folder, device=device)
    assert resumed.shape == SHAPE + (3,)
    np.testing.assert_array_equal(resumed, whole)


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
    data = bytearray(state_file(folder).read_bytes())
    data[len(data) // 2] ^= 0xFF
    state_file(folder).write_bytes(bytes(data))
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
    state = state_file(tmp_path / "c")
    with zipfile.ZipFile(state) as z, zipfile.ZipFile(short / state.name, "w") as out:
        out.writestr("volume.npy", z.read("volume.npy")[:-8])
    meta_text = json.loads((tmp_path / "c" / META).read_text())
    meta_text["state_sha256"] = hashlib.sha256((short / state.name).read_bytes()).hexdigest()
    (short / META).write_text(json.dumps(meta_text))
    with pytest.raises(CheckpointError, match="ends early"):
        read_checkpoint(short)


class Killed(BaseException):
    """A stop in the middle of a write, which nothing catches (as a kill)."""


@pytest.mark.parametrize("step", ["write_array", "fsync", "replace"])
def test_a_write_stopped_at_any_step_leaves_the_last_complete_checkpoint(tmp_path, monkeypatch, step):
    """Stopped while the arrays are written, before they reach the disk or at any rename, the
    folder reads as the checkpoint before (or, past the commit, the new one): never as corrupt."""
    first = {"volume": np.zeros((3, 4, 5), np.float32), "bias": np.array([1.0])}
    second = {"volume": np.ones((3, 4, 5), np.float32), "bias": np.array([2.0])}
    target = {"write_array": np.lib.format, "fsync": os, "replace": os}[step]
    real = getattr(target, step)
    stops = 0
    while True:
        folder = tmp_path / f"ck{stops}"
        write_checkpoint(folder, {"method": "ml", "n": 1}, first)
        calls = []

        def stopping(*args, **kwargs):
            calls.append(1)
            if len(calls) > stops:
                raise Killed
            return real(*args, **kwargs)

        monkeypatch.setattr(target, step, stopping)
        try:
            write_checkpoint(folder, {"method": "ml", "n": 2}, second)
            finished = True
        except Killed:
            finished = False
        monkeypatch.setattr(target, step, real)
        meta, arrays = read_checkpoint(folder)
        expected = second if meta["n"] == 2 else first
        assert meta["n"] == 2 or not finished
        for name, a in expected.items():
            np.testing.assert_array_equal(arrays[name], a)
        if finished:
            break
        stops += 1
    assert stops >= 2 if step != "write_array" else stops == 2  # every call of the write was stopped at once
    assert sorted(p.name for p in folder.iterdir()) == sorted([META, state_file(folder).name])


def test_a_write_removes_what_killed_writes_left(tmp_path):
    """A kill leaves temporary files (a kill runs no clean-up); the next write removes them,
    and the state files of earlier checkpoints."""
    write_checkpoint(tmp_path, {"method": "ml"}, {"a": np.zeros(2)})
    left = [tmp_path / ".state-0123456789ab.npz.cafe0000.partial", tmp_path / f".{META}.cafe0000.partial",
            tmp_path / "state.npz"]
    for f in left:
        f.write_bytes(b"partial")
    write_checkpoint(tmp_path, {"method": "ml"}, {"a": np.ones(2)})
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([META, state_file(tmp_path).name])
    np.testing.assert_array_equal(read_checkpoint(tmp_path)[1]["a"], np.ones(2))


def test_a_checkpoint_of_the_first_format_is_read(tmp_path):
    """Format 1 kept its arrays in ``state.npz``, which its description did not name."""
    np.savez(tmp_path / "state.npz", a=np.arange(3))
    digest = hashlib.sha256((tmp_path / "state.npz").read_bytes()).hexdigest()
    (tmp_path / META).write_text(json.dumps({"method": "ml", "format": 1, "state_sha256": digest}))
    meta, arrays = read_checkpoint(tmp_path)
    assert meta == {"method": "ml"} and state_file(tmp_path) == tmp_path / "state.npz"
    np.testing.assert_array_equal(arrays["a"], np.arange(3))


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



# -- a run killed at a random moment --------------------------------------------------------

#: The killed run's child: ``HOOK N MARKER ARGV...`` runs ``clsolid ARGV``, but the N-th call
#: (from 0) of HOOK (numpy's write of one array into the checkpoint's ``.npz``, or a rename
#: into the checkpoint folder) touches MARKER and waits there to be killed.
_CHILD = """
import os, sys, time
import numpy as np
hook, n, marker, argv = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4:]
folder = argv[argv.index("--checkpoint") + 1]
calls = []

def held(real, counts):
    def call(*args, **kwargs):
        if counts(args):
            calls.append(1)
            if len(calls) == n + 1:
                open(marker, "w").close()
                time.sleep(120)
        return real(*args, **kwargs)
    return call

if hook == "write_array":
    np.lib.format.write_array = held(np.lib.format.write_array, lambda args: True)
elif hook == "replace":
    os.replace = held(os.replace, lambda args: str(args[1]).startswith(folder))
from clsolid.cli import main
sys.exit(main(argv))
"""
KILL_ARGS = ["gravel", "--builtin-size", "32", "--shape", "20", "20", "20", "--neighborhood", "5", "--scales", "2",
             "--seed", "6", "--checkpoint-every", "0"]
#: When the run is killed, in seconds after its first sweep (a checkpoint is written by then),
#: drawn once from a seeded generator, so that every run of the suite kills at the same moments.
KILL_DELAYS = np.random.default_rng(48).uniform(0.0, 1.0, 3).round(3).tolist()
#: The moments: a random delay after the start (most often before the first checkpoint) or
#: after the first sweep, or held in the first or the second checkpoint's write (the 1 + N-th
#: array written, where N arrays make a checkpoint; the rename of its arrays or description).
MOMENTS = [("start", 0.5), *[("sweep", d) for d in KILL_DELAYS], ("write_array", 1), ("write_array", "N+1"),
           ("replace", 0), ("replace", 1), ("replace", 3)]


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory, device):
    """The uninterrupted run's volume, and the number of arrays in its checkpoint."""
    from clsolid.core.device import device_index

    where = tmp_path_factory.mktemp("whole")
    spec = device_index(device)
    assert main(["synth", *KILL_ARGS, "-o", str(where / "v.npy"), "--checkpoint", str(where / "ck"), "-q",
                 "--device", spec]) == 0
    return np.load(where / "v.npy"), len(read_checkpoint(where / "ck")[1]), spec


def _killed_run(tmp_path, spec: str, hook: str, n: int, delay: float) -> int:
    """Run ``clsolid synth`` in a child process and SIGKILL it: at the moment its hook is held,
    else *delay* seconds after it starts (``start``) or after its first sweep; its exit status."""
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    marker = tmp_path / "held"
    argv = ["synth", *KILL_ARGS, "-o", str(tmp_path / "v.npy"), "--checkpoint", str(tmp_path / "ck"),
            "--device", spec]
    env = {**os.environ, "PYTHONPATH": str(Path(clsolid.__file__).parents[1])}
    child = subprocess.Popen([sys.executable, "-c", _CHILD, hook, str(n), str(marker), *argv], env=env,
                             stderr=subprocess.PIPE, text=True)
    try:
        if hook in ("write_array", "replace"):
            deadline = time.monotonic() + 60
            while not marker.exists():
                assert child.poll() is None, f"the run ended ({child.returncode}) before its hook was held"
                assert time.monotonic() < deadline, "the run's hook was never held"
                time.sleep(0.01)
        else:
            if hook == "sweep":
                for line in child.stderr:  # progress: after a sweep and its checkpoint
                    if line.startswith("scale"):
                        break
            time.sleep(delay)
        child.send_signal(signal.SIGKILL)
        return child.wait(60)
    finally:
        child.kill()
        child.stderr.close()


@pytest.mark.slow
@pytest.mark.parametrize("hook, n", MOMENTS, ids=[f"{h}-{n}" for h, n in MOMENTS])
def test_a_killed_run_resumes_to_the_uninterrupted_volume(tmp_path, capsys, uninterrupted, hook, n):
    """SIGKILL at a random moment, or in the middle of a checkpoint's write: the folder holds
    the last complete checkpoint, and resuming it gives the uninterrupted run's volume. Killed
    before the first checkpoint was complete, the folder holds none: resuming is refused with
    an input error (exit status 2), and a fresh run with the same seed is the recovery."""
    whole, arrays, spec = uninterrupted
    count = arrays + 1 if n == "N+1" else n if hook in ("write_array", "replace") else 0
    status = _killed_run(tmp_path, spec, hook, count, n)
    assert status in (-9, 0)  # killed, or done before the kill (a short random delay can miss)
    assert status == 0 or not (tmp_path / "v.npy").exists()  # killed in the run: no volume written
    ck, out = tmp_path / "ck", tmp_path / "resumed.npy"
    complete = (ck / META).is_file()
    if hook in ("write_array", "replace"):  # the first write holds 1 + N arrays' writes, 2 renames
        assert complete == (count > arrays if hook == "write_array" else count > 1)
    capsys.readouterr()
    code = main(["synth", "--resume", str(ck), "-o", str(out), "-q", "--device", spec])
    if complete:
        assert code == 0
    else:
        assert code == EXIT_USAGE and "holds no checkpoint" in capsys.readouterr().err
        assert main(["synth", *KILL_ARGS, "-o", str(out), "--checkpoint", str(ck), "-q", "--device", spec]) == 0
    assert np.array_equal(np.load(out), whole)
    assert sorted(p.name for p in ck.iterdir()) == sorted([META, state_file(ck).name])  # the leftovers removed
