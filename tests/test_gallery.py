"""The gallery of exemplars (clsolid.gallery) and the metrics that judge a method on it."""

from __future__ import annotations

import numpy as np
import pytest

from clsolid.errors import InputError
from clsolid.gallery import SIZES, gallery_draw, gallery_exemplar, gallery_info, gallery_names, gallery_photograph
from clsolid.metrics import (match_counts, max_copy_fraction, mirror_chance, mirror_correlation,
                             mirror_correlations)

NAMES = gallery_names()

#: Measured percentage of each phase at 64 (at 128 within 0.5 pp of it), by phase value.
MEASURED = {
    "porous50": {0: 50.0, 255: 50.0},
    "porous80": {0: 22.8, 255: 77.2},
    "inclusions": {0: 97.2, 255: 2.8},
    "composite3": {0: 64.1, 128: 28.5, 255: 7.4},
    "composite4": {0: 69.0, 85: 17.4, 170: 4.6, 255: 9.0},
    "fibres": {0: 53.4, 255: 46.6},
    "grains": {0: 18.5, 255: 81.5},
    "cracks": {0: 14.7, 255: 85.3},
    "channels": {0: 30.0, 255: 70.0},
    "lamellae": {0: 49.5, 255: 50.5},
}
#: The ranges asked of the gallery's materials: (name, phase value, lowest %, highest %).
REQUIRED = [("porous50", 0, 45, 55), ("porous80", 255, 75, 85), ("inclusions", 255, 0.5, 5)]


@pytest.fixture(scope="module")
def images():
    return {(n, s): gallery_exemplar(n, s) for n in NAMES for s in SIZES}


def test_the_gallery_covers_every_kind_of_exemplar():
    assert len(NAMES) >= 14 and len(set(NAMES)) == len(NAMES)
    assert {"brick", "grass", "gravel", "hrtem", "lamellae", "channels", "grains", "inclusions"} <= set(NAMES)
    kinds = {n: gallery_info(n).kind for n in NAMES}
    assert sum(k == "grey" for k in kinds.values()) >= 5  # 4 natural textures and the fringes
    assert {len(gallery_info(n).phases) for n in NAMES if kinds[n] == "categorical"} == {2, 3, 4}
    assert set(MEASURED) == {n for n in NAMES if kinds[n] == "categorical"}
    directional = {n for n in NAMES if gallery_info(n).views == 2}  # layered or oriented: the top view differs
    assert directional == {"fibres", "channels", "lamellae", "hrtem", "brick", "grass"}
    for n in NAMES:
        info = gallery_info(n)
        assert info.name == n and info.kind in ("categorical", "grey") and len(info.description) > 20
        assert "\n" not in info.description and info.views in (2, 3)
        k = len(info.phases)
        if info.kind == "grey":
            assert k == 0
        else:
            assert info.phase_values == tuple(round(255 * i / (k - 1)) for i in range(k))


@pytest.mark.parametrize("name", NAMES)
def test_exemplar_is_deterministic_and_well_formed(name, images):
    info = gallery_info(name)
    for size in SIZES:
        img = images[name, size]
        assert img.shape == (size, size) and img.dtype == np.uint8
        assert np.array_equal(img, gallery_exemplar(name, size))
        if info.kind == "categorical":
            assert tuple(np.unique(img)) == info.phase_values
        else:
            assert int(img.max()) - int(img.min()) > 100


@pytest.mark.parametrize("name", sorted(MEASURED))
def test_phase_fractions_are_the_measured_ones(name, images):
    for size in SIZES:
        img = images[name, size]
        got = {v: 100 * np.mean(img == v) for v in gallery_info(name).phase_values}
        assert got == pytest.approx(MEASURED[name], abs=0.5 if size == 64 else 0.8), size


@pytest.mark.parametrize("name, value, lo, hi", REQUIRED)
def test_phase_fractions_are_in_the_asked_ranges(name, value, lo, hi, images):
    for size in SIZES:
        assert lo < 100 * np.mean(images[name, size] == value) <= hi


def test_sizes_show_one_field_of_view(images):
    """128 samples the generated materials twice as finely; the photographs are area-averaged."""
    for name in NAMES:
        a, b = images[name, 64].astype(float), images[name, 128].astype(float)
        if gallery_info(name).seed is not None:
            assert np.mean(b[::2, ::2] == a) > 0.99, name
        else:
            assert np.corrcoef(b.reshape(64, 2, 64, 2).mean(axis=(1, 3)).ravel(), a.ravel())[0, 1] > 0.99, name


