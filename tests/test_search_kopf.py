"""NP_K (clsolid.search.kopf): its weights, vote and histogram against hand computations,
the OpenCL run against the float64 reference, and a categorical exemplar kept in phases."""

import numpy as np
import pytest

import clsolid
from clsolid.gallery import gallery_exemplar
from clsolid.search.driver import run_search
from clsolid.search.kopf import vote
from clsolid.search.level import LevelHistogram
from clsolid.search.match import CLMatcher, ReferenceMatcher
from clsolid.search.params import SearchParams


def test_vote_takes_the_value_with_most_weight():
    values = np.array([[0.0, 1.0, 2.0, 5.0], [1.0, 1.0, 3.0, 5.0], [1.0, 0.0, 2.0, 6.0]])
    weights = np.array([[3.0, 1.0, 1.0, 1.0], [1.0, 1.0, 5.0, 1.0], [1.0, 5.0, 1.0, 1.0]])
    # column 0: 0 has 3, 1 has 2; column 1: 1 has 2, 0 has 5; column 2: 2 has 2, 3 has 5; column 3: 5 has 2
    assert vote(values, weights).tolist() == [0.0, 0.0, 3.0, 5.0]


def test_level_histogram_bins_and_follows_changes():
    finest = np.array([[0.0, 85.0], [170.0, 255.0]])
    vol = np.array([0.0, 0.0, 100.0, 250.0])
    h = LevelHistogram(finest, np.array([10.0, 80.0, 90.0, 240.0]), vol)
    assert h.exemplar.tolist() == [0.25, 0.5, 0.0, 0.25]  # nearest of 0, 85, 170, 255
    assert h.volume.tolist() == [0.5, 0.25, 0.0, 0.25]
    h.replace(np.array([0.0]), np.array([200.0]))
    assert h.volume.tolist() == [0.25, 0.25, 0.25, 0.25]


@pytest.mark.parametrize("name, views", [("composite3", 2), ("gravel", 3)])
def test_opencl_run_matches_the_reference(device, name, views):
    ex = gallery_exemplar(name, 64)[:32, :32].astype(np.float64)
    params = SearchParams(method="kopf", neighborhood=5, scales=2, iterations=2, views=views)
    ref = run_search(ex, (10, 12, 14), params, 3, ReferenceMatcher)[0]
    got = run_search(ex, (10, 12, 14), params, 3, lambda t: CLMatcher(device, t))[0]
    # weighted means: float32 distances move the weights in their last bits, so the values
    # agree to a thousandth of a grey level, not exactly
    agree = np.mean(np.isclose(ref, got, rtol=0, atol=1e-3))
    assert agree >= 0.99, f"only {agree:.2%} of voxels agree with the float64 reference"


def test_a_categorical_exemplar_stays_in_phases_and_a_grey_one_blends(device):
    vol = clsolid.synthesize(gallery_exemplar("composite3", 64), (16, 16, 16), method="kopf", iterations=2,
                             rng=1, device=device)
    assert set(np.unique(vol)) <= {0.0, 128.0, 255.0} and np.unique(vol).size == 3
    grey = clsolid.synthesize("gravel", (16, 16, 16), method="kopf", iterations=2, rng=1, device=device)
    assert np.unique(grey).size > 64  # weighted means of 32 levels


def test_kopf_keeps_the_minority_phase_better_than_wl(device):
    """porous80: the histogram re-weighting pulls the pore fraction toward the exemplar's."""
    ex = gallery_exemplar("porous80", 64)
    want = np.mean(ex == 0)
    err = {m: abs(np.mean(clsolid.synthesize(ex, (24, 24, 24), method=m, iterations=3, rng=1,
                                             device=device) < 128) - want) for m in ("wl", "kopf")}
    assert err["kopf"] < err["wl"], err
