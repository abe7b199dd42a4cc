"""An exemplar per view for the search methods: each view searches its own exemplar, the
OpenCL matcher agrees with the float64 reference, and what cannot take one says so."""

import numpy as np
import pytest

import clsolid
from clsolid.errors import InputError


def _stripes(shape, period, axis):
    """Binary stripes across *axis* of a 2D image (0 and 1), *period* pixels."""
    return ((np.indices(shape)[axis] // (period // 2)) % 2).astype(np.uint8)


FRONT, RIGHT = _stripes((36, 36), 8, 1), _stripes((36, 36), 12, 1)  # across x every 8, across z every 12


def _changes(vol: np.ndarray, axis: int) -> float:
    """Value changes per voxel along *axis* (binary stripes with period P: 2 / P)."""
    return float(np.mean(vol != np.roll(vol, 1, axis)))


@pytest.mark.each_device
def test_kopf_follows_each_views_exemplar(device):
    """Sheets across x every 8 voxels crossed with sheets across z every 12: the front view (y, x)
    shows the first, the right view (y, z) the second. One exemplar could not tell x from z."""
    res = clsolid.synthesize({"front": FRONT, "right": RIGHT}, (24, 24, 24), method="kopf", rng=1, device=device,
                             scales=2, neighborhood=9, full_output=True)
    assert res.params["search"] == "exact" and res.params["views"] == 2
    vol = res.volume
    assert set(np.unique(vol)) <= {0, 1}
    assert _changes(vol, 1) < 0.08
    assert 0.2 < _changes(vol, 2) < 0.32       # the front's period 8: 0.25
    assert 0.12 < _changes(vol, 0) < 0.22      # the right's period 12: 0.167


@pytest.mark.slow
@pytest.mark.parametrize("method", ["kopf", "wl"])
def test_per_view_search_matches_the_reference(method):
    kw = dict(method=method, rng=2, scales=1, neighborhood=5, iterations=2)
    images = {"front": FRONT[:16, :16], "top": RIGHT[:14, :18]}
    got = clsolid.synthesize(images, (8, 10, 12), **kw)
    want = clsolid.synthesize(images, (8, 10, 12), device="reference", **kw)
    np.testing.assert_allclose(got, want)


def test_what_takes_one_exemplar_says_so():
    images = {"front": FRONT, "right": RIGHT}
    with pytest.raises(InputError, match="chen-wang keeps its histograms"):
        clsolid.synthesize(images, (8, 8, 8), method="chen-wang", device="reference")
    with pytest.raises(InputError, match="search='coherence' follows"):
        clsolid.synthesize(images, (8, 8, 8), method="kopf", search="coherence", device="reference")
    with pytest.raises(InputError, match="site_map"):
        clsolid.synthesize(images, (8, 8, 8), method="kopf", site_map=True, full_output=True, device="reference")
