"""Can this OpenCL device compile and run clsolid's kernels? Asked once per device and driver version.

An OpenCL driver can list a device that cannot build our kernels. PoCL on LLVM 14 lists
a Zen 5 CPU, then fails every build ("unknown target CPU 'generic'"); on a Zen 4 CPU it
builds a tiny kernel but aborts the whole process on the 16-wide vectors of the likelihood
kernels ("LLVM ERROR: Cannot emit physreg copy instruction"). So the probe builds a tiny
kernel and runs it (checking its result), then runs every method's smoke test (:func:`register_smoke_test`: each builds and
launches its kernels on a tiny case) at the widest vector width that works (16, 8, then 4),
each attempt in a child process that an abort cannot take down. The answer, with that
width, is cached on disk (``clsolid.core.icd.cache_dir()``) and keyed by platform, device,
driver and OpenCL versions and the smoke tests: a few seconds the first time, nothing afterwards.
"""

from __future__ import annotations

import hashlib
import importlib
import json
import logging
import os
import subprocess
import sys
import tempfile
import warnings
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from ..errors import KernelBuildError
from .icd import cache_dir

log = logging.getLogger(__name__)

#: Bump when what the probe checks changes, so old cached answers are not reused.
PROBE_VERSION = 4
CACHE_FILE = "device-probes.json"
#: Vector widths tried, widest (fastest where it compiles) first.
VECTOR_WIDTHS = (16, 8, 4)
CHILD_TIMEOUT_S = 300
# A loop, a transcendental and a vector type: enough to exercise the compiler's back end.
PROBE_SOURCE = """
__kernel void probe(__global float *out, float a)
{
    int i = get_global_id(0);
    float4 v = (float4)(0.0f, 1.0f, 2.0f, 3.0f) * a;
    float s = 0.0f;
    for (int k = 0; k < 4; ++k) s += exp(-v.x - (float)k) + v.w;
    out[i] = s;
}
"""
_memo: dict[str, "ProbeResult"] = {}
#: The smoke tests each probe runs after the tiny kernel, as ``"module:function"``; each is
#: called with a :class:`~clsolid.core.device.Device` and a vector width, and raises on failure.
SMOKE_TESTS: list[str] = []


def register_smoke_test(target: str) -> None:
    """Add a method's smoke test (``"package.module:function"``) to those every probe runs.

    The function builds and launches the method's kernels on a tiny case at the vector
    width it is given; the probe runs it in a child process, which imports it by name.
    """
    if ":" not in target:
        raise ValueError(f"a smoke test is named 'module:function', not {target!r}")
    if target not in SMOKE_TESTS:
        SMOKE_TESTS.append(target)


@dataclass(frozen=True)
class ProbeResult:
    """Whether a device compiled and ran clsolid's kernels.

    ``message`` says why not; ``vector_width`` is the widest that compiled (None if none).
    """

    ok: bool
    message: str = ""
    vector_width: int | None = None


def device_key(dev: Any) -> str:
    """Identity of a device and of the driver that compiles for it."""
    p = dev.platform
    tests = hashlib.sha256(" ".join(sorted(SMOKE_TESTS)).encode()).hexdigest()[:8]
    parts = (p.name, p.version, dev.name, dev.driver_version, dev.version, f"probe{PROBE_VERSION}", tests)
    return " | ".join(str(s).strip() for s in parts)


def _expected(n: int, a: float) -> np.ndarray:
    """What the probe kernel writes: v.x = 0 and v.w = 3a in every work item."""
    return np.full(n, sum(np.exp(-k) + 3.0 * a for k in range(4)), np.float32)


def compiler_message(exc: BaseException, lines: int = 3) -> str:
    """The compiler's own complaint in an OpenCL error (error lines of the build log first)."""
    text = [ln.strip() for ln in str(exc).splitlines()]
    keep = [ln for ln in text if ln and not ln.startswith(("=", "Build on", "(options:", "(source saved", "building "))]
    errors = [ln for ln in keep if "error" in ln.lower() and not ln.startswith("clBuildProgram")]
    chosen = (errors + [ln for ln in keep if ln not in errors])[:lines]
    return " / ".join(chosen) or type(exc).__name__


def _build(ctx: Any, source: str, options: list[str]) -> Any:
    import pyopencl as cl

    with warnings.catch_warnings():  # a compiler's chatter on success is not news
        warnings.simplefilter("ignore", cl.CompilerWarning)
        return cl.Program(ctx, source).build(options=options)


def run_smoke_tests(device: Any, vector_width: int, targets: list[str] | None = None) -> None:
    """Every registered smoke test (or *targets*) on *device* at *vector_width*.

    Running matters, not only building: PoCL generates a kernel's machine code at its first
    launch, and that is where LLVM 14 aborts on a Zen 4 CPU.
    """
    for target in SMOKE_TESTS if targets is None else targets:
        module, function = target.split(":")
        getattr(importlib.import_module(module), function)(device, vector_width)