def test_bad_name_or_size_is_refused():
    with pytest.raises(InputError, match="not a gallery exemplar.*porous50"):
        gallery_exemplar("marble")
    with pytest.raises(InputError, match="size"):
        gallery_exemplar("porous50", 32)
    with pytest.raises(InputError, match="size"):
        gallery_exemplar("porous50", 64.0)


# ----------------------------------------------------------------------------- mirror correlation


def _centred(vol, kept):
    other = tuple(a for a in range(3) if a != kept)
    return vol - vol.mean(axis=other, keepdims=True)


def test_mirror_correlation_is_pearson_after_plane_means():
    rng = np.random.default_rng(0)
    vol = rng.random((6, 6, 6)) + 0.5 * np.swapaxes(rng.random((6, 6, 6)), 0, 1)
    for (a, b) in [(0, 1), (0, 2), (1, 2)]:
        kept = 3 - a - b
        x = _centred(vol, kept)
        expected = np.corrcoef(x.ravel(), np.swapaxes(x, a, b).ravel())[0, 1]
        assert mirror_correlation(vol, (a, b)) == pytest.approx(expected, abs=1e-12)
        assert mirror_correlation(vol, (b, a)) == pytest.approx(expected, abs=1e-12)
    assert set(mirror_correlations(vol)) == {"zy", "zx", "yx"}
    assert mirror_correlations(vol, [(0, 2)]) == {"zx": mirror_correlation(vol)}


def test_mirror_correlation_hand_made_volumes():
    rng = np.random.default_rng(1)
    v = rng.random((48, 48, 48))
    assert mirror_correlation(v + np.swapaxes(v, 0, 2)) == pytest.approx(1.0, abs=1e-12)
    assert mirror_correlation(v - np.swapaxes(v, 0, 2)) == pytest.approx(-1.0, abs=1e-12)
    assert abs(mirror_correlation(v) - 1 / 48) < 0.02  # the plane z = x is its own mirror: about 1/N
    layers = np.broadcast_to(rng.random(48)[None, :, None] * 100, v.shape)
    assert abs(mirror_correlation(layers + v)) < 0.05  # layers along y rightly look symmetric: removed
    assert np.isnan(mirror_correlation(np.ascontiguousarray(layers)))


def test_mirror_correlation_refuses_bad_input():
    with pytest.raises(InputError, match="different lengths"):
        mirror_correlation(np.zeros((4, 5, 6)))
    with pytest.raises(InputError, match="axes"):
        mirror_correlation(np.zeros((4, 4, 4)), (1, 1))
    with pytest.raises(InputError, match="axes"):
        mirror_correlation(np.zeros((4, 4, 4)), (0, 3))
    with pytest.raises(InputError, match="3D"):
        mirror_correlation(np.zeros((4, 4)))


def _isotropic_field(seed: int, n: int, sigma: float) -> np.ndarray:
    """A periodic, isotropic Gaussian random field: white noise smoothed by a Gaussian."""
    k = np.fft.fftfreq(n)
    kz, ky, kx = np.meshgrid(k, k, k, indexing="ij")
    gain = np.exp(-2 * (np.pi * sigma) ** 2 * (kx**2 + ky**2 + kz**2))
    noise = np.random.default_rng(seed).standard_normal((n, n, n))
    return np.real(np.fft.ifftn(np.fft.fftn(noise) * gain))


def test_mirror_chance_predicts_isotropic_volumes():
    # The mean mirror correlation of 16 isotropic fields, against the level predicted from
    # one slice of each: they agree (standard error of the mean about 0.01 here), and
    # both are far above the 1/N of white noise, which a correlated material cannot reach.
    n = 32
    fields = [_isotropic_field(seed, n, 1.5) for seed in range(16)]
    measured = np.mean([mirror_correlation(f) for f in fields])
    predicted = np.mean([mirror_chance(f[0], n) for f in fields])
    assert predicted > 2.5 / n
    assert measured == pytest.approx(predicted, abs=0.03)
    noise = np.random.default_rng(0).standard_normal((64, 64))
    assert mirror_chance(noise, n) == pytest.approx(1 / n, abs=0.01)


def test_mirror_chance_refuses_bad_input():
    with pytest.raises(InputError, match="constant"):
        mirror_chance(np.ones((8, 8)), 8)
    with pytest.raises(InputError, match="2D"):
        mirror_chance(np.ones(8), 8)
    with pytest.raises(InputError, match="side"):
        mirror_chance(np.eye(8), 0)


