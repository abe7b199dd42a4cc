"""What the search methods' per-voxel rules need at one pyramid level."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..exemplar import nearest_level_index
from .params import SearchParams


class LevelHistogram:
    """Grey-level histograms of the exemplar and of the block at one level, on the finest
    exemplar's own values as bins (each value counts for the nearest), kept up to date as
    voxels change (``kopf``'s re-weighting, thesis_spec §1.6.2)."""

    def __init__(self, finest: np.ndarray, exemplar: np.ndarray, volume: np.ndarray) -> None:
        self.values = np.unique(finest)
        n = self.values.size
        self.exemplar = np.bincount(self.bin(exemplar), minlength=n) / exemplar.size
        self.counts = np.bincount(self.bin(volume), minlength=n).astype(np.int64)
        self.total = volume.size

    def bin(self, values: np.ndarray) -> np.ndarray:
        """The bin of each value (the nearest of the finest exemplar's values)."""
        return nearest_level_index(values, self.values)

    @property
    def volume(self) -> np.ndarray:
        """The block's histogram, as fractions."""
        return self.counts / self.total

    def replace(self, old: np.ndarray, new: np.ndarray) -> None:
        """Voxels whose values went from *old* to *new*."""
        n = self.values.size
        self.counts += np.bincount(self.bin(new), minlength=n) - np.bincount(self.bin(old), minlength=n)


@dataclass
class Level:
    """One level's matcher and tables: ``centres[s]`` is site s's centre value and
    ``patches[s]`` its k x k square, row by row; ``values`` the level image's distinct
    values; the first search of a voxel weighs its terms by ``w_first`` (centre left out),
    repeated ones by ``w_again``; ``histogram`` only for ``kopf``."""

    params: SearchParams
    matcher: Any
    centres: np.ndarray
    patches: np.ndarray
    values: np.ndarray
    w_first: np.ndarray
    w_again: np.ndarray
    histogram: LevelHistogram | None = None
