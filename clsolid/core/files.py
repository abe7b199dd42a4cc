"""Files written whole or not at all: a crash, a full disk or a kill while writing leaves the
file that was there before (or none), never a partial one under the final name."""

from __future__ import annotations

import contextlib
import os
import uuid
from pathlib import Path
from typing import Iterator


def fsync_path(path: str | os.PathLike, folder: bool = False) -> None:
    """Flush *path* (a file, or a *folder*'s entries) to the disk. A folder that cannot be
    flushed (Windows opens none; some network filesystems refuse) is left to the system: the
    rename is done either way, only its surviving a power cut is less sure."""
    if not folder:
        fd = os.open(path, os.O_RDWR)  # Windows flushes only a file open for writing
    elif hasattr(os, "O_DIRECTORY"):
        try:
            fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY)
        except OSError:
            return
    else:
        return
    try:
        os.fsync(fd)
    except OSError:
        if not folder:
            raise
    finally:
        os.close(fd)


@contextlib.contextmanager
def replaced_atomically(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary name in *path*'s folder to write to; on success it is flushed to the disk and
    renamed to *path* (replacing what was there), on any error removed.

    The rename is atomic on one filesystem, hence the same folder; the flush before it makes the
    new name point at written data even after a power cut. The temporary name starts with a dot
    and ends in ``.partial``, so a kill that leaves it behind does not pass for a result.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write; its folder must exist.

    Yields
    ------
    pathlib.Path
        Where to write the file's whole content.
    """
    final = Path(path)
    tmp = final.with_name(f".{final.name}.{uuid.uuid4().hex[:8]}.partial")
    try:
        yield tmp
        fsync_path(tmp)
        os.replace(tmp, final)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    fsync_path(final.parent, folder=True)


def write_bytes_atomically(path: str | os.PathLike, data: bytes) -> Path:
    """Write *data* to *path* with :func:`replaced_atomically`; the path."""
    with replaced_atomically(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text_atomically(path: str | os.PathLike, text: str) -> Path:
    """Write *text* (UTF-8) to *path* with :func:`replaced_atomically`; the path."""
    return write_bytes_atomically(path, text.encode("utf-8"))
