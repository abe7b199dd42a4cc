"""OpenCL device discovery and selection.

Nothing here touches OpenCL at import time: ``pyopencl`` is imported inside the
functions, so ``import clsolid`` works on a machine without any OpenCL driver.
"""

from __future__ import annotations

import os
import warnings
from typing import Any

from ..errors import DeviceSkippedWarning, InputError, KernelBuildError, NoDeviceError
from .platforms import INSTALL_HINT, Device, devices_of, platforms
from .probe import probe

__all__ = ["Device", "INSTALL_HINT", "select_device", "list_devices", "device_index", "type_name"]

#: What to do about a CPU device whose compiler fails (e.g. PoCL's LLVM 14 on AMD Zen 5).
CPU_FIX = (
    "install Intel's CPU OpenCL runtime, which compiles on any x86-64 CPU: "
    "`pip install intel-opencl-rt intel-cmplr-lib-rt` (or `pip install \"clsolid[cpu]\"`), "
    "then select it with --device intel (device=\"intel\")"
)
GPU_FIX = "update the device's OpenCL driver, or choose another device (`clsolid devices` lists them)"


def type_name(device_type: int) -> str:
    """The device type as one word (``GPU``, ``ACCELERATOR``, ``CPU``, ``CUSTOM``), whatever other bits are set."""
    import pyopencl as cl

    for word in ("GPU", "ACCELERATOR", "CPU", "CUSTOM"):
        if device_type & getattr(cl.device_type, word):
            return word
    return "OTHER"


def list_devices(*, probe_devices: bool = True) -> list[dict]:
    """Describe every OpenCL device visible on this machine.

    Parameters
    ----------
    probe_devices : bool
        Also say whether each device compiles and runs clsolid's kernels (see
        :func:`clsolid.core.probe.probe`; cached per device and driver version, so only the
        first call builds anything).

    Returns
    -------
    list of dict
        One entry per device with keys ``index`` (``"p:d"``, usable as a device spec),
        ``platform``, ``name``, ``type`` (``"CPU"``, ``"GPU"``, ``"ACCELERATOR"``…),
        ``compute_units``, ``global_mem``, ``max_alloc``, ``fp64``, ``driver``
        (driver version), ``opencl_c`` (OpenCL C version) and, when probed,
        ``compiles`` (bool), ``probe_message`` (the compiler's complaint, or "") and
        ``vector_width`` (the widest kernel vectors it handles, used by default).

    Raises
    ------
    NoDeviceError
        If no OpenCL platform is installed.
    """
    out = []
    for ip, platform in enumerate(platforms()):
        for idev, dev in enumerate(devices_of(platform)):
            entry = {
                "index": f"{ip}:{idev}",
                "platform": platform.name.strip(),
                "name": dev.name.strip(),
                "type": type_name(dev.type),
                "compute_units": int(dev.max_compute_units),
                "global_mem": int(dev.global_mem_size),
                "max_alloc": int(dev.max_mem_alloc_size),
                "fp64": bool(dev.double_fp_config),
                "driver": dev.driver_version.strip(),
                "opencl_c": dev.opencl_c_version.strip(),
            }
            if probe_devices:
                result = probe(dev)
                entry["compiles"], entry["probe_message"] = result.ok, result.message
                entry["vector_width"] = result.vector_width
            out.append(entry)
    return out


def device_index(device: Device) -> str:
    """The ``"platform:device"`` index of *device* among this machine's OpenCL devices: a spec
    that another process on this machine (a Dask worker) opens as the same device."""
    for ip, platform in enumerate(platforms()):
        for idev, dev in enumerate(devices_of(platform)):
            if dev == device.device:
                return f"{ip}:{idev}"
    raise NoDeviceError(f"{device.name} is not among this machine's OpenCL devices; give a device spec instead")


def _pick(items: list, token: str, what: str, label) -> Any:
    """Pick an item by index or by case-insensitive substring of its label."""
    token = token.strip()
    if token.isdigit():
        i = int(token)
        if i >= len(items):
            raise NoDeviceError(
                f"{what} index {i} does not exist (there are {len(items)}); "
                "run `clsolid devices` to list them"
            )
        return items[i]
    matches = [it for it in items if token.lower() in label(it).lower()]
    if not matches:
        names = ", ".join(repr(label(it)) for it in items)
        raise NoDeviceError(
            f"no {what} matches {token!r} (have: {names}); run `clsolid devices` to list them"
        )
    return matches[0]


def _score(dev) -> tuple:
    import pyopencl as cl

    return (bool(dev.type & cl.device_type.GPU), int(dev.global_mem_size))


def _names(dev) -> tuple[str, ...]:
    """What a name given as ``--device`` may match: the device, its platform's name, vendor and
    version ("pocl" is only in PoCL's version string)."""
    p = dev.platform
    return dev.name, p.name, p.vendor, p.version


def _label(dev) -> str:
    return f"{dev.platform.name.strip()} / {dev.name.strip()}"


