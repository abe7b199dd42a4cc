"""The labelled preview: sizes, orientation of each panel, captions, bad input."""

import numpy as np
import pytest
from PIL import Image

from clsolid.errors import InputError
from clsolid.ml.params import MLParams
from clsolid.preview import PREVIEW_MIN_SIDE, render_preview, save_preview
from clsolid.core.slices import far_depth, inserted_depths, preview_depths


def _panel(preview, i):
    x, y, w, h = preview.boxes[i]
    return preview.image[y:y + h, x:x + w]


@pytest.mark.parametrize("shape", [(64, 64, 64), (8, 10, 12), (300, 20, 40)])
def test_every_panel_is_at_least_256_pixels_on_its_long_side(shape):
    p = render_preview(np.zeros((64, 64)), np.ones(shape))
    assert len(p.boxes) == 4
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
    assert p.captions == ["exemplar 8x8", "front z=1, constrained", "right x=7, constrained", "top y=3"]


def test_constrained_views_are_marked():
    p = render_preview(np.zeros((8, 8)), np.zeros((8, 8, 8)), constrained=("front", "right", "top"))
    assert all(c.endswith(", constrained") for c in p.captions[1:])
    # captions are drawn: dark pixels above every panel
    assert all((p.image[:y, x:x + w] < 128).any() for x, y, w, h in p.boxes)


def test_saved_png_is_the_rendered_image(tmp_path):
    rng = np.random.default_rng(0)
    ex, vol = rng.random((16, 16)), rng.random((16, 16, 16))
    path = save_preview(tmp_path / "sub" / "p.png", ex, vol)
    with Image.open(path) as img:
        np.testing.assert_array_equal(np.asarray(img), render_preview(ex, vol).image)


def test_preview_slices_avoid_the_inserted_slices():
    params = MLParams(insert_slices=4)  # 4 +in slices per constrained view, 3 scales
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
