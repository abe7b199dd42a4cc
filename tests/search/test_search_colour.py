"""Colour exemplars in the search methods (clsolid.search.palette): squares compared in CIELAB,
the colour pyramid, every method's run on the device against the float64 reference, and what
``synthesize`` gives and refuses."""

from functools import partial

import numpy as np
import pytest
from conftest import slow_except

import clsolid
from clsolid.errors import InputError
from clsolid.exemplar import level_map
from clsolid.gallery import gallery_exemplar
from clsolid.search.driver import run_search
from clsolid.search.match import CLMatcher, ReferenceMatcher
from clsolid.search.palette import Palette, colour_pyramid
from clsolid.search.params import SearchParams
from clsolid.search.pyramid import gaussian_pyramid


@pytest.fixture(scope="module")
def coffee():
    """A 24x24 crop of scikit-image's coffee, and its palette of 10 colours."""
    from skimage import data

    image = np.ascontiguousarray(data.coffee()[180:204, 300:324])
    return image, level_map(image, 10)


def test_encoded_rows_compare_colours_jointly():
    """The matcher's weighted squared distance between two encoded rows is the sum, over the
    terms, of the term's weight times the squared CIELAB distance of the two colours, with
    the parent terms' colours scaled as the grey table's parents are."""
    rng = np.random.default_rng(0)
    lab = rng.uniform(-50, 80, (6, 3))
    pal = Palette(lab, square=4, parent_scale=2.0)
    a, b = rng.integers(0, 6, (2, 7)).astype(np.float64)  # 4 square terms, 3 parent terms
    w = np.array([1.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    want = sum(w[j] * (4.0 if j >= 4 else 1.0) * np.sum((lab[int(a[j])] - lab[int(b[j])]) ** 2) for j in range(7))
    ea, eb = pal.encode_terms(a[None]), pal.encode_terms(b[None])
    assert ea.shape == (1, 21)
    assert np.sum(pal.weights(w) * (ea - eb) ** 2) == pytest.approx(want, rel=1e-12)
    assert pal.weights(w).tolist() == np.repeat(w, 3).tolist()


def test_span_is_the_palettes_diameter():
    assert Palette(np.array([[0.0, 0, 0], [3.0, 4.0, 0.0], [1.0, 1.0, 1.0]]), 1).span == pytest.approx(5.0)
    assert Palette(np.array([[50.0, 0, 0]]), 1).span == 1.0


def test_solve_takes_the_matched_colour_nearest_the_weighted_mean():
    lab = np.array([[0.0, 0, 0], [10.0, 0, 0], [4.0, 0, 0]])
    pal = Palette(lab, 1)
    labels = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]])
    weights = np.array([[1.0, 1.0], [1.0, 3.0], [0.1, 0.1]])
    # column 0: mean about 4.9, nearest proposal label 2 (4); column 1: mean about 7.4 -> label 1 (10)
    assert pal.solve(labels, weights).tolist() == [2, 1]


def test_the_colour_pyramid_keeps_palette_labels(coffee):
    _, levels = coffee
    pyr = colour_pyramid(levels.labels, levels.features, 3)
    assert np.array_equal(pyr[0], levels.labels)
    assert [p.shape for p in pyr] == [(24, 24), (12, 12), (6, 6)]
    lab = levels.features
    for level in (1, 2):  # each pixel the palette colour nearest the smoothed colour
        smooth = np.stack([gaussian_pyramid(lab[levels.labels][..., c], 3)[level] for c in range(3)], axis=-1)
        d = np.sum((smooth[:, :, None, :] - lab[None, None]) ** 2, axis=-1)
        assert np.array_equal(pyr[level], np.argmin(d, axis=-1))
    flat = colour_pyramid(np.full((8, 8), 3.0), lab, 3)
    assert all(np.all(p == 3) for p in flat)


@pytest.mark.parametrize("method, search", slow_except([("kopf", "coherence"), ("kopf", "exact"), ("wl", "exact"),
                                                         ("chen-wang", "exact")], 0))
def test_opencl_run_matches_the_reference_in_colour(device, coffee, method, search):
    _, levels = coffee
    params = SearchParams(method=method, neighborhood=5, scales=2, iterations=2, views=3, search=search)
    labels = levels.labels.astype(np.float64)
    ref = run_search(labels, (8, 10, 12), params, 3, ReferenceMatcher, palette=levels.features)[0]
    got = run_search(labels, (8, 10, 12), params, 3, partial(CLMatcher, device), palette=levels.features)[0]
    assert set(np.unique(got)) <= set(range(levels.n_labels))  # every voxel a palette label
    # float32 distances can swap two near-equal matches, and a vote or a copy follows them
    agree = np.mean(ref == got)
    assert agree >= 0.98, f"only {agree:.2%} of voxels agree with the float64 reference"


def test_synthesize_grows_colour_with_kopf(device):
    ex = gallery_exemplar("stained")
    res = clsolid.synthesize(ex, (24, 24, 24), method="kopf", channel_axis=-1, rng=2, device=device,
                             full_output=True)
    assert res.volume.shape == (24, 24, 24, 3) and res.volume.dtype == np.uint8
    assert np.array_equal(res.level_values[res.labels], res.volume)
    palette = {tuple(c) for c in res.level_values.tolist()}
    assert {tuple(c) for c in np.unique(res.volume.reshape(-1, 3), axis=0).tolist()} <= palette
    # the colours keep their shares: the labels' total variation distance to the exemplar's
    # (0.15 measured; a uniform draw from the palette: 0.26), and the mean colour (CIELAB,
    # 1.3-2.2 measured; the palette's mean: 9)
    n = res.level_values.shape[0]
    have = np.bincount(res.labels.ravel(), minlength=n) / res.labels.size
    want = np.bincount(res.exemplar_labels.ravel(), minlength=n) / res.exemplar_labels.size
    assert 0.5 * np.abs(have - want).sum() < 0.2
    lab = level_map(ex, 32).features
    assert np.linalg.norm(lab[res.labels].mean(axis=(0, 1, 2)) - lab[res.exemplar_labels].mean(axis=(0, 1))) < 4.0
    again = clsolid.synthesize(ex, (24, 24, 24), method="kopf", channel_axis=-1, rng=2, device=device)
    assert np.array_equal(again, res.volume)


@pytest.mark.slow
def test_an_exemplar_per_view_in_colour(device, coffee):
    image, _ = coffee
    from skimage import data

    other = np.ascontiguousarray(data.coffee()[100:124, 300:324])
    vol = clsolid.synthesize({"front": image, "right": other}, (12, 12, 12), method="kopf", channel_axis=-1,
                             iterations=2, scales=2, neighborhood=5, rng=1, device=device)
    assert vol.shape == (12, 12, 12, 3) and vol.dtype == np.uint8


@pytest.mark.parametrize("options, words", [
    ({"specify": True}, "specify"),
    ({"distance": "weighted"}, "CIELAB"),
    ({"rule": "overlap"}, "rule='centres'"),
])
def test_colour_refuses_what_compares_grey_levels(options, words):
    ex = gallery_exemplar("stained")
    with pytest.raises(InputError, match=words):
        clsolid.synthesize(ex, (8, 8, 8), method="kopf", channel_axis=-1, device="reference", **options)
