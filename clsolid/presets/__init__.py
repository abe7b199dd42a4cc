"""Settings named after the thesis's experiments, so that they can be rerun.

Each preset is a config file shipped with the package (``clsolid/presets/NAME.toml``): a
method, a block size, the built-in exemplar's size and the method's options, with the
thesis section it comes from and, plainly, what clsolid cannot honour yet. From the command
line, ``clsolid synth --preset NAME`` reads it as ``--config`` would (flags given explicitly
override it); from Python, ``synthesize(exemplar, **get_preset(NAME).keywords())``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..core.tomlfile import read_toml
from ..errors import InputError

#: The folder of the preset files.
FOLDER = Path(__file__).resolve().parent
#: Keys of a preset file that are not the method's options.
_RUN_KEYS = ("method", "shape", "builtin_size", "about")


@dataclass(frozen=True)
class Preset:
    """One thesis experiment's settings.

    Attributes
    ----------
    name : str
        The preset's name (``ch5_np_common``, ...).
    method : str
        ``synthesize``'s ``method``.
    shape : tuple of 3 ints
        The block the thesis grew.
    exemplar_size : int
        The side the thesis's exemplar had (built-in exemplars are made at this side).
    options : dict
        The method's options (``synthesize`` keywords).
    source : str
        The thesis section.
    departures : tuple of str
        What the thesis did that clsolid does not (yet), in words.
    """

    name: str
    method: str
    shape: tuple[int, int, int]
    exemplar_size: int
    options: dict[str, Any]
    source: str
    departures: tuple[str, ...] = field(default=())

    @property
    def path(self) -> Path:
        """The preset's file (a config ``clsolid synth --config`` reads)."""
        return FOLDER / f"{self.name}.toml"

    def keywords(self) -> dict[str, Any]:
        """``shape``, ``method`` and the options, ready for ``synthesize(exemplar, **kw)``."""
        return {"shape": self.shape, "method": self.method, **self.options}


def _read(path: Path) -> Preset:
    data = read_toml(path)
    about = data.get("about", {})
    return Preset(name=path.stem, method=data["method"], shape=tuple(data["shape"]),
                  exemplar_size=int(data["builtin_size"]),
                  options={k: v for k, v in data.items() if k not in _RUN_KEYS},
                  source=about.get("source", ""), departures=tuple(about.get("departures", ())))


#: Every preset, by name.
PRESETS: dict[str, Preset] = {p.stem: _read(p) for p in sorted(FOLDER.glob("*.toml"))}


def get_preset(name: str) -> Preset:
    """The preset called *name*.

    Raises
    ------
    InputError
        No preset has that name (the message lists them).
    """
    try:
        return PRESETS[name]
    except (KeyError, TypeError):
        raise InputError(f"preset {name!r} is not known; use one of: {', '.join(PRESETS)}") from None
