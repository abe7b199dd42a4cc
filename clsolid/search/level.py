"""What the search methods' per-voxel rules need at one pyramid level."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from ..core.views import DEPTH_AXIS
from ..exemplar import nearest_level_index
from .block import DeviceBlock
from .features import voxel_features
from .match import CLMatcher
from .params import SearchParams
from .projection import Projection
from ..phases import is_categorical


def vote(values: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Per column, the value of ``values (views, m)`` with the largest total weight (the
    first view's on a tie)."""
    support = np.stack([(weights * (values == values[j])).sum(axis=0) for j in range(values.shape[0])])
    return values[np.argmax(support, axis=0), np.arange(values.shape[1])]


class LevelHistogram:
    """Grey-level histograms of the exemplar and of the block at one level, on the finest
    exemplar's own values as bins (each value counts for the nearest), kept up to date as
    voxels change (``kopf``'s re-weighting, Urs thesis, §3.4.1).

    With *views*, the block's histogram is also kept per slice of each of those views
    (``histogram="slice"``): :meth:`slice_fractions` gives, for voxels, the histogram of
    their own slice in a view.
    """

    def __init__(self, finest: np.ndarray, exemplar: np.ndarray, volume: np.ndarray,
                 views: tuple[str, ...] = ()) -> None:
        self.values = np.unique(finest)
        n = self.values.size
        self.exemplar = np.bincount(self.bin(exemplar), minlength=n) / exemplar.size
        bins = self.bin(volume.ravel())
        self.counts = np.bincount(bins, minlength=n).astype(np.int64)
        self.total = volume.size
        self.shape = volume.shape
        self.slices = {}
        for view in views:  # counts[depth, bin] of every slice of the view
            self.slices[view] = np.zeros((volume.shape[DEPTH_AXIS[view]], n), np.int64)
            np.add.at(self.slices[view], (self._depth(view, np.arange(volume.size)), bins), 1)

    def bin(self, values: np.ndarray) -> np.ndarray:
        """The bin of each value (the nearest of the finest exemplar's values)."""
        return nearest_level_index(values, self.values)

    def _depth(self, view: str, voxels: np.ndarray) -> np.ndarray:
        return np.unravel_index(voxels, self.shape)[DEPTH_AXIS[view]]

    @property
    def volume(self) -> np.ndarray:
        """The block's histogram, as fractions."""
        return self.counts / self.total

    def slice_fractions(self, view: str, voxels: np.ndarray) -> np.ndarray:
        """``(len(voxels), bins)``: the histogram, as fractions, of each voxel's slice in *view*."""
        counts = self.slices[view][self._depth(view, voxels)]
        return counts / counts.sum(axis=1, keepdims=True)

    def replace(self, old: np.ndarray, new: np.ndarray, voxels: np.ndarray | None = None) -> None:
        """Voxels (flat indices *voxels*; needed with per-slice histograms) whose values went
        from *old* to *new*."""
        n = self.values.size
        b_old, b_new = self.bin(old), self.bin(new)
        self.counts += np.bincount(b_new, minlength=n) - np.bincount(b_old, minlength=n)
        for view, counts in self.slices.items():
            depth = self._depth(view, voxels)
            np.add.at(counts, (depth, b_old), -1)
            np.add.at(counts, (depth, b_new), 1)


