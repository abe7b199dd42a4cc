"""Settings named after the thesis's experiments (thesis_spec §6.5), so that they can be rerun.

A preset is a method, a block size, an exemplar size and ``synthesize`` keywords, with the
thesis section it comes from and, plainly, what clsolid cannot honour yet. Use it from
Python as ``synthesize(exemplar, preset.shape, method=preset.method, **preset.options)``
(:meth:`Preset.keywords` gives all three) or from the command line with
``clsolid synth --preset NAME``, where any flag given explicitly overrides the preset.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .errors import InputError

#: The thesis's ML settings (ICM, no balance, thesis bandwidth and pyramid, aligned ``+in``
#: tiled seams and all, the exact Parzen sum of squared grey-level differences, every term alike).
_ML_THESIS = dict(relaxation="icm", balance=0.0, bandwidth_factor=1.0, pyramid="decimate",
                  slice_layout="aligned", xi=-3.0, stop_fraction=0.95, heuristic="h2-product",
                  likelihood="exact", distance="squared", falloff=0.0, seam_gap=0,
                  parent_weight=0.0, shared_weight=1.0)
_NP_ORDER = ("the thesis visits voxels in a random scan; clsolid updates conflict-free sets in a "
             "seeded order (order='random' is the sequential random scan, for small blocks)")
_NP_K = ("k = 15 is NP_CW's candidate set (method='chen-wang', candidates=15); NP_K's search here is "
         "exact (search='coherence' is the accelerated one)")


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
        ``synthesize`` keywords.
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

    def keywords(self) -> dict[str, Any]:
        """``shape``, ``method`` and the options, ready for ``synthesize(exemplar, **kw)``."""
        return {"shape": self.shape, "method": self.method, **self.options}


def _np(name: str, neighborhood: int, source: str, *extra: str, **options: Any) -> Preset:
    opts = {"neighborhood": neighborhood, "scales": 3, "iterations": 10, "views": 2, "levels": 32,
            "specify": False, "balance": 0.0, "insert_spacing": 0.0, "parent_weight": 1.0, "distance": "squared",
            "search": "exact", **options}
    return Preset(name, "kopf", (64, 64, 64), 64, opts, source, (_NP_ORDER, _NP_K, *extra))


def _ml(name: str, neighborhood: int, upsampling: str, slices: int, source: str, *extra: str) -> Preset:
    opts = {**_ML_THESIS, "neighborhood": neighborhood, "scales": 3, "upsampling": upsampling,
            "inherited": "resynthesize", "insert_slices": slices, "views": 2, "levels": 32}
    order = "the thesis's random scan is clsolid's conflict-free sets in a seeded order"
    return Preset(name, "ml", (64, 64, 64), 64, opts, source, (order, *extra))


_NOISE = ("the thesis starts each level from noise plus exemplar patches; clsolid's kopf starts a "
          "finer level from the coarser result (init='noise' is plain noise)")

PRESETS: dict[str, Preset] = {p.name: p for p in (
    _np("ch5_np_common", 7, "thesis §5.2.1 (NP_K, the common settings)", _NOISE),
    _np("ch5_np_11", 11, "thesis §5.2.1 (NP_K, 11x11)", _NOISE),
    _ml("ch5_ml_common", 7, "8/8", 0, "thesis §5.3.1 (NP_ML, the common settings)",
        "-in (no inserted slices) collapses to the exemplar's mode under ICM, as docs/choices.md explains"),
    _ml("ch5_compare", 9, "1/8", 4, "thesis §5.4 (NP_ML against NP_K; for NP_K use ch5_np_common with "
        "neighborhood 9)"),
    Preset("ch6_hrtem_np", "kopf", (128, 128, 128), 128,
           {"neighborhood": 7, "scales": 5, "iterations": 10, "views": 2, "levels": 32, "specify": False,
            "balance": 0.0, "insert_spacing": 0.0, "search": "exact"},
           "thesis §6.3.3 (NP_K on an HRTEM image)",
           ("the thesis visits voxels along a 3D Hilbert curve; clsolid updates conflict-free sets in a "
            "seeded order (order='hilbert' visits one voxel at a time, about 0.7 ms a voxel: hours at 128^3)",
            _NP_K)),
    _ml("ch6_hrtem_ml", 9, "1/8", 4, "thesis §6.3.4 (NP_ML_H2c on an HRTEM image)"),
    Preset("ch5_views", "kopf", (64, 64, 64), 64,
           {"neighborhood": 11, "scales": 3, "iterations": 10, "views": 3, "levels": 32, "specify": False,
            "balance": 0.0, "insert_spacing": 0.0, "search": "exact"},
           "thesis §5.5 (NP_K, 11x11, with 1, 2 and 3 views; views=2 for the second)",
           ("one constrained view is not supported: the 1-view run of the thesis cannot be repeated", _NP_ORDER)),
)}


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
