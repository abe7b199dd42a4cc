"""Synthesis outputs judged by statistics against the exemplar, not by "it ran"."""

import numpy as np
import pytest

import clsolid
from clsolid import metrics

# 64^3 runs judged by statistics (and one at 32^3): slow-only.
pytestmark = pytest.mark.slow


def _scores(exemplar, volume, seed=0):
    rng = np.random.default_rng(seed)
    shuffled = rng.choice(exemplar.ravel(), volume.size).reshape(volume.shape)
    noise = rng.integers(exemplar.min(), exemplar.max() + 1, volume.shape)
    hist = dict(bins=int(exemplar.max()) + 1, value_range=(0, int(exemplar.max()) + 1))
    out = {}
    for view in ("front", "right"):
        sl = metrics.view_slices(volume, view)
        out[view] = (metrics.autocorrelation_distance(exemplar, sl),
                     metrics.histogram_distance(exemplar, sl, **hist))
    out["shuffled_acd"] = metrics.autocorrelation_distance(exemplar, metrics.view_slices(shuffled, "front"))
    out["noise_hist"] = metrics.histogram_distance(exemplar, metrics.view_slices(noise, "front"), **hist)
    return out


def test_default_settings_beat_no_structure(device, brick_labels):
    """32^3, 2 scales, defaults otherwise: slices closer to brick than structureless volumes."""
    vol = clsolid.synthesize("brick", (32, 32, 32), scales=2, rng=3, device=device, output="labels")
    s = _scores(brick_labels, vol)
    for view in ("front", "right"):
        acd, hist = s[view]
        assert acd < 0.9 * s["shuffled_acd"], f"{view}: autocorrelation {acd:.3f} vs shuffled {s['shuffled_acd']:.3f}"
        assert hist < s["noise_hist"], f"{view}: histogram KL {hist:.3f} vs noise {s['noise_hist']:.3f}"


@pytest.fixture(scope="module")
def scores_of(tool):
    """Calibrated scores {(view, metric): score}, computed as tools/quality_ml.py computes
    them: 0 = as close as two halves of the exemplar, 1 = no structure (shuffled pixels;
    uniform noise for the histogram)."""
    return tool("quality_ml").scores


# The thesis's case: brick 64x64 -> 64^3, 9x9, 3 scales, 1/8, re-synthesis, ICM, h2-product,
# xi=-3, 95 %, 32 levels, 2 views. "Far closer than no structure" is read as a calibrated
# score below 0.3 on both constrained views, for every seed here.
SEEDS = (1, 2, 3)
#: The thesis's relaxation: ICM, no balance, the same 4 +in slices in both views.
ICM = dict(views=2, relaxation="icm", balance=0.0, slice_layout="aligned", insert_slices=4, neighborhood=9)


@pytest.fixture(scope="module")
def default_scores(device, brick_labels, scores_of):
    """The thesis case (ICM) with clsolid's pyramid and bandwidth (binomial, 0.2 x Silverman), once per seed."""
    return {seed: scores_of(brick_labels, clsolid.synthesize("brick", (64, 64, 64), rng=seed, device=device,
                                                             output="labels", **ICM))
            for seed in SEEDS}


@pytest.fixture(scope="module")
def gibbs_scores(device, brick_labels, scores_of):
    """The same brick case with the defaults (Gibbs, balance, staggered +in) and the two views a
    brick wall calls for (docs/design.md#three-views), once per seed."""
    return {seed: scores_of(brick_labels, clsolid.synthesize("brick", (64, 64, 64), rng=seed, device=device,
                                                             output="labels", views=2))
            for seed in SEEDS}


def _assert_every_seed_below(scores: dict, metric: str, limit: float) -> None:
    bad = {(seed, view): round(s[view, metric], 2) for seed, s in scores.items()
           for view in ("front", "right") if not s[view, metric] < limit}
    assert not bad, f"{metric} score >= {limit} for (seed, view): {bad}"


def test_defaults_keep_brick_histogram(gibbs_scores):
    _assert_every_seed_below(gibbs_scores, "histogram_kl", 0.1)


def test_defaults_keep_brick_autocorrelation(gibbs_scores):
    """With 9x9 windows the dense +in slices cut the bricks; 11x11 carries them (docs/design.md#window-size)."""
    _assert_every_seed_below(gibbs_scores, "autocorrelation_l2", 0.3)


@pytest.mark.parametrize("metric", ["histogram_kl", "autocorrelation_l2"])
def test_thesis_case_is_close_for_every_seed(default_scores, metric):
    _assert_every_seed_below(default_scores, metric, 0.3)


def test_thesis_decimation_is_close_on_its_worst_seed(device, brick_labels, scores_of):
    """The thesis's plain decimation (docs/design.md#pyramid) meets the criterion too, on its worst seed."""
    scores = {3: scores_of(brick_labels, clsolid.synthesize("brick", (64, 64, 64), rng=3, device=device,
                                                             output="labels", pyramid="decimate", **ICM))}
    for metric in ("autocorrelation_l2", "histogram_kl"):
        _assert_every_seed_below(scores, metric, 0.3)


@pytest.mark.xfail(strict=True, reason="with the thesis's Silverman bandwidth the ICM is mode-seeking on brick: two dark "
                   "levels merge (the histogram fails; the autocorrelation is fine; docs/design.md#bandwidth)")
def test_thesis_bandwidth_keeps_the_grey_levels(device, brick_labels, scores_of):
    scores = {1: scores_of(brick_labels, clsolid.synthesize("brick", (64, 64, 64), rng=1, device=device,
                                                             output="labels", bandwidth_factor=1.0, **ICM))}
    _assert_every_seed_below(scores, "histogram_kl", 0.3)
