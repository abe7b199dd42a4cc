"""Reading TOML files (configs and presets), with errors that name the file and the line."""

from __future__ import annotations

import os
import sys
from typing import Any

from ..errors import InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib


def read_toml(path: str | os.PathLike) -> dict[str, Any]:
    """The contents of a TOML file; :class:`~clsolid.errors.InputError` if it cannot be read or parsed."""
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except OSError as exc:
        raise InputError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:  # TOML is UTF-8 text
        raise InputError(f"{path}: not valid TOML ({exc})") from None
