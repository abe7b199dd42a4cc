"""The generated 3D ground truths: determinism, phase fractions, correlation lengths along
each axis, round separate particles under a thin binder, the registry and the sections."""

import numpy as np
import pytest
from scipy import ndimage
from skimage.measure import label, regionprops

from clsolid.errors import InputError
from clsolid.groundtruth import (anisotropic_field, ground_truth, ground_truth_info, ground_truth_names,
                                 isotropic_field, particulate_composite, sections)
from clsolid.metrics import correlation_lengths

#: Small particles for a small cube: the same generator as at 256, a few seconds faster.
SMALL_PARTICLES = dict(diameters=(10.0, 16.0), particle_fraction=0.3)

MAKERS = {
    "isotropic": lambda seed: isotropic_field(24, seed=seed, correlation_length=3.0, fractions=(0.3, 0.7)),
    "anisotropic": lambda seed: anisotropic_field((16, 24, 32), seed=seed, correlation_lengths=(2, 3, 4)),
    "particulate": lambda seed: particulate_composite(48, seed=seed, **SMALL_PARTICLES),
}


@pytest.mark.parametrize("kind", MAKERS)
def test_the_same_seed_gives_the_same_bits(kind):
    a, b, other = MAKERS[kind](5), MAKERS[kind](5), MAKERS[kind](6)
    assert a.dtype == np.uint8 and a.flags.c_contiguous
    np.testing.assert_array_equal(a, b)
    assert (a != other).mean() > 0.1


@pytest.mark.parametrize("fractions", [(0.5, 0.5), (0.2, 0.8), (0.4, 0.35, 0.25)])
def test_phase_fractions_are_the_ones_asked(fractions):
    for volume in (isotropic_field(32, seed=1, correlation_length=4.0, fractions=fractions),
                   anisotropic_field((20, 32, 40), seed=1, correlation_lengths=(2, 4, 8), fractions=fractions)):
        got = np.bincount(volume.ravel(), minlength=len(fractions)) / volume.size
        assert volume.max() == len(fractions) - 1
        np.testing.assert_allclose(got, fractions, atol=1e-4)  # whole voxels, no ties in a float field


@pytest.mark.parametrize("fractions", [(0.5, 0.5), (0.4, 0.35, 0.25)])
def test_the_isotropic_field_has_the_asked_length_along_every_axis(fractions):
    volume = isotropic_field(64, seed=2, correlation_length=5.0, fractions=fractions)
    lengths = correlation_lengths(volume, phases=np.arange(len(fractions)))
    # One 64^3 draw scatters by about 7 % along an axis, less in the mean of the three.
    np.testing.assert_allclose(lengths, 5.0, rtol=0.15)
    assert np.mean(lengths) == pytest.approx(5.0, rel=0.1) and max(lengths) / min(lengths) < 1.25


@pytest.mark.parametrize("fractions", [(0.5, 0.5), (0.4, 0.35, 0.25)])
def test_the_anisotropic_field_has_the_three_asked_lengths(fractions):
    asked = (3.0, 6.0, 12.0)
    volume = anisotropic_field(64, seed=3, correlation_lengths=asked, fractions=fractions)
    lengths = correlation_lengths(volume, phases=np.arange(len(fractions)))
    assert lengths[0] < lengths[1] < lengths[2]
    # One 64^3 draw scatters by about 7 % along an axis.
    np.testing.assert_allclose(lengths, asked, rtol=0.2)


@pytest.fixture(scope="module")
def composite():
    return particulate_composite(64, seed=4, **SMALL_PARTICLES)


def test_the_composite_has_matrix_particles_and_binder(composite):
    fractions = np.bincount(composite.ravel(), minlength=3) / composite.size
    assert composite.max() == 2
    assert 0.2 < fractions[1] <= 0.32  # up to the fraction asked, less where spheres found no place
    assert 0.03 < fractions[2] < 0.25 and fractions[0] > 0.4


def test_particles_are_round_separate_and_within_the_diameters(composite):
    lab = label(composite == 1, connectivity=3)  # diagonal neighbours joined: touching particles would merge
    side = composite.shape[0]
    inside = [r for r in regionprops(lab)
              if min(r.bbox[:3]) > 0 and max(r.bbox[3:]) < side]  # not cut by a face of the periodic cube
    assert len(inside) >= 5
    for r in inside:
        assert 10.0 - 1.0 <= r.equivalent_diameter_area <= 16.0 + 1.0
        assert r.axis_major_length / r.axis_minor_length < 1.2
        assert r.solidity > 0.85  # a digital sphere 10 voxels across is about 0.9


