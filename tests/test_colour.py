"""Colour exemplars: their palette, and colour volumes from the likelihood method."""

import numpy as np
import pytest

import clsolid
from clsolid.colour import kmeans, lab, luminance, palette
from clsolid.errors import InputError
from clsolid.exemplar import level_map, load_exemplars

SHAPE = (10, 12, 14)


@pytest.fixture(scope="module")
def coffee():
    """A 32x32 crop of scikit-image's coffee (uint8 RGB, hundreds of colours)."""
    from skimage import data

    return np.ascontiguousarray(data.coffee()[180:212, 300:332])


@pytest.fixture(scope="module")
def tiles():
    """Four colours in 4x4 blocks: a colour exemplar that needs no quantisation."""
    colours = np.array([[200, 30, 30], [30, 160, 40], [20, 40, 220], [240, 230, 60]], np.uint8)
    index = np.kron(np.array([[0, 1, 2, 3], [2, 3, 0, 1], [1, 0, 3, 2], [3, 2, 1, 0]]), np.ones((4, 4), int))
    return colours[index]


def test_few_colours_are_the_palette_itself(tiles):
    levels = level_map(tiles, 32)
    assert levels.exact and levels.colour and levels.n_labels == 4 and levels.values.dtype == np.uint8
    np.testing.assert_array_equal(levels.to_values(levels.labels), tiles)
    lightness = levels.features[:, 0]
    assert np.all(np.diff(lightness) > 0)  # ordered by CIELAB lightness
    np.testing.assert_allclose(levels.features, lab(levels.values, np.uint8))


def test_many_colours_are_quantised_by_kmeans_in_cielab(coffee):
    levels = level_map(coffee, 12)
    assert not levels.exact and levels.n_labels == 12 and levels.values.shape == (12, 3)
    again = level_map(coffee.copy(), 12)
    np.testing.assert_array_equal(again.labels, levels.labels)  # a fixed start: the same palette every time
    # each pixel's label is its nearest palette colour in CIELAB (k-means has converged)
    d = np.sum((lab(coffee, np.uint8)[:, :, None, :] - levels.features[None, None]) ** 2, axis=-1)
    near = np.take_along_axis(d, levels.labels[..., None], axis=-1)[..., 0]
    assert np.mean(near <= d.min(axis=-1) + 1.0) > 0.98
    # and the palette is each cluster's mean colour: the quantisation error is small
    error = np.abs(levels.to_values(levels.labels).astype(int) - coffee.astype(int)).mean()
    assert error < 6.0


def test_kmeans_finds_well_separated_clusters():
    rng = np.random.default_rng(0)
    centres = np.array([[0.0, 0, 0], [50, 0, 0], [0, 50, 0]])
    points = np.concatenate([c + rng.normal(0, 1, (40, 3)) for c in centres])
    found, labels = kmeans(points, 3)
    assert sorted(np.bincount(labels).tolist()) == [40, 40, 40]
    for c in centres:
        assert np.min(np.linalg.norm(found - c, axis=1)) < 1.0


def test_a_float_colour_image_is_read_as_zero_to_one():
    rgb = np.random.default_rng(1).random((6, 7, 3))
    labels, values, exact = palette(rgb, 8)
    assert values.dtype == rgb.dtype and values.shape == (8, 3) and not exact
    assert labels.shape == (6, 7) and labels.max() == 7


def test_colour_levels_need_a_number(tiles):
    with pytest.raises(InputError, match="colour exemplar needs a number"):
        level_map(tiles, None)


def test_views_are_all_grey_or_all_colour(tmp_path, tiles):
    from PIL import Image

    Image.fromarray(tiles).save(tmp_path / "colour.png")
    Image.fromarray(tiles[..., 0]).save(tmp_path / "grey.png")
    with pytest.raises(InputError, match="all grey or all colour"):
        load_exemplars({"front": tmp_path / "colour.png", "right": tmp_path / "grey.png"})