def _fix_for(dev) -> str:
    import pyopencl as cl

    return CPU_FIX if dev.type & cl.device_type.CPU else GPU_FIX


def _candidates(spec: str | None) -> tuple[list, bool]:
    """Devices matching *spec* (PYOPENCL_CTX syntax or a name), and whether one was named exactly."""
    found = platforms()
    all_devices = [d for p in found for d in devices_of(p)]
    if not all_devices:
        raise NoDeviceError(f"OpenCL platforms exist but expose no device. {INSTALL_HINT}.")
    if spec is None or not spec.strip():
        return all_devices, False
    spec = spec.strip()
    if ":" in spec:
        ptok, dtok = spec.split(":", 1)
        platform = _pick(found, ptok, "OpenCL platform", lambda p: p.name)
        devices = devices_of(platform)
        if not dtok.strip():
            return devices, False
        return [_pick(devices, dtok, f"device on platform {platform.name.strip()!r}", lambda d: d.name)], True
    if spec.isdigit():
        return devices_of(_pick(found, spec, "OpenCL platform", lambda p: p.name)), False
    low = spec.lower()
    if low in ("cpu", "gpu", "accelerator"):
        import pyopencl as cl

        kind = getattr(cl.device_type, low.upper())
        typed = [d for d in all_devices if d.type & kind]
        if not typed:
            raise NoDeviceError(f"no OpenCL device of type {low!r}; run `clsolid devices` to list them")
        return typed, False
    by_name = [d for d in all_devices if any(low in text.lower() for text in _names(d))]
    if not by_name:
        names = ", ".join(repr(d.name.strip()) for d in all_devices)
        raise NoDeviceError(f"no OpenCL device matches {spec!r} (have: {names}); run `clsolid devices`")
    return by_name, len(by_name) == 1


def _resolve(spec: str | None):
    """The best device matching *spec* that compiles; skips (with a warning) those that do not."""
    candidates, exact = _candidates(spec)
    failed = [(d, probe(d)) for d in candidates]
    working = [d for d, result in failed if result.ok]
    failed = [(d, result) for d, result in failed if not result.ok]
    if exact and failed:
        dev, result = failed[0]
        raise KernelBuildError(f"the OpenCL device {_label(dev)} cannot compile kernels "
                               f"({result.message}); {_fix_for(dev)}")
    if not working:
        why = "; ".join(f"{_label(d)}: {r.message}" for d, r in failed)
        raise NoDeviceError(f"no OpenCL device{'' if spec is None else f' matching {spec!r}'} can compile "
                            f"kernels ({why}). {INSTALL_HINT}.")
    for dev, result in failed:
        warnings.warn(f"skipping OpenCL device {_label(dev)}: it cannot compile kernels ({result.message})",
                      DeviceSkippedWarning, stacklevel=4)
    return max(working, key=_score)


#: Each device opened once a process: its context, queue and the programs built on it serve
#: every later run (a build costs up to seconds; docs/benchmarks.md).
_OPENED: dict[int, Device] = {}


def select_device(spec: "str | Device | None" = None) -> Device:
    """Choose an OpenCL device and open its context and queue (once a process).

    Parameters
    ----------
    spec : str, Device or None
        ``PYOPENCL_CTX`` syntax (``"0"``, ``"0:1"``, ``"portable:"``), a substring of a
        device or platform name (``"pocl"``, ``"H100"``), or a type (``"cpu"``, ``"gpu"``).
        ``None`` falls back to ``$CLSOLID_DEVICE``, then ``$PYOPENCL_CTX``, then the best
        device (a GPU first, then the most global memory). Never prompts. Devices
        that cannot compile a tiny probe kernel (cached per driver version) are
        skipped, with a :class:`DeviceSkippedWarning`.

    Returns
    -------
    Device
        The same object for the same device throughout the process, so that the programs
        built for one run serve the next.

    Raises
    ------
    NoDeviceError
        No OpenCL platform, nothing matches *spec*, or no matching device compiles;
        the message says how to fix it.
    KernelBuildError
        *spec* names exactly one device and it cannot compile (the message gives the
        compiler's complaint and the fix).
    """
    if isinstance(spec, Device):
        return spec
    if spec is not None and not isinstance(spec, str):
        raise InputError(f"device={spec!r} must be a string (PYOPENCL_CTX syntax such as '0' or '0:1', a name, "
                         "'cpu' or 'gpu'), a Device or None")
    import pyopencl as cl

    if spec is None:
        spec = os.environ.get("CLSOLID_DEVICE") or os.environ.get("PYOPENCL_CTX")
    dev = _resolve(spec)
    opened = _OPENED.get(dev.int_ptr)
    if opened is None:
        ctx = cl.Context([dev])
        opened = _OPENED[dev.int_ptr] = Device(device=dev, context=ctx, queue=cl.CommandQueue(ctx))
    return opened
