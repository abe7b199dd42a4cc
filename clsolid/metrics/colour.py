"""Colour distances between a volume's slices and an RGB exemplar.

:func:`clsolid.metrics.evaluate` measures a colour volume's structure on luminance (every
grey distance), and its colours here: the joint colour histogram, each pixel counted as one
of the exemplar's colours (its palette of at most :data:`COLOUR_BINS`, k-means in CIELAB, as
:func:`clsolid.colour.palette` makes it), and each channel's own histogram.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..colour import float_top, full_scale, lab, nearest, palette
from . import references
from ._common import smoothed_probabilities, symmetric_kl

#: Colours of the joint histogram: the exemplar's palette, at most this many.
COLOUR_BINS = 32
#: Bins of each channel's histogram, over the channel's full range.
CHANNEL_BINS = 32
#: The joint distance's key in a view's ``distances``.
KEY = "colour_histogram_kl"


class ColourBins:
    """The joint colour bins of an RGB exemplar: its palette, and the nearest colour of any pixel."""

    def __init__(self, exemplar: np.ndarray, bins: int = COLOUR_BINS):
        self.dtype, self.top = exemplar.dtype, float_top(exemplar)
        _, values, _ = palette(exemplar, bins)
        self.values = values
        self.lab = lab(values, self.dtype, self.top)

    def index(self, rgb: np.ndarray) -> np.ndarray:
        """The palette index of each pixel of *rgb* ``(..., 3)`` (nearest in CIELAB)."""
        return nearest(lab(rgb.reshape(-1, 3), self.dtype, self.top), self.lab).reshape(rgb.shape[:-1])

    def counts(self, index: np.ndarray) -> np.ndarray:
        return np.bincount(np.ravel(index), minlength=len(self.values)).astype(np.float64)

    def distance(self, a: np.ndarray, b: np.ndarray) -> float:
        """Symmetric KL divergence between two index images' joint colour histograms."""
        return symmetric_kl(smoothed_probabilities(self.counts(a)), smoothed_probabilities(self.counts(b)))


def _channel_edges(exemplar: np.ndarray) -> np.ndarray:
    return np.linspace(0.0, full_scale(exemplar.dtype, float_top(exemplar)), CHANNEL_BINS + 1)


def channel_distances(exemplar: np.ndarray, stack: np.ndarray) -> dict[str, float]:
    """Each channel's histogram divergence (symmetric KL, ``CHANNEL_BINS`` bins over its full range)."""
    edges = _channel_edges(exemplar)
    out = {}
    for c, name in enumerate("RGB"):
        a = np.histogram(exemplar[..., c], edges)[0].astype(np.float64)
        b = np.histogram(stack[..., c], edges)[0].astype(np.float64)
        out[name] = symmetric_kl(smoothed_probabilities(a), smoothed_probabilities(b))
    return out


def colour_distances(exemplar: np.ndarray, stacks: dict[str, np.ndarray], gen: np.random.Generator,
                     repeats: int) -> tuple[dict[str, dict[str, Any]], dict[str, dict[str, float]]]:
    """The joint colour-histogram distance of each view's slices ``(n, h, w, 3)``, with its
    floor (random halves of the exemplar, matched to the sizes compared) and ceiling
    (uniform noise in the RGB cube, as many pixels as the view's), in the report's form;
    and each view's per-channel divergences."""
    bins = ColourBins(exemplar)
    ex = bins.index(exemplar)
    halves = [(bins.distance(a, b), a.size, b.size) for a, b in references.exemplar_halves(ex, gen, repeats)]
    top = _channel_edges(exemplar)[-1]
    joint, channels = {}, {}
    for view, stack in stacks.items():
        n = stack.size // 3
        value = bins.distance(ex, bins.index(stack))
        noise = [bins.distance(ex, bins.index(gen.uniform(0.0, top, (n, 3)))) for _ in range(repeats)]
        floor = references.floor_reference(halves, ex.size, n, 1.0)
        ceiling = references.spread(noise)
        joint[view] = {"label": "joint colour histogram", "units": "nats", "value": value, "floor": floor,
                       "ceiling": None if ceiling is None else {**ceiling, "kind": "noise"},
                       **references.readable(value, floor, ceiling)}
        channels[view] = channel_distances(exemplar, stack)
    return joint, channels