def test_the_binder_is_thin_and_on_the_particles(composite):
    binder = composite == 2
    pad = 16  # the cube is periodic: a particle across a face is as near as one inside
    to_particle = ndimage.distance_transform_edt(np.pad(composite != 1, pad, mode="wrap"))[pad:-pad, pad:-pad, pad:-pad]
    # a shell voxel is within 1 of a surface, a neck voxel within half the widest neck (5)
    assert to_particle[binder].max() <= 2.5 + 1.0
    assert np.median(to_particle[binder]) <= 1.5
    # two erosions take away anything up to 4 voxels thick: almost all of the binder
    assert ndimage.binary_erosion(binder, iterations=2).sum() < 0.02 * binder.sum()
    coated = ndimage.binary_dilation(binder) & (composite == 1)
    lab = label(composite == 1, connectivity=3)
    assert set(np.unique(lab[coated])) == set(range(1, lab.max() + 1))  # every particle coated


def test_necks_bridge_narrow_gaps_only():
    without = particulate_composite(48, seed=7, **SMALL_PARTICLES, neck=0.0)
    shells = particulate_composite(48, seed=7, **SMALL_PARTICLES, neck=1.0)  # no neck reaches past a shell
    with_necks = particulate_composite(48, seed=7, **SMALL_PARTICLES)
    np.testing.assert_array_equal(without, shells)
    np.testing.assert_array_equal(without == 1, with_necks == 1)  # the particles do not move
    assert (with_necks == 2).sum() > (without == 2).sum()


def test_the_registry_makes_each_ground_truth():
    names = ground_truth_names()
    assert names == ("iso2", "iso3", "aniso2", "aniso3", "particles")
    for name in names[:4]:
        info = ground_truth_info(name)
        volume = ground_truth(name, info.min_side, seed=1)
        assert volume.shape == (info.min_side,) * 3 and volume.max() == len(info.phases) - 1
        np.testing.assert_array_equal(volume, ground_truth(name, info.min_side, seed=1))
    assert ground_truth_info("particles").phases == ("matrix", "particle", "binder")


def test_sections_are_the_central_views():
    z, y, x = np.meshgrid(np.arange(6), np.arange(8), np.arange(10), indexing="ij")
    volume = x + 10 * y + 100 * z
    s = sections(volume)
    np.testing.assert_array_equal(s["front"], volume[3])
    np.testing.assert_array_equal(s["right"], volume[:, :, 5].T)
    np.testing.assert_array_equal(s["top"], volume[:, 4, :])
    assert s["right"].shape == (8, 6) and s["top"].shape == (6, 10)


@pytest.mark.parametrize("call, param", [
    (lambda: isotropic_field(4, seed=0), "shape"),
    (lambda: isotropic_field((8, 8), seed=0), "shape"),
    (lambda: isotropic_field((2**22, 2**22, 2**22), seed=0), "shape"),  # 2^66 voxels, 0 in int64
    (lambda: isotropic_field(16, seed=-1), "seed"),
    (lambda: isotropic_field(16, seed=0, fractions=(0.5, 0.6)), "fractions"),
    (lambda: isotropic_field(16, seed=0, fractions=(1.0,)), "fractions"),
    (lambda: isotropic_field(16, seed=0, correlation_length=9.0), "correlation_length"),
    (lambda: isotropic_field(16, seed=0, correlation_length=0.5), "correlation_length"),
    (lambda: anisotropic_field(16, seed=0, correlation_lengths=(2, 3)), "correlation_lengths"),
    (lambda: anisotropic_field((8, 32, 32), seed=0, correlation_lengths=(5, 3, 3)), r"correlation_lengths\[0\]"),
    (lambda: particulate_composite(48, seed=0, diameters=(16, 10)), "diameters"),
    (lambda: particulate_composite(32, seed=0, **SMALL_PARTICLES), "side"),
    (lambda: particulate_composite(48, seed=0, particle_fraction=0.6, diameters=(10, 16)), "particle_fraction"),
    (lambda: particulate_composite(48, seed=0, binder=-1.0, diameters=(10, 16)), "binder"),
    (lambda: ground_truth("foam", 64), "foam"),
    (lambda: ground_truth("particles", 64), "side"),
    (lambda: sections(np.zeros((4, 4))), "volume"),
])
def test_bad_input_names_the_parameter(call, param):
    with pytest.raises(InputError, match=param):
        call()


@pytest.mark.slow
def test_the_particles_at_256_are_20_to_40_voxels_across():
    volume = ground_truth("particles", 256, seed=0)
    fractions = np.bincount(volume.ravel(), minlength=3) / volume.size
    assert 0.3 < fractions[1] <= 0.36 and 0.03 < fractions[2] < 0.15
    lab = label(volume == 1, connectivity=3)
    inside = [r for r in regionprops(lab) if min(r.bbox[:3]) > 0 and max(r.bbox[3:]) < 256]
    diameters = np.array([r.equivalent_diameter_area for r in inside])
    assert len(inside) > 100 and diameters.min() >= 19.0 and diameters.max() <= 41.0
    for view, section in sections(volume).items():
        assert section.shape == (256, 256), view
