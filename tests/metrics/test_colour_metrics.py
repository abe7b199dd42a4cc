"""Colour distances: the joint colour histogram and each channel's, on a readable scale."""

import numpy as np
import pytest

from clsolid.errors import InputError
from clsolid.metrics import evaluate
from clsolid.metrics.colour import KEY, ColourBins


@pytest.fixture(scope="module")
def exemplar():
    from skimage import data

    return np.ascontiguousarray(data.astronaut()[288:336, 96:144])  # the suit's red and white stripes


def _tiled(image, shape):
    """A volume whose every front slice is a periodic crop of *image* (its own colours)."""
    z, y, x = shape
    return np.stack([np.roll(image, (3 * k, 5 * k), axis=(0, 1))[:y, :x] for k in range(z)])


def test_the_exemplars_own_colours_score_as_well_as_its_halves_and_others_do_not(exemplar):
    own = _tiled(exemplar, (12, 40, 40))
    swapped = own[..., ::-1]  # blue for red: the same structure, other colours
    reports = [evaluate(exemplar, v, views=("front",), max_slices=6, reference_repeats=4) for v in (own, swapped)]
    good, bad = (r["views"]["front"]["distances"][KEY] for r in reports)
    assert good["informative"] and good["score"] < 0.1
    assert bad["score"] > 0.3
    # structure on luminance: every grey distance is there, beside the colour one
    assert {"histogram_kl", "autocorrelation_l2", "patch_sw", KEY} <= set(reports[0]["views"]["front"]["distances"])
    assert reports[0]["views"]["front"]["distances"]["autocorrelation_l2"]["score"] < 0.3
    channels = [r["views"]["front"]["colour_channels"] for r in reports]
    assert channels[0]["G"] < channels[1]["R"]
    assert any(row["metric"] == KEY for row in reports[0]["summary"])
    assert reports[0]["volume"]["shape"] == [12, 40, 40, 3]


def test_every_pixel_counts_as_its_nearest_palette_colour(exemplar):
    bins = ColourBins(exemplar, 8)
    assert len(bins.values) == 8
    np.testing.assert_array_equal(bins.index(bins.values[None]), np.arange(8)[None])


def test_colour_goes_with_colour(exemplar):
    with pytest.raises(InputError, match="RGB exemplar goes with an RGB volume"):
        evaluate(exemplar, np.zeros((8, 16, 16)))
    with pytest.raises(InputError, match="RGB exemplar goes with an RGB volume"):
        evaluate(exemplar[..., 0], np.zeros((8, 16, 16, 3), np.uint8))
