"""Traces of inserted slices (clsolid.metrics.traces): the slices at and beside the inserted
depths against the spread of the others."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi

from clsolid.errors import InputError
from clsolid.metrics import slice_profile, slice_traces
from clsolid.metrics.traces import depth_distance

DEPTHS = np.arange(0, 48, 6)  # every 6th slice, as +in slices are laid out


def _phases(seed: int, side: int = 48) -> np.ndarray:
    """A smooth two-phase field, about half of each, the same in every direction."""
    field = ndi.gaussian_filter(np.random.default_rng(seed).standard_normal((side,) * 3), 2.0, mode="wrap")
    return (field > 0).astype(np.uint8)


def _grey(seed: int, side: int = 48) -> np.ndarray:
    field = ndi.gaussian_filter(np.random.default_rng(seed).standard_normal((side,) * 3), 2.0, mode="wrap")
    return 100.0 + 10.0 * field / field.std()


def test_depth_distance_wraps_around():
    np.testing.assert_array_equal(depth_distance(10, [0]), [0, 1, 2, 3, 4, 5, 4, 3, 2, 1])
    np.testing.assert_array_equal(depth_distance(8, [2, 5]), [2, 1, 0, 1, 1, 0, 1, 2])


@pytest.mark.parametrize("make", [_phases, _grey])
def test_a_volume_without_inserted_slices_shows_no_trace(make):
    vol = make(1)
    report = slice_traces(vol, {"front": DEPTHS, "right": DEPTHS + 3, "top": DEPTHS + 1})
    assert report["within"], report["outside"]
    assert set(report["views"]) == {"front", "right", "top"}


def test_planted_slices_with_other_fractions_show_in_their_view_only():
    vol = _phases(2)
    vol[DEPTHS] = (np.random.default_rng(0).random((DEPTHS.size, 48, 48)) < 0.2).astype(np.uint8)
    report = slice_traces(vol, {"front": DEPTHS, "right": DEPTHS}, exemplar=_phases(3)[0])
    assert "front fraction 0" in report["outside"] and "front fraction 1" in report["outside"]
    assert "front isolated" in report["outside"]  # random pixels: speckled planes
    assert "front step" in report["outside"]  # and each is unlike its neighbours
    assert not any(name.startswith("right") for name in report["outside"])
    effect = report["views"]["front"]["fraction 1"]["effect"]
    assert effect[0] < -1.0 and abs(effect[1]) <= 1.0  # the slices themselves, not their neighbours


def test_a_seam_beside_each_inserted_slice_shows_as_a_step():
    """Each inserted slice copied from another block: the same statistics, but a jump to its
    neighbours, which the other views show as straight lines."""
    vol, other = _grey(4), _grey(5)
    vol[:, :, DEPTHS] = other[:, :, DEPTHS]
    report = slice_traces(vol, {"right": DEPTHS})
    assert report["outside"] == ["right step"] or set(report["outside"]) == {"right step", "right isolated"}
    assert report["views"]["right"]["step"]["effect"][0] > 1.0


def test_the_profile_names_each_phase_and_the_patch_distance_with_an_exemplar():
    vol = _phases(6, 24)
    profile = slice_profile(vol, "top", exemplar=vol[0])
    assert set(profile) == {"fraction 0", "fraction 1", "isolated", "step", "patch"}
    assert all(series.shape == (24,) for series in profile.values())
    np.testing.assert_allclose(profile["fraction 0"] + profile["fraction 1"], 1.0)
    grey = slice_profile(_grey(6, 24), "front")
    assert set(grey) == {"mean", "std", "isolated", "step"}


def test_patch_distance_finds_slices_unlike_the_exemplar():
    """Inserted planes with features four times as coarse: the same fractions, other patches."""
    vol = _phases(7)
    coarse = ndi.gaussian_filter(np.random.default_rng(8).standard_normal((DEPTHS.size, 48, 48)), (0, 8, 8), mode="wrap")
    vol[DEPTHS] = coarse > 0
    report = slice_traces(vol, {"front": DEPTHS}, exemplar=_phases(9)[0])
    assert "front patch" in report["outside"]
    assert report["views"]["front"]["patch"]["effect"][0] > 1.0


def test_bad_input_is_refused():
    vol = _phases(9, 12)
    with pytest.raises(InputError, match="reach"):
        slice_traces(vol, {"front": [0]}, reach=-1)
    with pytest.raises(InputError, match="nothing to compare"):
        slice_traces(vol, {"front": np.arange(0, 12, 2)})
    with pytest.raises(InputError, match="map view names"):
        slice_traces(vol, [0, 4])
    with pytest.raises(InputError):
        slice_traces(vol, {"side": [0]})
    with pytest.raises(InputError, match="none of the exemplar's values"):
        slice_traces(vol, {"front": [0]}, exemplar=np.full((12, 12), 7, np.uint8) + np.eye(12, dtype=np.uint8))
    assert slice_traces(vol, {"front": []})["within"]  # no inserted slices: nothing to find


def test_patch_distance_by_slice_is_each_slices_patch_distance():
    from clsolid.metrics import patch_distance
    from clsolid.metrics.patches import patch_distance_by_slice

    rng = np.random.default_rng(3)
    exemplar, stack = rng.random((40, 40)), rng.random((3, 24, 24))  # small: no patch is subsampled
    got = patch_distance_by_slice(exemplar, stack, scales=(1, 2))
    np.testing.assert_allclose(got, [patch_distance(exemplar, s, scales=(1, 2)) for s in stack], rtol=1e-12)
    assert np.isnan(patch_distance_by_slice(exemplar, rng.random((2, 4, 4)))).all()  # no scale fits 4 x 4