def try_device(dev: Any, vector_width: int | None, targets: list[str] | None = None) -> ProbeResult:
    """In this process: run the tiny kernel, then (if *vector_width*) the smoke tests (*targets*,
    default every registered one)."""
    import pyopencl as cl

    from .platforms import Device

    try:
        ctx = cl.Context([dev])
        queue = cl.CommandQueue(ctx)
        program = _build(ctx, PROBE_SOURCE, [])
        out = np.empty(4, np.float32)
        buf = cl.Buffer(ctx, cl.mem_flags.WRITE_ONLY, out.nbytes)
        program.all_kernels()[0](queue, (4,), None, buf, np.float32(0.5))
        cl.enqueue_copy(queue, out, buf)
        queue.finish()
        if not np.allclose(out, _expected(4, 0.5), rtol=1e-4):
            return ProbeResult(False, f"the probe kernel ran but returned {out.tolist()}")
        if vector_width is not None:
            run_smoke_tests(Device(dev, ctx, queue), vector_width, targets)
    except (cl.Error, KernelBuildError) as exc:
        return ProbeResult(False, compiler_message(exc))
    return ProbeResult(True, "", vector_width)


def _in_child(dev: Any, vector_width: int | None) -> ProbeResult:
    """:func:`try_device` in a child process, with a private PoCL cache; an abort is an answer too."""
    env = dict(os.environ)
    with tempfile.TemporaryDirectory(prefix="clsolid-probe-") as scratch:
        env["POCL_CACHE_DIR"] = scratch  # a crashed build must not leave a broken binary in the user's cache
        args = [sys.executable, "-m", "clsolid.core.probe", device_key(dev), str(vector_width or 0), *SMOKE_TESTS]
        try:
            run = subprocess.run(args, env=env, capture_output=True, text=True, timeout=CHILD_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            return ProbeResult(False, f"building the kernels took over {CHILD_TIMEOUT_S} s")
    lines = run.stdout.strip().splitlines()
    if run.returncode == 0 and lines:
        return ProbeResult(**json.loads(lines[-1]))
    said = [ln.strip() for ln in run.stderr.splitlines() if ln.strip() and not ln.startswith(" ")]
    why = next((ln for ln in said if "error" in ln.lower()), said[-1] if said else "no output")
    return ProbeResult(False, f"the compiler crashed (exit status {run.returncode}): {why}")


def compile_and_run(dev: Any) -> ProbeResult:
    """Probe *dev* now (no cache): the tiny kernel, then a tiny synthesis, widest vectors first."""
    first = _in_child(dev, VECTOR_WIDTHS[0])
    if first.ok:
        return first
    if not _in_child(dev, None).ok:  # not even the tiny kernel: report the first failure
        return first
    for width in VECTOR_WIDTHS[1:]:
        result = _in_child(dev, width)
        if result.ok:
            return result
    return first


def _load_cache(path) -> dict:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _store(key: str, result: ProbeResult) -> None:
    """Add one answer to the on-disk cache (atomic replace; a lost race only costs a re-probe)."""
    path = cache_dir() / CACHE_FILE
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        data = _load_cache(path)
        data[key] = asdict(result)
        fd, tmp = tempfile.mkstemp(prefix=".probes-", dir=path.parent)
        with os.fdopen(fd, "w") as fh:
            json.dump(data, fh, indent=1)
        os.replace(tmp, path)
    except OSError as exc:
        log.debug("could not cache the probe of %s: %s", key, exc)


def probe(dev: Any) -> ProbeResult:
    """Whether *dev* can compile and run clsolid's kernels, from the cache or by trying once."""
    key = device_key(dev)
    if key in _memo:
        return _memo[key]
    try:
        result = ProbeResult(**_load_cache(cache_dir() / CACHE_FILE)[key])
    except (KeyError, TypeError):
        result = compile_and_run(dev)
        _store(key, result)
    _memo[key] = result
    return result


def _child_main(key: str, width: int, targets: list[str]) -> int:
    """``python -m clsolid.core.probe KEY WIDTH TARGET...``: probe the device whose key is KEY
    with the smoke tests TARGET; print JSON."""
    from .platforms import devices_of, platforms

    SMOKE_TESTS[:] = targets  # the parent's, so that the key matches
    for platform in platforms():
        for dev in devices_of(platform):
            if device_key(dev) == key:
                print(json.dumps(asdict(try_device(dev, width or None, targets))), flush=True)
                return 0
    print(f"no device has the key {key!r}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(_child_main(sys.argv[1], int(sys.argv[2]), sys.argv[3:]))
