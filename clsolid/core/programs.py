"""Locate the ``.cl`` sources and build programs, one cache per context."""

from __future__ import annotations

import functools
import warnings
from pathlib import Path

from .device import Device
from ..errors import KernelBuildError

_PACKAGE = Path(__file__).resolve().parents[1]  # clsolid/


def kernel_dir() -> Path:
    """Directory holding the OpenCL sources.

    A wheel installs them as ``clsolid/kernels``; a source checkout or an editable
    install keeps them in the top-level ``kernels/`` beside the package.
    """
    for candidate in (_PACKAGE / "kernels", _PACKAGE.parent / "kernels"):
        if (candidate / "ml" / "common.cl").is_file():
            return candidate
    raise FileNotFoundError(
        f"clsolid's OpenCL kernels were not found in {_PACKAGE / 'kernels'} or "
        f"{_PACKAGE.parent / 'kernels'}; reinstall clsolid (pip install clsolid)"
    )


@functools.lru_cache(maxsize=None)
def read_source(name: str) -> str:
    """Source of ``kernels/<name>`` (e.g. ``"ml/common.cl"``) prefixed by a ``#line`` so errors point at the file.

    Read once a process: the search drivers ask for their kernels once per conflict-free set,
    and reading the file each time shows in a run's profile."""
    path = kernel_dir() / name
    return f'#line 1 "kernels/{name}"\n' + path.read_text()


def include_options() -> list[str]:
    """Compiler options that make ``#include <pyopencl-random123/philox.cl>`` work."""
    import pyopencl as cl

    return ["-I", str(Path(cl.__file__).parent / "cl")]


def build(device: Device, name: str | tuple[str, ...], defines: dict[str, int | float] | None = None) -> dict:
    """Build ``kernels/<name>`` with ``-D`` *defines*; return its kernels by name. Several
    names: one program of their sources in that order (a file that uses another's functions
    after it).

    *defines* are for what changes the code (vector widths, array sizes, which terms exist);
    sizes and per-input tables go in kernel arguments, or every new input would be a new build.

    Programs are cached on the Device by (source, options) and every kernel object is
    retrieved once, so repeated calls are free.
    """
    import pyopencl as cl

    names = (name,) if isinstance(name, str) else tuple(name)
    source = "\n".join(read_source(n) for n in names)
    title = " + ".join(f"kernels/{n}" for n in names)
    # -w: PoCL on AVX2 CPUs notes that float16 arguments change the ABI, once per call
    # site, and prints "N warnings generated." on every run; nothing there is actionable.
    macros = tuple(f"-D{k}={v}" for k, v in sorted((defines or {}).items()))
    options = tuple(include_options()) + ("-w",) + macros
    key = (source, options)
    cached = device.programs.get(key)
    if cached is not None:
        return cached
    try:
        with warnings.catch_warnings():  # compiler chatter on a successful build (Intel's) is not news
            warnings.simplefilter("ignore", cl.CompilerWarning)
            program = cl.Program(device.context, source).build(options=list(options))
    except cl.RuntimeError as exc:
        raise KernelBuildError(
            f"building {title} with {' '.join(macros) or 'no defines'} failed on "
            f"{device.name}:\n{exc}"
        ) from exc
    kernels = {k.function_name: k for k in program.all_kernels()}
    device.programs[key] = kernels
    return kernels
