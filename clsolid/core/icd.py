"""Make a pip-installed Intel CPU OpenCL runtime visible, without hiding any other platform.

Why: the PoCL that ``pip install "pyopencl[pocl]"`` brings is built on LLVM 14, which
cannot compile for CPUs newer than it (AMD Zen 5: "unknown target CPU 'generic'").
Intel's CPU runtime from PyPI (``intel-opencl-rt``) compiles on any x86-64 CPU, AMD's
included, but the ICD file its wheel installs names a placeholder path
(``/opt/anaconda1anaconda2anaconda3/lib/libintelocl.so``), and the OpenCL loader does not
look in the Python prefix anyway, so it stays invisible.

How: before the first OpenCL call of the process, and only when the user has not set
``OCL_ICD_VENDORS`` themselves, clsolid writes a vendors directory in its user cache
holding one ``.icd`` file per system ICD (``/etc/OpenCL/vendors``, or
``$OPENCL_VENDOR_PATH``; a GPU's driver stays listed) plus one naming the real path of
the installed ``libintelocl.so``, and points ``OCL_ICD_VENDORS`` at it. Both the ocl-icd
loader bundled in pyopencl's wheel (which also keeps finding its own PoCL) and the
Khronos loader honour that variable. No root is needed and nothing outside the cache is
written. Setting ``OCL_ICD_VENDORS`` yourself turns this off.
"""

from __future__ import annotations

import hashlib
import logging
import os
import sys
import tempfile
from pathlib import Path

log = logging.getLogger(__name__)

SYSTEM_VENDORS = "/etc/OpenCL/vendors"
INTEL_DISTRIBUTION = "intel-opencl-rt"
INTEL_LIBRARY = "libintelocl.so"
_applied: str | None = None


def cache_dir() -> Path:
    """clsolid's per-user cache: ``$CLSOLID_CACHE_DIR``, else ``$XDG_CACHE_HOME/clsolid``."""
    explicit = os.environ.get("CLSOLID_CACHE_DIR")
    if explicit:
        return Path(explicit)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "clsolid"


def intel_cpu_library() -> Path | None:
    """Path of the ``libintelocl.so`` that pip installed, or None."""
    try:
        from importlib import metadata

        dist = metadata.distribution(INTEL_DISTRIBUTION)
        for entry in dist.files or ():
            if entry.name == INTEL_LIBRARY:
                path = Path(dist.locate_file(entry)).resolve()
                if path.is_file():
                    return path
    except Exception:  # noqa: BLE001 - not installed, or unreadable metadata
        pass
    for prefix in {sys.prefix, sys.base_prefix}:  # wheels put their data files in <prefix>/lib
        path = Path(prefix) / "lib" / INTEL_LIBRARY
        if path.is_file():
            return path.resolve()
    return None


def system_icds(vendor_dir: str | None = None) -> dict[str, str]:
    """``{file name: library}`` of every ``.icd`` file in the system's vendors directory."""
    folder = Path(vendor_dir or os.environ.get("OPENCL_VENDOR_PATH") or SYSTEM_VENDORS)
    out = {}
    try:
        entries = sorted(folder.iterdir())
    except OSError:
        return out
    for entry in entries:
        if entry.suffix == ".icd":
            try:
                out[entry.name] = entry.read_text().strip()
            except OSError as exc:
                log.debug("skipping unreadable ICD file %s: %s", entry, exc)
    return out


def vendor_entries(intel: Path | None, system: dict[str, str]) -> dict[str, str]:
    """The ``.icd`` files to offer the loader: the system's, plus the pip-installed Intel CPU one."""
    entries = dict(system)
    if intel is not None:
        entries["clsolid-intel-cpu.icd"] = str(intel)
    return entries


def write_vendor_dir(entries: dict[str, str], root: Path) -> Path:
    """Write *entries* into a directory named by their content (atomic, safe in parallel)."""
    digest = hashlib.sha256(repr(sorted(entries.items())).encode()).hexdigest()[:16]
    target = root / f"opencl-vendors-{digest}"
    if target.is_dir():
        return target
    root.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=".vendors-", dir=root))
    for name, library in entries.items():
        (staging / name).write_text(library + "\n")
    try:
        staging.rename(target)
    except OSError:  # another process won the race: its directory is identical
        for f in staging.iterdir():
            f.unlink()
        staging.rmdir()
    return target


def ensure_vendors() -> str | None:
    """Point ``OCL_ICD_VENDORS`` at a directory that also lists the pip-installed Intel CPU runtime.

    Called before clsolid's first OpenCL call. Does nothing when ``OCL_ICD_VENDORS`` is
    already set or when no pip-installed Intel runtime exists. Returns the directory in
    use, or None.
    """
    global _applied
    if _applied is not None or os.environ.get("OCL_ICD_VENDORS"):
        return _applied
    intel = intel_cpu_library()
    if intel is None:
        return None
    entries = vendor_entries(intel, system_icds())
    try:
        folder = write_vendor_dir(entries, cache_dir())
    except OSError:
        user = getattr(os, "getuid", lambda: "user")()  # a read-only home: a per-user temporary folder
        folder = write_vendor_dir(entries, Path(tempfile.gettempdir()) / f"clsolid-{user}")
    os.environ["OCL_ICD_VENDORS"] = _applied = str(folder)
    log.debug("OCL_ICD_VENDORS=%s (%s)", folder, ", ".join(entries))
    return _applied
