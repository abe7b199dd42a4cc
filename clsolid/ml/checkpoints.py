"""Checkpoints of a likelihood run: what :func:`clsolid.synthesize` writes with
``checkpoint=`` and what :func:`clsolid.resume` reads back (the folder format is
:mod:`clsolid.core.checkpoint`'s)."""

from __future__ import annotations

import os
import time
from typing import Any, Callable

import numpy as np

from ..core.checkpoint import CheckpointError, read_checkpoint, write_checkpoint
from ..core.views import VIEW_ORDER
from .driver import RunState
from .params import MLParams


class Checkpointer:
    """The ``checkpoint`` of :func:`~clsolid.ml.driver.run_ml`: writes *folder* after a sweep
    when *every_s* seconds have passed since the last write (0: every sweep), and always
    after the sweep that ends a scale. :meth:`due` says so before the state is gathered,
    so a sweep that writes nothing reads nothing back from the device. The exemplar as
    loaded goes in too, so a resumed run needs nothing else."""

    def __init__(self, folder: str | os.PathLike, every_s: float, meta: dict[str, Any],
                 exemplar: np.ndarray | dict[str, np.ndarray]) -> None:
        self.folder, self.every_s, self.meta, self.exemplar = folder, every_s, meta, exemplar
        self.last = -np.inf

    def due(self, scale_done: bool) -> bool:
        return scale_done or time.monotonic() - self.last >= self.every_s

    def save(self, state: RunState) -> None:
        write_checkpoint(self.folder, {**self.meta, "timings": state.timings},
                         {**state.arrays(), **exemplar_arrays(self.exemplar)})
        self.last = time.monotonic()


def check_every(value: Any) -> float:
    """``checkpoint_every``: seconds between checkpoints, a finite number >= 0."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value) or value < 0:
        raise CheckpointError(f"checkpoint_every={value!r} must be a number of seconds >= 0 (0: every sweep)")
    return float(value)


def load_run(folder: str | os.PathLike, empty: Callable[[tuple, np.dtype], np.ndarray] = np.empty
             ) -> tuple[dict[str, Any], MLParams, np.ndarray | dict[str, np.ndarray], RunState]:
    """The description, parameters, exemplar and state of a likelihood run's checkpoint, its
    arrays made by *empty* (:func:`clsolid.core.checkpoint.read_checkpoint`).

    Raises
    ------
    CheckpointError
        Not a checkpoint, corrupt, or not of a likelihood run.
    """
    meta, arrays = read_checkpoint(folder, empty)
    if meta.get("method") != "ml":
        raise CheckpointError(f"{folder} is a checkpoint of method {meta.get('method')!r}; only 'ml' runs resume")
    missing = {"volume", "temperature", "inherited", "bias", "scalars", "position"} - set(arrays)
    if missing or not {"params", "shape", "seed", "timings"} <= set(meta):
        raise CheckpointError(f"{folder} lacks {sorted(missing) or 'part of its description'}: the checkpoint "
                              "is corrupt")
    params = MLParams.from_dict(meta["params"])
    if params.likelihood == "pruned" and "sources" not in arrays:
        raise CheckpointError(f"{folder} is of a likelihood='pruned' run but holds no sources: the checkpoint "
                              "is corrupt")
    exemplar = arrays.get("exemplar")
    if exemplar is None:  # one per view
        exemplar = {v: arrays[f"exemplar_{v}"] for v in VIEW_ORDER if f"exemplar_{v}" in arrays} or None
    if exemplar is None:
        raise CheckpointError(f"{folder}: the checkpoint holds no exemplar: it is corrupt")
    return meta, params, exemplar, RunState.from_arrays(arrays, meta["timings"])


def exemplar_arrays(exemplar: np.ndarray | dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The arrays a checkpoint keeps its exemplar in: ``exemplar``, or ``exemplar_<view>`` for each view's."""
    if isinstance(exemplar, dict):
        return {f"exemplar_{v}": im for v, im in exemplar.items()}
    return {"exemplar": exemplar}
