"""Checkpoints of a likelihood run: what :func:`clsolid.synthesize` writes with
``checkpoint=`` and what :func:`clsolid.resume` reads back (the folder format is
:mod:`clsolid.core.checkpoint`'s)."""

from __future__ import annotations

import os
import time
from typing import Any, Callable

import numpy as np

from ..core.checkpoint import CheckpointError, read_checkpoint, write_checkpoint
from .driver import RunState
from .params import MLParams


def checkpointer(folder: str | os.PathLike, every_s: float, meta: dict[str, Any],
                 exemplar: np.ndarray) -> Callable[[RunState], None]:
    """A ``checkpoint`` hook for :func:`~clsolid.ml.driver.run_ml` that writes *folder* after
    a sweep when *every_s* seconds have passed since the last write (0: every sweep), and
    always after the sweep that ends a scale. The exemplar as loaded goes in too, so a
    resumed run needs nothing else."""
    last = [-np.inf]

    def save(state: RunState) -> None:
        now = time.monotonic()
        if state.done or now - last[0] >= every_s:
            write_checkpoint(folder, {**meta, "timings": state.timings}, {**state.arrays(), "exemplar": exemplar})
            last[0] = now

    return save


def check_every(value: Any) -> float:
    """``checkpoint_every``: seconds between checkpoints, a finite number >= 0."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value) or value < 0:
        raise CheckpointError(f"checkpoint_every={value!r} must be a number of seconds >= 0 (0: every sweep)")
    return float(value)


def load_run(folder: str | os.PathLike) -> tuple[dict[str, Any], MLParams, np.ndarray, RunState]:
    """The description, parameters, exemplar and state of a likelihood run's checkpoint.

    Raises
    ------
    CheckpointError
        Not a checkpoint, corrupt, or not of a likelihood run.
    """
    meta, arrays = read_checkpoint(folder)
    if meta.get("method") != "ml":
        raise CheckpointError(f"{folder} is a checkpoint of method {meta.get('method')!r}; only 'ml' runs resume")
    missing = {"exemplar", "volume", "temperature", "inherited", "bias", "scalars", "position"} - set(arrays)
    if missing or not {"params", "shape", "seed", "timings"} <= set(meta):
        raise CheckpointError(f"{folder} lacks {sorted(missing) or 'part of its description'}: the checkpoint "
                              "is corrupt")
    params = MLParams.from_dict(meta["params"])
    return meta, params, arrays["exemplar"], RunState.from_arrays(arrays, meta["timings"])
