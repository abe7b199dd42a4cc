"""The labelled preview: sizes, orientation of each panel, captions, the cube, bad input."""

import math

import numpy as np
import pytest
from PIL import Image

from clsolid.errors import InputError
from clsolid.ml.params import MLParams
from clsolid.preview import PREVIEW_MIN_SIDE, render_cube, render_preview, save_preview
from clsolid.core.slices import far_depth, inserted_depths, preview_depths


def _panel(preview, i):
    x, y, w, h = preview.boxes[i]
    return preview.image[y:y + h, x:x + w]


@pytest.mark.parametrize("shape", [(64, 64, 64), (8, 10, 12), (300, 20, 40)])
def test_every_panel_is_at_least_256_pixels_on_its_long_side(shape):
    p = render_preview(np.zeros((64, 64)), np.ones(shape))
    assert len(p.boxes) == 5  # exemplar, three slices, cube
    for x, y, w, h in p.boxes:
        assert max(w, h) >= PREVIEW_MIN_SIDE
    # 64 -> 4x exactly: small blocks are enlarged by whole factors only
    assert p.boxes[0][2:] == (256, 256)


def test_panels_show_the_named_slices_in_the_right_orientation():
    Z, Y, X = 6, 8, 10
    z, y, x = np.meshgrid(np.arange(Z), np.arange(Y), np.arange(X), indexing="ij")
    volume = (x + 10 * y + 100 * z).astype(np.float64)
    depths = {"front": 1, "right": 7, "top": 3}
    p = render_preview(np.zeros((8, 8)), volume, depths=depths)
    lo, hi = 0.0, max(volume[1].max(), volume[:, :, 7].max(), volume[:, 3, :].max())

    def grey(a):
        return np.rint((a - lo) * (255 / hi)).astype(np.uint8)

    for i, expected in ((1, volume[1]), (2, volume[:, :, 7].T), (3, volume[:, 3, :])):
        panel = _panel(p, i)
        k = panel.shape[0] // expected.shape[0]
        np.testing.assert_array_equal(panel[::k, ::k], grey(expected))
        np.testing.assert_array_equal(panel, np.kron(panel[::k, ::k], np.ones((k, k), np.uint8)))
    assert p.captions == ["exemplar 8x8", "front z=1, constrained", "right x=7, constrained", "top y=3",
                          "block z>=1 y>=3 x<=7"]


def test_constrained_views_are_marked():
    p = render_preview(np.zeros((8, 8)), np.zeros((8, 8, 8)), constrained=("front", "right", "top"))
    assert all(c.endswith(", constrained") for c in p.captions[1:4])
    # captions are drawn: dark pixels above every panel
    assert all((p.image[:y, x:x + w] < 128).any() for x, y, w, h in p.boxes)


def test_saved_png_is_the_rendered_image(tmp_path):
    rng = np.random.default_rng(0)
    ex, vol = rng.random((16, 16)), rng.random((16, 16, 16))
    path = save_preview(tmp_path / "sub" / "p.png", ex, vol)
    with Image.open(path) as img:
        np.testing.assert_array_equal(np.asarray(img), render_preview(ex, vol).image)


