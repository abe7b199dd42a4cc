"""OpenCL device discovery and selection.

Nothing here touches OpenCL at import time: ``pyopencl`` is imported inside the
functions, so ``import clsolid`` works on a machine without any OpenCL driver.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

from .errors import NoDeviceError

INSTALL_HINT = (
    "Install an OpenCL driver (ICD): on a CPU-only machine `pip install \"pyopencl[pocl]\"` "
    "gives PoCL; on a GPU machine install the vendor's OpenCL runtime"
)


@dataclass
class Device:
    """A chosen OpenCL device with its context and in-order queue.

    Attributes
    ----------
    device, context, queue
        The ``pyopencl`` objects.
    programs : dict
        Program cache of this context, keyed by (source, options); see ``clsolid._kernels``.
    """

    device: Any
    context: Any
    queue: Any
    programs: dict = field(default_factory=dict, repr=False)

    @property
    def name(self) -> str:
        return f"{self.device.platform.name.strip()} / {self.device.name.strip()}"

    @property
    def max_alloc(self) -> int:
        return int(self.device.max_mem_alloc_size)

    @property
    def global_mem(self) -> int:
        return int(self.device.global_mem_size)

    @property
    def is_cpu(self) -> bool:
        import pyopencl as cl

        return bool(self.device.type & cl.device_type.CPU)


def _platforms():
    try:
        import pyopencl as cl
    except ImportError as exc:  # pragma: no cover - pyopencl is a hard dependency
        raise NoDeviceError(f"pyopencl cannot be imported ({exc}). {INSTALL_HINT}.") from exc
    try:
        platforms = cl.get_platforms()
    except cl.Error as exc:
        raise NoDeviceError(f"no OpenCL platform found ({exc}). {INSTALL_HINT}.") from exc
    if not platforms:
        raise NoDeviceError(f"no OpenCL platform found. {INSTALL_HINT}.")
    return platforms


def _devices_of(platform) -> list:
    import pyopencl as cl

    try:
        return list(platform.get_devices())
    except cl.Error:
        return []


def list_devices() -> list[dict]:
    """Describe every OpenCL device visible on this machine.

    Returns
    -------
    list of dict
        One entry per device with keys ``index`` (``"p:d"``, usable as a device spec),
        ``platform``, ``name``, ``type``, ``compute_units``, ``global_mem``, ``max_alloc``
        and ``fp64``.

    Raises
    ------
    NoDeviceError
        If no OpenCL platform is installed.
    """
    import pyopencl as cl

    out = []
    for ip, platform in enumerate(_platforms()):
        for idev, dev in enumerate(_devices_of(platform)):
            out.append(
                {
                    "index": f"{ip}:{idev}",
                    "platform": platform.name.strip(),
                    "name": dev.name.strip(),
                    "type": cl.device_type.to_string(dev.type),
                    "compute_units": int(dev.max_compute_units),
                    "global_mem": int(dev.global_mem_size),
                    "max_alloc": int(dev.max_mem_alloc_size),
                    "fp64": bool(dev.double_fp_config),
                }
            )
    return out


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


def _resolve(spec: str | None):
    """Return the pyopencl device for *spec* (PYOPENCL_CTX syntax or a name)."""
    platforms = _platforms()
    all_devices = [d for p in platforms for d in _devices_of(p)]
    if not all_devices:
        raise NoDeviceError(f"OpenCL platforms exist but expose no device. {INSTALL_HINT}.")
    if spec is None or not spec.strip():
        return max(all_devices, key=_score)
    spec = spec.strip()
    if ":" in spec:
        ptok, dtok = spec.split(":", 1)
        platform = _pick(platforms, ptok, "OpenCL platform", lambda p: p.name)
        devices = _devices_of(platform)
        if not dtok.strip():
            return max(devices, key=_score)
        return _pick(devices, dtok, f"device on platform {platform.name.strip()!r}", lambda d: d.name)
    if spec.isdigit():
        return max(_devices_of(_pick(platforms, spec, "OpenCL platform", lambda p: p.name)), key=_score)
    low = spec.lower()
    if low in ("cpu", "gpu", "accelerator"):
        import pyopencl as cl

        kind = getattr(cl.device_type, low.upper())
        typed = [d for d in all_devices if d.type & kind]
        if not typed:
            raise NoDeviceError(f"no OpenCL device of type {low!r}; run `clsolid devices` to list them")
        return max(typed, key=_score)
    by_name = [d for d in all_devices if low in d.name.lower() or low in d.platform.name.lower()]
    if not by_name:
        names = ", ".join(repr(d.name.strip()) for d in all_devices)
        raise NoDeviceError(f"no OpenCL device matches {spec!r} (have: {names}); run `clsolid devices`")
    return max(by_name, key=_score)


def select_device(spec: "str | Device | None" = None) -> Device:
    """Choose an OpenCL device and create its context and queue.

    Parameters
    ----------
    spec : str, Device or None
        ``PYOPENCL_CTX`` syntax (``"0"``, ``"0:1"``, ``"portable:"``), a substring of a
        device or platform name (``"pocl"``, ``"H100"``), or a type (``"cpu"``, ``"gpu"``).
        ``None`` falls back to ``$CLSOLID_DEVICE``, then ``$PYOPENCL_CTX``, then the best
        device (a GPU first, then the most global memory). Never prompts.

    Returns
    -------
    Device

    Raises
    ------
    NoDeviceError
        No OpenCL platform, or nothing matches *spec*; the message says how to fix it.
    """
    if isinstance(spec, Device):
        return spec
    import pyopencl as cl

    if spec is None:
        spec = os.environ.get("CLSOLID_DEVICE") or os.environ.get("PYOPENCL_CTX")
    dev = _resolve(spec)
    ctx = cl.Context([dev])
    return Device(device=dev, context=ctx, queue=cl.CommandQueue(ctx))
