"""A generated volume's 3D properties against a real volume's: bands, means, verdicts."""

import numpy as np
import pytest
from scipy import ndimage

from clsolid.errors import InputError
from clsolid.metrics.truth import (
    TARGETS,
    compare_properties,
    mean_properties,
    property_band,
    solid_properties,
    subvolume_corners,
)


def _field(shape=(24, 24, 24), seed=0, sigma=2.0):
    f = ndimage.gaussian_filter(np.random.default_rng(seed).standard_normal(shape), sigma)
    return (f > np.median(f)).astype(np.uint8)


def test_a_slab_has_the_properties_worked_by_hand():
    vol = np.zeros((8, 6, 5), np.uint8)
    vol[4:] = 1
    props = solid_properties(vol)
    for key in ("0", "1"):
        p = props[key]
        assert p["fraction"] == 0.5
        assert p["surface_area"] == pytest.approx(6 * 5 / vol.size)  # one interface plane
        assert p["connected"] == [0.0, 1.0, 1.0]  # the slab spans y and x, not z
        assert p["tortuosity"][0] == np.inf and p["tortuosity"][1:] == pytest.approx([1.0, 1.0])
        assert p["s2"][1] == pytest.approx(np.full(3, 0.5))  # lags 0 to half the shortest side


def test_tortuosity_is_solved_for_the_phases_asked_or_those_over_a_quarter():
    vol = np.zeros((10, 10, 10), np.uint8)
    vol[:2] = 1  # 20 % of the block
    assert solid_properties(vol)["1"]["tortuosity"] is None
    assert solid_properties(vol)["0"]["tortuosity"] is not None
    asked = solid_properties(vol, tortuosity=[1])
    assert asked["0"]["tortuosity"] is None and asked["1"]["tortuosity"] == pytest.approx([np.inf, 1, 1])
    assert all(p["tortuosity"] is None for p in solid_properties(vol, tortuosity=False).values())


@pytest.mark.parametrize("shape, size, count", [((64, 64, 64), (32, 32, 32), 8), ((50, 33, 20), (16, 16, 20), 6),
                                                ((12, 12, 12), (12, 12, 12), 1)])
def test_sub_volumes_tile_the_block_without_overlap(shape, size, count):
    corners = subvolume_corners(shape, size)
    assert len(corners) == count
    cover = np.zeros(shape, np.int32)
    for z, y, x in corners:
        cover[z:z + size[0], y:y + size[1], x:x + size[2]] += 1
    assert cover.max() == 1 and cover.sum() == count * np.prod(size)


def test_a_sub_volume_larger_than_the_block_is_refused():
    with pytest.raises(InputError, match="does not fit"):
        subvolume_corners((16, 16, 16), (8, 8, 32))


def test_the_band_is_the_spread_over_the_sub_volumes():
    vol = _field()
    band, count = property_band(vol, (12, 12, 12), tortuosity=False)
    assert count == 8
    parts = [solid_properties(vol[z:z + 12, y:y + 12, x:x + 12], phases=[0, 1], tortuosity=False)
             for z, y, x in subvolume_corners(vol.shape, (12, 12, 12))]
    fractions = [p["1"]["fraction"] for p in parts]
    assert band["1"]["fraction"] == [min(fractions), max(fractions)]
    low, high = band["0"]["s2"][2]
    assert np.all(low <= parts[0]["0"]["s2"][2]) and np.all(parts[0]["0"]["s2"][2] <= high)
    assert band["0"]["tortuosity"] is None


def test_the_mean_averages_each_property_curve_by_curve():
    a, b = solid_properties(_field(seed=1), tortuosity=False), solid_properties(_field(seed=2), tortuosity=False)
    mean = mean_properties([a, b])
    assert mean["1"]["fraction"] == pytest.approx((a["1"]["fraction"] + b["1"]["fraction"]) / 2)
    np.testing.assert_allclose(mean["0"]["s2"][1], (a["0"]["s2"][1] + b["0"]["s2"][1]) / 2)
    with pytest.raises(InputError):
        mean_properties([])


def test_a_volume_meets_every_target_against_itself():
    vol = _field()
    real = solid_properties(vol, max_lag=6)
    band, _ = property_band(vol, (12, 12, 12), max_lag=6, tortuosity=[0, 1])
    compared = compare_properties(real, band, mean_properties([real]))
    for rows in compared.values():
        assert rows["fraction"]["error"] == 0 and rows["fraction"]["met"]
        assert rows["surface_area"]["met"] and rows["s2"]["error"] == [0, 0, 0] and all(rows["s2"]["met"])
        assert all(rows["tortuosity"]["met"])


def test_speckle_misses_the_surface_area_and_a_shifted_fraction_misses_its_own():
    vol = _field()
    real = solid_properties(vol, max_lag=6, tortuosity=False)
    band, _ = property_band(vol, (12, 12, 12), max_lag=6, tortuosity=False)
    noisy = vol.copy()
    flip = np.random.default_rng(3).random(vol.shape) < 0.03
    noisy[flip & (vol == 0)] = 1  # 1.5 points of phase 0 become isolated voxels of phase 1
    compared = compare_properties(real, band, mean_properties([solid_properties(noisy, max_lag=6,
                                                                                tortuosity=False)]))
    assert compared["1"]["fraction"]["error"] > TARGETS["fraction"] and not compared["1"]["fraction"]["met"]
    assert compared["1"]["surface_area"]["error"] > TARGETS["surface_area"]
    assert not compared["1"]["surface_area"]["met"]