# ----------------------------------------------------------------------------- copy fraction


def _brute_counts(stack, ex):
    n, h, w = stack.shape
    big_h, big_w = ex.shape
    out = np.zeros((n, big_h, big_w), int)
    for dy in range(big_h):
        for dx in range(big_w):
            window = ex[(np.arange(h)[:, None] + dy) % big_h, (np.arange(w)[None, :] + dx) % big_w]
            out[:, dy, dx] = (stack == window).sum(axis=(1, 2))
    return out


@pytest.mark.parametrize("shape", [(3, 5, 7), (2, 9, 13), (1, 4, 6)])
def test_match_counts_equal_a_brute_force_loop(shape):
    rng = np.random.default_rng(sum(shape))
    ex = rng.integers(0, 3, (4, 6))
    stack = rng.integers(0, 4, shape)  # value 3 is not in the exemplar
    assert np.array_equal(match_counts(stack, ex), _brute_counts(stack, ex))


def test_copied_slices_are_found_in_every_view():
    rng = np.random.default_rng(2)
    ex = rng.integers(0, 8, (24, 24))
    window = np.roll(ex, (-5, -9), axis=(0, 1))[:16, :16]
    for view, put in [("front", lambda v: v.__setitem__(3, window)),
                      ("right", lambda v: v.__setitem__((slice(None), slice(None), 7), window.T)),
                      ("top", lambda v: v.__setitem__((slice(None), 11), window))]:
        vol = rng.integers(0, 8, (16, 16, 16))
        put(vol)
        m = max_copy_fraction(vol, ex)
        assert (m.fraction, m.view, m.index, m.shift) == (1.0, view, {"front": 3, "right": 7, "top": 11}[view], (5, 9))
        assert m.per_view[view][m.index] == 1.0 and sorted(m.per_view) == ["front", "right", "top"]


def test_tiled_slices_larger_than_the_exemplar_count_as_copies():
    rng = np.random.default_rng(3)
    ex = rng.integers(0, 4, (8, 8))
    vol = rng.integers(0, 4, (20, 20, 20))
    vol[4] = np.tile(ex, (3, 3))[:20, :20]
    vol[4, :2] = (vol[4, :2] + 1) % 4  # 40 of 400 pixels differ
    m = max_copy_fraction(vol, ex, views=["front"])
    assert (m.fraction, m.index, m.shift) == (0.9, 4, (0, 0))


def test_random_volume_copies_little():
    rng = np.random.default_rng(4)
    m = max_copy_fraction(rng.integers(0, 16, (16, 16, 16)), rng.integers(0, 16, (16, 16)))
    assert m.fraction < 0.25


@pytest.mark.parametrize("name, rows, cols", [("brick", 0, 0), ("tissue", 64, 32)])
def test_a_photograph_holds_its_exemplar_as_one_quarter(name, rows, cols):
    photo = gallery_photograph(name, 64)
    assert photo.shape == (128, 128) and photo.dtype == np.float64
    quarter = np.clip(np.round(photo[rows: rows + 64, cols: cols + 64]), 0, 255)
    np.testing.assert_array_equal(quarter, gallery_exemplar(name, 64))  # the exemplar, cut where it was
    assert np.mean(np.abs(photo[:64, 64:] - photo[64:, :64])) > 5  # the rest is more of it, not a copy
    with pytest.raises(InputError, match="generated"):
        gallery_photograph("porous50")


def test_a_draw_is_another_sample_of_the_same_material():
    ex = gallery_exemplar("composite3", 64)
    one, two = gallery_draw("composite3"), gallery_draw("composite3", 64, 2)
    np.testing.assert_array_equal(one, gallery_draw("composite3", 64, 1))  # reproducible; draw 1 by default
    assert two.shape == ex.shape and set(np.unique(two)) == set(np.unique(ex))  # the same phases
    assert np.mean(one != ex) > 0.2 and np.mean(one != two) > 0.2  # new pieces
    fractions = [np.mean(img == 128) for img in (ex, one)]
    assert abs(fractions[0] - fractions[1]) < 0.1  # of the same law
    with pytest.raises(InputError, match="photograph"):
        gallery_draw("brick")
    with pytest.raises(InputError, match="draw"):
        gallery_draw("porous50", 64, 0)