def test_a_preview_that_fills_the_disk_leaves_what_was_there(tmp_path, full_disk):
    """Out of space partway: the PNG that was there stays whole, and no partial file is left."""
    rng = np.random.default_rng(1)
    ex, vol = rng.random((16, 16)), rng.random((12, 12, 12))
    path = save_preview(tmp_path / "p.png", ex, vol)
    before = path.read_bytes()
    full_disk(tmp_path, len(before) // 2)
    with pytest.raises(OSError, match="No space left"):
        save_preview(path, ex, vol[::-1])
    assert sorted(tmp_path.iterdir()) == [path] and path.read_bytes() == before


def test_preview_slices_avoid_the_inserted_slices():
    params = MLParams(insert_slices=4, views=2)  # 4 +in slices per constrained view, 3 scales
    shape = (64, 48, 64)
    taken = inserted_depths(shape, params)
    assert set(taken) == {"front", "right"} and taken["front"].tolist() == [0, 16, 32, 48]
    chosen = preview_depths(shape, params)
    for view in ("front", "right"):
        assert np.min(np.abs(taken[view] - chosen[view])) == 8
    assert chosen["top"] == 24  # no +in slices: the middle
    assert far_depth(10, np.array([0])) == 5 and far_depth(7, np.empty(0, int)) == 3


def test_default_slices_follow_the_spacing():
    # About one slice every insert_spacing voxels, on multiples of 2^(scales-1), on each
    # view's own depth axis; a count, when given, wins; 0 is -in.
    for size, spacing in [(48, 6.0), (64, 6.0), (32, 6.0), (128, 6.0), (48, 12.0)]:
        params = MLParams(insert_spacing=spacing)
        depths = inserted_depths((size, 20, 2 * size), params)
        assert len(depths["front"]) == round(size / spacing) and len(depths["right"]) == round(2 * size / spacing)
        assert all(np.all(d % 4 == 0) for d in depths.values())
    assert len(inserted_depths((48, 20, 48), MLParams(insert_slices=3))["front"]) == 3
    assert all(d.size == 0 for d in inserted_depths((48, 20, 48), MLParams(insert_slices=0)).values())
    with pytest.raises(InputError, match="insert_spacing"):
        MLParams(insert_spacing=0.5)


@pytest.mark.parametrize("kwargs, param", [
    ({"path": "p.jpg"}, "path"),
    ({"exemplar": np.zeros((2, 2, 2))}, "exemplar"),
    ({"exemplar": np.array([[np.nan]])}, "exemplar"),
    ({"volume": np.zeros((4, 4))}, "volume"),
    ({"volume": np.full((2, 2, 2), np.inf)}, "volume"),
    ({"depths": {"front": 9}}, "depths"),
    ({"depths": {"side": 1}}, "depths"),
])
def test_preview_bad_input(tmp_path, kwargs, param):
    args = {"path": "p.png", "exemplar": np.zeros((4, 4)), "volume": np.zeros((4, 4, 4))}
    args.update(kwargs)
    args["path"] = tmp_path / args["path"]
    with pytest.raises(InputError, match=param):
        save_preview(**args)


# --------------------------------------------------------------------------- the cube

#: render_cube's grey levels for a volume whose front face is 2, top face 1 and right face 3:
#: front mid-grey, top black lightened by the default shade 0.2, right white darkened by it.
FRONT, TOP, RIGHT, EDGE, BACKGROUND = 128, 51, 204, 0, 255


def _faces_volume(shape):
    """A volume holding 2 on its front face, 1 on its top face, 3 on its right face, 0 inside."""
    volume = np.zeros(shape)
    volume[0] = 2
    volume[:, 0, :] = 1
    volume[:, :, -1] = 3
    return volume


def _face_masks(shape):
    image = render_cube(_faces_volume(shape))
    return {name: image == value for name, value in (("front", FRONT), ("top", TOP), ("right", RIGHT))}


def test_the_cube_faces_carry_the_volume_faces():
    Z, Y, X = 6, 8, 10
    image = render_cube(_faces_volume((Z, Y, X)))
    assert set(np.unique(image)) == {FRONT, TOP, RIGHT, EDGE, BACKGROUND}
    # the smallest whole pixels per voxel that take the long side, X plus the receding depth, to 256
    k = math.ceil(PREVIEW_MIN_SIDE / (X + Z * 0.5 * np.cos(np.pi / 4)))
    rows, cols = np.indices(image.shape)
    centre = {}
    for name, value in (("front", FRONT), ("top", TOP), ("right", RIGHT)):
        mask = image == value
        centre[name] = rows[mask].mean(), cols[mask].mean()
        assert mask[int(centre[name][0]), int(centre[name][1])], name  # a face is one convex piece
    # areas: the front face is Y x X voxels of k x k pixels; the oblique faces are sheared by half
    # the depth at 45 degrees, so each is Z * 0.5 * sin(45) voxels deep on screen
    # (the top face's voxels overwrite the front face's top row, the right face's their last column)
    assert (image == FRONT).sum() == pytest.approx((Y - 1) * (X - 1) * k * k, rel=0.02)
    assert (image == TOP).sum() == pytest.approx((X - 1) * Z * 0.5 * np.sin(np.pi / 4) * k * k, rel=0.05)
    assert (image == RIGHT).sum() == pytest.approx(Y * Z * 0.5 * np.cos(np.pi / 4) * k * k, rel=0.05)
    assert centre["top"][0] < centre["front"][0] and centre["top"][1] > centre["front"][1]
    assert centre["right"][1] > centre["front"][1] and centre["right"][0] < centre["front"][0]
    # white outside the cube at the top-left and bottom-right corners, black edges around it
    assert image[0, 0] == image[-1, -1] == BACKGROUND
    assert image[-1, 0] == EDGE and (image[:, 0] == EDGE).sum() > Y * k * 0.9


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_the_cube_faces_are_oriented_as_the_views(axis):
    shape = (6, 8, 10)
    masks = _face_masks(shape)
    volume = np.indices(shape)[axis].astype(np.float64)  # values rise along one axis only
    image = render_cube(volume).astype(int)

    def along_rows(face):  # the face's pixels left to right along its middle row
        mask = masks[face]
        r = int(np.median(np.nonzero(mask)[0]))
        return image[r, mask[r]]

    def down_cols(face):  # the face's pixels top to bottom along its middle column
        mask = masks[face]
        c = int(np.median(np.nonzero(mask)[1]))
        return image[mask[:, c], c]

    def rising(values):
        return np.all(np.diff(values) >= 0) and values[-1] > values[0]

    def flat(values):
        return np.ptp(values) == 0

    if axis == 0:  # z recedes: up the top face, rightwards across the right face; the front is z = 0
        assert rising(-down_cols("top")) and rising(along_rows("right")) and flat(along_rows("front"))
    elif axis == 1:  # y runs down the front and right faces; the top face is y = 0
        assert rising(down_cols("front")) and rising(down_cols("right")) and flat(along_rows("top"))
    else:  # x runs along the front and top faces; the right face is x = X - 1
        assert rising(along_rows("front")) and rising(along_rows("top")) and flat(down_cols("right"))


def test_the_cube_at_a_corner_is_the_block_behind_it():
    volume = np.random.default_rng(1).random((12, 10, 14))
    np.testing.assert_array_equal(render_cube(volume, corner=(3, 2, 9)), render_cube(volume[3:, 2:, :10]))
    assert render_cube(volume, min_side=64).shape[1] < render_cube(volume).shape[1]
    faces = _faces_volume((6, 8, 10))
    edged, plain = render_cube(faces), render_cube(faces, edges=False)
    lines = edged != plain
    assert np.all(edged[lines] == EDGE) and lines.sum() > 2 * sum(plain.shape)  # edges only, all round
    # unshaded, the oblique faces keep the volume's grey levels: 1, 2, 3 -> 0, 128, 255
    assert set(np.unique(render_cube(faces, shade=0.0))) == {0, 128, 255}


def test_the_preview_grows_to_show_the_cube_of_the_block_behind_its_slices():
    rng = np.random.default_rng(2)
    segmented = rng.integers(0, 3, (16, 20, 24)).astype(np.uint8)  # three phases, as labels
    exemplar = rng.integers(0, 3, (16, 16)).astype(np.uint8)
    depths = {"front": 5, "right": 17, "top": 6}
    with_cube = render_preview(exemplar, segmented, depths=depths)
    without = render_preview(exemplar, segmented, depths=depths, cube=False)
    assert len(with_cube.boxes) == 5 and len(without.boxes) == 4
    x, y, w, h = with_cube.boxes[4]
    assert with_cube.image.shape[1] == without.image.shape[1] + w + 8 and max(w, h) >= PREVIEW_MIN_SIDE
    # its faces are the slices shown, in the preview's grey scale (here the faces' own: 0..2)
    cube = render_cube(segmented, corner=(5, 6, 17))
    np.testing.assert_array_equal(with_cube.image[y:y + h, x:x + w], cube)
    assert set(np.unique(cube)) >= {0, 128, 255}  # the front face keeps the phases' grey levels
    for i in range(4):
        np.testing.assert_array_equal(_panel(with_cube, i), _panel(without, i))


def test_a_grey_volume_previews_with_its_cube(tmp_path):
    rng = np.random.default_rng(3)
    grey = rng.normal(100.0, 20.0, (32, 32, 32)).astype(np.float32)
    path = save_preview(tmp_path / "p.png", rng.normal(100.0, 20.0, (32, 32)), grey)
    with Image.open(path) as img:
        image = np.asarray(img)
    preview = render_preview(rng.normal(100.0, 20.0, (32, 32)), grey)
    assert image.shape == preview.image.shape and preview.captions[4] == "block z>=16 y>=16 x<=16"
    cube = _panel(preview, 4)
    assert len(np.unique(cube)) > 50  # grey levels, not a few phases


@pytest.mark.parametrize("kwargs, param", [
    ({"volume": np.zeros((4, 4))}, "volume"),
    ({"volume": np.full((2, 2, 2), np.nan)}, "volume"),
    ({"corner": (0, 0, 4)}, "corner"),
    ({"corner": (0, 0)}, "corner"),
    ({"depth": 0.0}, "depth"),
    ({"angle": 90.0}, "angle"),
    ({"shade": 1.0}, "shade"),
    ({"min_side": 0}, "min_side"),
])
def test_cube_bad_input(kwargs, param):
    args = {"volume": np.zeros((4, 4, 4))}
    args.update(kwargs)
    volume = args.pop("volume")
    with pytest.raises(InputError, match=param):
        render_cube(volume, **args)


def test_a_colour_preview_shows_the_colours_as_they_are():
    rng = np.random.default_rng(2)
    exemplar = rng.integers(0, 256, (16, 16, 3)).astype(np.uint8)
    volume = rng.integers(0, 256, (8, 10, 12, 3)).astype(np.uint8)
    p = render_preview(exemplar, volume, depths={"front": 2, "right": 5, "top": 4})
    assert p.image.ndim == 3 and p.image.shape[-1] == 3
    for i, expected in ((0, exemplar), (1, volume[2]), (2, np.swapaxes(volume[:, :, 5], 0, 1)), (3, volume[:, 4])):
        panel = _panel(p, i)
        k = panel.shape[0] // expected.shape[0]
        np.testing.assert_array_equal(panel[::k, ::k], expected)  # 8-bit colours unscaled
    cube = render_cube(volume)
    assert cube.ndim == 3 and cube.shape[-1] == 3
    with pytest.raises(InputError, match="RGB"):
        render_preview(exemplar[..., 0], volume)
