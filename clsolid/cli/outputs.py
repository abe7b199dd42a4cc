"""Every file a command writes is checked before any work starts, and none is left half written."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from ..errors import InputError


def check_writable(flag: str, path: Path, folder: bool = False) -> None:
    """Refuse (:class:`~clsolid.errors.InputError`) a *path* the command could not write.

    Its folder (*path* itself where *folder*) is made if missing, and a file is really
    created there and removed: permissions alone do not tell (root passes them, and a
    pseudo-filesystem such as ``/proc`` takes no new files). An existing file is left as it is.
    """
    if not folder and path.is_dir():
        raise InputError(f"{flag} {path} is a folder; give a file name")
    where = path if folder else path.parent
    try:
        where.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"{flag} {path}: its folder cannot be made ({exc.strerror or exc}); choose a writable "
                         "folder") from None
    if not folder and path.exists():
        if not os.access(path, os.W_OK):
            raise InputError(f"{flag} {path} exists and cannot be replaced; choose another name")
        return
    try:
        with tempfile.NamedTemporaryFile(prefix=".clsolid-check-", dir=where):
            pass
    except OSError as exc:
        raise InputError(f"{flag} {path}: the folder {where} does not take new files ({exc.strerror or exc}); "
                         "choose another") from None