@dataclass
class Level:
    """One level's matcher and tables: ``centres[s]`` is site s's centre value and
    ``patches[s]`` its k x k square, row by row; ``values`` the level image's distinct
    values; the first search of a voxel weighs its terms by ``w_first`` (centre left out),
    repeated ones by ``w_again``; ``span`` is the finest exemplar's range (1 if constant),
    the scale of Kopf's ``eps``; ``histogram`` for ``kopf``, ``sources``
    (:class:`~clsolid.search.chenwang.Sources`) for ``chen-wang``, ``coherence``
    (:class:`~clsolid.search.coherence.Coherence`) for the accelerated search; ``codes``
    (:class:`~clsolid.search.codes.PhaseCodes`) where the squares compare phase codes
    (the matcher's table holds them; ``patches`` and ``centres`` stay grey values);
    ``categorical`` whether the exemplar's values are phases (:func:`clsolid.phases.is_categorical`);
    ``colour`` (:class:`~clsolid.search.palette.Palette`) where the values are a colour palette's
    labels (the matcher's rows and the weights hold their colours, channel by channel)."""

    params: SearchParams
    matcher: Any
    centres: np.ndarray
    patches: np.ndarray
    values: np.ndarray
    w_first: np.ndarray
    w_again: np.ndarray
    span: float
    categorical: bool = False
    histogram: LevelHistogram | None = None
    sources: Any = None
    coherence: Any = None
    exhaustive: bool = False  # this pass searches every site even under the coherence search
    seeding: bool = False  # ...and seeds the candidates of the passes after (exact_passes)
    codes: Any = None
    colour: Any = None
    view_matchers: list | None = None  # an exemplar per view: each view's matcher over its own sites...
    view_starts: list[int] | None = None  # ...which start there in centres and patches
    _projections: dict = field(default_factory=dict, init=False, repr=False)  # by weights: projection()

    @property
    def phases(self) -> bool:
        """Whether this level's exemplar holds nothing but the categorical exemplar's phases
        (its finest level; a coarser level's are blends)."""
        return self.categorical and is_categorical(self.values.size)

    @cached_property
    def block(self) -> DeviceBlock | None:
        """The block on an OpenCL matcher's device (:class:`~clsolid.search.block.DeviceBlock`), made
        at the first search; None for another matcher (the float64 reference), or where the
        queries are gathered on the host (an exemplar per view, colour labels)."""
        if not isinstance(self.matcher, CLMatcher) or self.view_matchers is not None or self.colour is not None:
            return None
        return DeviceBlock(self.matcher)

    def projection(self, weights: np.ndarray) -> Projection | None:
        """The seeding passes' principal components (``seed_components``) for *weights*, made
        once each; None where the search compares every term (another pass, no components,
        phase codes)."""
        if not (self.seeding and self.params.seed_components and self.codes is None):
            return None
        key = weights.tobytes()
        if key not in self._projections:
            self._projections[key] = Projection(self.matcher.table, weights, self.params.seed_components)
        return self._projections[key]

    @cached_property
    def centre_bins(self) -> np.ndarray:
        """``histogram.bin(centres)``: each site's centre's bin, found once a level, not once a set."""
        return self.histogram.bin(self.centres)

    def searched(self, vol: np.ndarray) -> np.ndarray:
        """The block as the matcher compares it: *vol*, or with ``codes`` its phases' codes."""
        return vol if self.codes is None else self.codes.encode(vol)

    def queries(self, view: int, voxels: np.ndarray, vol: np.ndarray, coarse: np.ndarray | None) -> np.ndarray:
        """The neighbourhoods of *voxels* of the block *vol* in the *view*-th constrained view,
        as the matcher compares them (the square's terms encoded with ``codes``)."""
        k = self.params.neighborhood
        q = voxel_features(vol, coarse, voxels, self.params.view_names[view], k)
        if self.colour is not None:
            return self.colour.encode_terms(q)
        return q if self.codes is None else self.codes.encode_terms(q, k * k)

    def blend(self, values: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
        """Per column of *values* ``(views, m)``, their (*weights*-weighted) mean; with colour
        labels, their weighted vote (:func:`vote`): a mean colour, even taken to the nearest
        palette colour, drifts toward the palette's middle (docs/design.md#colour-search)."""
        if self.colour is not None:
            return vote(values, np.ones(values.shape) if weights is None else weights)
        if weights is None:
            return values.mean(axis=0)
        return (weights * values).sum(axis=0) / weights.sum(axis=0)

    def best(self, view: int, voxels: np.ndarray, vol: np.ndarray, coarse: np.ndarray | None,
             weights: np.ndarray, queries: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The best match of *voxels* of the block *vol* (*coarse*: the parent level's) in the
        *view*-th constrained view: exhaustive (in a seeding pass on :meth:`projection`'s
        components, where it has some), or among k-coherence candidates
        (``search="coherence"``, :meth:`~clsolid.search.coherence.Coherence.search`).
        *queries*, their neighbourhoods (:meth:`queries`), are gathered here (on an OpenCL
        matcher's device: :attr:`block`) unless given. Returns ``(site (m,), distance (m,))``."""
        k = self.params.neighborhood
        if self.view_matchers is not None:  # the view's own exemplar, searched whole on gathered queries
            site, least = self.view_matchers[view].best(
                self.queries(view, voxels, vol, coarse) if queries is None else queries, weights)
            return site + self.view_starts[view], least
        if self.coherence is not None and not self.exhaustive:
            if self.colour is not None:  # colours: the queries gathered and encoded on the host
                return self.coherence.best(self.matcher, view, voxels,
                                           self.queries(view, voxels, vol, coarse) if queries is None else queries,
                                           weights)
            return self.coherence.search(self.matcher, view, voxels, self.searched(vol), coarse, k, weights, queries,
                                         self.block)
        projection = self.projection(weights)
        if projection is not None:
            if self.block is not None:
                site, least = self.block.best_projected(self.params.view_names[view], voxels, self.searched(vol),
                                                        coarse, k, projection)
            else:
                site, least = projection.best_reference(
                    self.queries(view, voxels, vol, coarse) if queries is None else queries)
        elif queries is None and self.block is not None:  # gathered on the device
            site, least = self.block.best(self.params.view_names[view], voxels, self.searched(vol), coarse, k,
                                          weights)
        else:
            if queries is None:
                queries = self.queries(view, voxels, vol, coarse)
            site, least = self.matcher.best(queries, weights)
        if self.coherence is not None:  # an exact pass seeds the candidates of the passes after
            self.coherence.record(view, voxels, site)
        return site, least
