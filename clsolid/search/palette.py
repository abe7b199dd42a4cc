"""Colour exemplars in the search methods: the block holds palette labels, and squares are
compared in CIELAB (docs/design.md#colour-search).

A colour exemplar arrives as labels of a palette (:func:`clsolid.colour.palette`), each
label a CIELAB colour. The block, the exemplar's pyramid and the tables all hold labels;
only where squares are compared does each label become its three CIELAB coordinates, so a
square of k x k labels is a row of 3 k^2 terms and the matchers' squared distance is the
sum of squared CIELAB distances over the square: the channels are one joint feature, as
the likelihood method's colour distance is. Where a method averages grey values (``wl``'s
mean, ``kopf``'s weighted mean) a colour voxel takes the weighted vote of the matched
colours instead (:meth:`clsolid.search.level.Level.blend`); ``chen-wang``'s solver takes the
matched colour nearest to their weighted mean in CIELAB. Every voxel stays a palette colour.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..colour import nearest
from .pyramid import gaussian_pyramid


@dataclass(frozen=True)
class Palette:
    """A palette's CIELAB colours *lab* ``(P, C)`` as the search compares them.

    *square* is the number of leading terms of a feature row that are the k x k square;
    the terms after it (the parent square) are scaled by *parent_scale* once encoded, as a
    grey table's parent terms are by the square root of ``parent_weight``.
    """

    lab: np.ndarray
    square: int
    parent_scale: float = 1.0

    @property
    def channels(self) -> int:
        return int(self.lab.shape[1])

    @property
    def span(self) -> float:
        """The largest CIELAB distance between two palette colours (1 if there is one colour):
        the range Kopf's ``eps`` is relative to."""
        d = np.sqrt(np.sum((self.lab[:, None, :] - self.lab[None, :, :]) ** 2, axis=-1))
        return float(d.max()) or 1.0

    def encode_terms(self, rows: np.ndarray) -> np.ndarray:
        """Feature *rows* ``(m, dim)`` of labels as the matcher compares them: ``(m, dim * C)``
        float64, term j's colour in columns ``j*C .. j*C + C - 1``."""
        rows = np.asarray(rows)
        out = self.lab[np.rint(rows).astype(np.intp)]  # (m, dim, C)
        if self.parent_scale != 1.0:
            out[:, self.square:, :] *= self.parent_scale
        return out.reshape(rows.shape[0], -1)

    def weights(self, weights: np.ndarray) -> np.ndarray:
        """Per-term *weights* ``(dim,)`` repeated for each channel of the term."""
        return np.repeat(np.asarray(weights), self.channels)

    def _mean(self, labels: np.ndarray, weights: np.ndarray | None) -> np.ndarray:
        colours = self.lab[np.rint(labels).astype(np.intp)]  # (views, m, C)
        if weights is None:
            return colours.mean(axis=0)
        w = np.asarray(weights, np.float64)[..., None]
        return (w * colours).sum(axis=0) / w.sum(axis=0)

    def solve(self, labels: np.ndarray, weights: np.ndarray) -> np.ndarray:
        """``chen-wang``'s discrete solver in colour: per column of *labels* ``(views, m)``, the
        row whose colour is nearest to the weighted mean colour (the first row on a tie)."""
        target = self._mean(labels, weights)
        colours = self.lab[np.rint(labels).astype(np.intp)]
        return np.argmin(np.sum((colours - target[None]) ** 2, axis=-1), axis=0)


def colour_pyramid(labels: np.ndarray, lab: np.ndarray, levels: int) -> list[np.ndarray]:
    """The search's pyramid (:func:`~clsolid.search.pyramid.gaussian_pyramid`) of a label image
    whose labels are the colours *lab*: each CIELAB channel filtered and decimated, each pixel
    of a coarser level the label of the nearest palette colour. Label images, float64,
    finest first (the finest is *labels* itself)."""
    channels = [gaussian_pyramid(lab[np.rint(labels).astype(np.intp)][..., c], levels) for c in range(lab.shape[1])]
    out = [np.asarray(labels, np.float64)]
    for level in range(1, levels):
        smooth = np.stack([ch[level] for ch in channels], axis=-1)
        out.append(nearest(smooth.reshape(-1, lab.shape[1]), lab).reshape(smooth.shape[:2]).astype(np.float64))
    return out