def test_luminance_weights_green_most():
    assert luminance(np.array([0.0, 1.0, 0.0])) > luminance(np.array([1.0, 0.0, 0.0])) > luminance(
        np.array([0.0, 0.0, 1.0]))


def test_a_colour_volume_holds_only_palette_colours(device, coffee):
    result = clsolid.synthesize(coffee, SHAPE, channel_axis=-1, rng=3, device=device, full_output=True,
                                neighborhood=5, scales=2, levels=16)
    vol = result.volume
    assert vol.shape == SHAPE + (3,) and vol.dtype == np.uint8
    assert result.params["likelihood"] == "pruned" and result.params["distance"] == "squared"
    np.testing.assert_array_equal(vol, result.level_values[result.labels])
    assert result.labels.max() < 16
    # the colours' shares follow the exemplar's (the balance keeps the label fractions)
    want = np.bincount(result.exemplar_labels.ravel(), minlength=16) / result.exemplar_labels.size
    got = np.bincount(result.labels.ravel(), minlength=16) / result.labels.size
    assert 0.5 * np.abs(got - want).sum() < 0.1
    again = clsolid.synthesize(coffee, SHAPE, channel_axis=-1, rng=3, device=device, neighborhood=5, scales=2,
                               levels=16)
    np.testing.assert_array_equal(again, vol)


def test_a_colour_run_in_tiles_is_the_one_piece_run(device, tiles):
    kw = dict(channel_axis=-1, rng=5, device=device, neighborhood=3, scales=2)
    whole = clsolid.synthesize(tiles, SHAPE, **kw)
    np.testing.assert_array_equal(clsolid.synthesize(tiles, SHAPE, backend={"tile": 6}, **kw), whole)


def test_segmented_colours_are_phases(device, tiles):
    """Four colours exactly: a segmented image, its labels compared as phases (the pruned sum)."""
    result = clsolid.synthesize(tiles, SHAPE, channel_axis=-1, rng=1, device=device, full_output=True,
                                neighborhood=3, scales=1)
    assert result.params["distance"] == "weighted" and result.params["likelihood"] == "pruned"
    colours = {tuple(c) for c in tiles.reshape(-1, 3).tolist()}
    assert {tuple(c) for c in result.volume.reshape(-1, 3).tolist()} <= colours


def test_colours_by_their_distance_refuse_projected_candidates(coffee):
    with pytest.raises(InputError, match="colours, have no projection"):
        clsolid.synthesize(coffee, SHAPE, channel_axis=-1, likelihood="pruned", prune_projected=4, device="reference",
                           neighborhood=3, scales=1)


@pytest.mark.parametrize("likelihood", ["exact", "pruned"])
def test_a_colour_volume_does_not_depend_on_the_kernels_tuning(device, tiles, likelihood):
    """The work-group size and the voxel-views an item change how the sums are launched,
    never the volume."""
    kw = dict(channel_axis=-1, rng=4, device=device, neighborhood=3, scales=2, distance="squared",
              likelihood=likelihood)
    want = clsolid.synthesize(tiles, SHAPE, **kw)
    for tuning in ({"local_size": 4}, {"local_size": 32, "voxels_per_item": 1}):
        np.testing.assert_array_equal(clsolid.synthesize(tiles, SHAPE, backend=tuning, **kw), want)


def test_each_view_may_have_its_own_colour_exemplar(device, coffee, tiles):
    other = np.ascontiguousarray(np.tile(tiles, (2, 2, 1)))  # 32x32: four other colours
    result = clsolid.synthesize({"front": coffee, "right": other}, SHAPE, channel_axis=-1, rng=2, device=device,
                                full_output=True, neighborhood=3, scales=1, levels=12)
    assert result.volume.shape == SHAPE + (3,) and result.params["views"] == 2
    assert {tuple(c) for c in result.volume.reshape(-1, 3).tolist()} <= {tuple(c) for c in
                                                                        result.level_values.tolist()}
