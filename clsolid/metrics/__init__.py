"""Metrics comparing a solid texture's slices with its 2D exemplar, view by view.

Views of a (Z, Y, X) volume: ``front`` = the (y, x) planes ``volume[z]``; ``right`` = the
(z, y) planes ``volume[:, :, x].T`` (rows = y, columns = z); ``top`` = the (z, x) planes
``volume[:, y, :]`` (rows = z, columns = x). :func:`evaluate` computes every metric per view,
each distance with a floor (two halves of the exemplar) and a ceiling (shuffled pixels or
noise), and says where a distance cannot tell these apart. :func:`mirror_correlation` and
:func:`max_copy_fraction` catch what slice statistics miss: a volume mirrored across the
views' shared axis, and slices copied from the exemplar; :func:`stretch`, features drawn out
along that axis. Properties that only a whole segmented volume has (surface area, S2 along
each axis, the share of a phase that spans the block, its tortuosity factor) are in
:mod:`clsolid.metrics.solid`; speckle, voxels unlike all their neighbours, in
:mod:`clsolid.metrics.speckle`; whether the inserted slices left a trace, in
:mod:`clsolid.metrics.traces`. The building blocks are public
so that tests and the engine can use them directly.
"""

from ._common import VIEWS, symmetric_kl, view_slices, wasserstein_1d
from .autocorr import autocorrelation, autocorrelation_distance
from .axes import correlation_length, correlation_lengths, lag_correlations, stretch
from .evaluate import evaluate
from .firstorder import first_order_stats, histogram_distance, quantise
from .fringes import Fringes, fringe_distances, trace_fringes
from .orientation import (OrientationField, dominant_orientation_deg, orientation_correlation_lengths,
                          orientation_distance, orientation_histogram, structure_tensor_orientation)
from .patches import patch_distance
from .solid import (connected_fraction, s2_error, specific_surface_area, tortuosity_factor,
                    two_point_correlation_axes)
from .speckle import (contrast_threshold, isolated_contrast_fraction, isolated_fraction,
                      isolated_fraction_by_slice)
from .phases import chord_lengths, lineal_path, two_point_cluster, two_point_correlation, volume_fractions
from .traces import slice_profile, slice_traces
from .symmetry import (CopyMatch, match_counts, max_copy_fraction, mirror_chance, mirror_correlation,
                       mirror_correlations)

__all__ = [
    "VIEWS", "evaluate", "view_slices", "first_order_stats", "quantise", "histogram_distance",
    "symmetric_kl", "wasserstein_1d", "autocorrelation", "autocorrelation_distance",
    "structure_tensor_orientation", "OrientationField", "orientation_histogram",
    "dominant_orientation_deg", "orientation_distance", "orientation_correlation_lengths", "trace_fringes", "Fringes",
    "fringe_distances", "patch_distance", "volume_fractions", "two_point_correlation", "two_point_cluster",
    "lineal_path", "chord_lengths", "mirror_correlation", "mirror_correlations", "mirror_chance", "max_copy_fraction",
    "CopyMatch", "match_counts", "lag_correlations", "correlation_length", "correlation_lengths", "stretch",
    "specific_surface_area", "two_point_correlation_axes", "s2_error", "connected_fraction", "tortuosity_factor",
    "isolated_fraction", "isolated_contrast_fraction", "isolated_fraction_by_slice", "contrast_threshold",
    "slice_profile", "slice_traces",
]
