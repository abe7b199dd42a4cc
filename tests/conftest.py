"""Shared fixtures: every OpenCL test runs on one device, or on every device that compiles.

By default the ``device`` fixture is one device: PoCL where it compiles (the CPU device the
project is specified on), else the first that compiles. A test marked ``each_device`` (the
kernels against their float64 references) runs on every device that compiles, in the
default run too: where PoCL and Intel's CPU runtime both do, on both. ``CLSOLID_TEST_DEVICES=all``
runs every OpenCL test on every device that compiles (that doubles the suite's time). Filter
devices with ``PYOPENCL_TEST`` (a substring of the platform or device name). With no device:
fail when ``$CI`` is set, skip locally with the reason.
"""

from __future__ import annotations

import importlib.util
import os
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

# Each test process gets its own PoCL kernel cache (parallel runs must not share one), and
# its own clsolid cache (device probes, OpenCL vendors directory), so no stale answer leaks in.
os.environ.setdefault("POCL_CACHE_DIR", tempfile.mkdtemp(prefix="clsolid-pocl-"))
os.environ.setdefault("CLSOLID_CACHE_DIR", tempfile.mkdtemp(prefix="clsolid-cache-"))


def _device_specs() -> list[str]:
    """Every device that compiles (PoCL and Intel's CPU runtime where both do), as "p:d"."""
    try:
        from clsolid.core.device import list_devices

        devices = list_devices()
    except Exception as exc:  # noqa: BLE001 - reported below
        return [f"!{exc}"]
    wanted = os.environ.get("PYOPENCL_TEST", "").lower()
    matching = [d for d in devices if not wanted or wanted in d["name"].lower() or wanted in d["platform"].lower()]
    compiling = [d for d in matching if d["compiles"]]
    if compiling:  # PoCL first: with one device tested, it is the one the project is specified on
        return [d["index"] for d in sorted(compiling, key=lambda d: "portable" not in d["platform"].lower())]
    if matching:
        why = "; ".join(f"{d['platform']} / {d['name']}: {d['probe_message']}" for d in matching)
        return [f"!no OpenCL device compiles ({why})"]
    return ["!no OpenCL device matches PYOPENCL_TEST"]


_DEVICES: dict = {}


#: Every device that compiles (PoCL first), or why there is none ("!reason").
ALL_DEVICE_SPECS = _device_specs()
#: The devices the ``device`` fixture takes: all of them with ``CLSOLID_TEST_DEVICES=all``, else the first.
DEVICE_SPECS = ALL_DEVICE_SPECS if os.environ.get("CLSOLID_TEST_DEVICES", "").lower() == "all" else ALL_DEVICE_SPECS[:1]


def pytest_generate_tests(metafunc):
    """Give ``device`` its devices, as pyopencl's ``pytest_generate_tests_for_pyopencl`` does:
    every one that compiles for a test marked ``each_device``, else :data:`DEVICE_SPECS`."""
    if "device" in metafunc.fixturenames:
        every = metafunc.definition.get_closest_marker("each_device") is not None
        metafunc.parametrize("device", ALL_DEVICE_SPECS if every else DEVICE_SPECS, indirect=True, scope="session")


@pytest.fixture(scope="session")
def device(request):
    """A :class:`clsolid.Device` for each device the test runs on (one per session)."""
    spec = request.param
    if spec.startswith("!"):
        if os.environ.get("CI"):
            pytest.fail(f"no OpenCL device on CI: {spec[1:]}")
        pytest.skip(f"no OpenCL device: {spec[1:]}")
    from clsolid.core.device import select_device

    if spec not in _DEVICES:
        _DEVICES[spec] = select_device(spec)
    return _DEVICES[spec]


@pytest.fixture(scope="session")
def brick_labels():
    """The default exemplar, quantised to 32 levels (64x64)."""
    from clsolid.exemplar import builtin_exemplar, quantise

    return quantise(builtin_exemplar("brick"), 32)


@pytest.fixture(scope="session")
def small_labels(brick_labels):
    """A 24x24 corner of a 16-level brick, for runs the float64 reference can afford."""
    from clsolid.exemplar import quantise

    return quantise(brick_labels[:24, :24], 16)


def slow_except(cases, *keep):
    """*cases* for ``pytest.mark.parametrize``, each marked ``slow`` but those at the indices
    *keep*: a large parametrization keeps a small representative case in the default run.
    A tuple is one case's arguments, as parametrize reads it."""
    slow = pytest.mark.slow
    return [case if i in keep else pytest.param(*case if isinstance(case, tuple) else (case,), marks=slow)
            for i, case in enumerate(cases)]


def random_state(model, seed=0, cold=0.3):
    """A random volume and temperatures (some exactly 0) for a scale model."""
    rng = np.random.default_rng(seed)
    vol = rng.choice(model.labels, size=model.shape)
    temp = rng.random(model.shape)
    temp[temp < cold] = 0.0
    return vol, temp


@pytest.fixture(scope="session")
def tool():
    """Import a script of ``tools/`` by name, e.g. ``tool("quality_ml")``.

    tools/ goes on ``sys.path`` as it does when a script runs, so the scripts can import
    each other (gallery and compare_devices reuse quality_ml's helpers).
    """
    folder = Path(__file__).resolve().parents[1] / "tools"
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))

    def load(name: str):
        spec = importlib.util.spec_from_file_location(name, folder / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module

    return load


@pytest.fixture
def full_disk(monkeypatch):
    """``full_disk(folder, room, name="")``: from then on, the files opened for writing in
    *folder* whose names hold *name* take *room* bytes in all; a write past that fails with
    ``ENOSPC``, as on a full disk, after writing what fits. Every ``open`` (the built-in,
    ``io.open``: what tifffile, Pillow, NumPy and pathlib call) goes through it; each call
    fills one more folder."""
    import builtins
    import errno
    import io

    real_open = io.open
    full: list[tuple[Path, str, list[int]]] = []  # folder, name, bytes left

    def room_left(file, mode: str) -> list[int] | None:
        if not isinstance(file, (str, os.PathLike)) or not any(c in mode for c in "wax+"):
            return None
        target = Path(file)
        return next((left for folder, name, left in reversed(full)  # the latest call's rule
                     if name in target.name and target.resolve().parent == folder), None)

    def full_open(file, mode="r", buffering=-1, encoding=None, errors=None, newline=None, closefd=True,
                  opener=None):
        left = room_left(file, mode)
        if left is None:
            return real_open(file, mode, buffering, encoding, errors, newline, closefd, opener)

        class FullFile(io.FileIO):
            def write(self, data):
                data = memoryview(data).cast("B")
                done = super().write(data[:left[0]]) if left[0] else 0
                left[0] -= done
                if done < len(data):
                    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), self.name)
                return done

            def fileno(self):  # none to give: NumPy and tifffile then write through write(), not past it
                raise io.UnsupportedOperation("fileno")

        raw = FullFile(file, mode.replace("b", "").replace("t", ""))
        buffered = io.BufferedRandom(raw) if "+" in mode else io.BufferedWriter(raw)
        return buffered if "b" in mode else io.TextIOWrapper(buffered, encoding or "utf-8", errors, newline)

    def fill(folder, room: int, name: str = "") -> None:
        full.append((Path(folder).resolve(), name, [room]))
        monkeypatch.setattr(builtins, "open", full_open)
        monkeypatch.setattr(io, "open", full_open)

    return fill
