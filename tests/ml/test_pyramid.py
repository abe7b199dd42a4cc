"""The exemplar of each scale (docs/design.md#pyramid) and the ``+in`` slices at every scale."""

import numpy as np
import pytest
from scipy.ndimage import correlate1d

from clsolid.errors import InputError
from clsolid.ml.model import build_scale, scale_exemplar
from clsolid.ml.params import MLParams
from clsolid.ml.reference import ReferenceBackend
from clsolid.core.slices import inserted_depths, slice_depths
from clsolid.ml.driver import run_ml


def _binomial_reference(labels: np.ndarray, level: int) -> np.ndarray:
    """float64, written independently: scipy's correlate with edge repeat, then a brute-force nearest level."""
    img = labels.astype(np.float64)
    for _ in range(level):
        for axis in (0, 1):
            img = correlate1d(img, [0.25, 0.5, 0.25], axis=axis, mode="nearest")
        img = img[::2, ::2]
    levels = np.unique(labels).astype(np.float64)
    return levels[np.argmin(np.abs(img[..., None] - levels), axis=-1)]  # argmin: lower level on a tie


@pytest.mark.parametrize("shape", [(16, 16), (13, 10), (7, 21)])
@pytest.mark.parametrize("level", [1, 2, 3])
def test_binomial_pyramid_matches_reference(shape, level):
    rng = np.random.default_rng(level)
    labels = rng.choice(np.array([0, 3, 4, 9, 15]), shape).astype(np.uint8)
    got = scale_exemplar(labels, level, "binomial")
    assert got.shape == tuple(-(-n // 2**level) for n in shape) and got.dtype == labels.dtype
    np.testing.assert_array_equal(got, _binomial_reference(labels, level))
    assert set(np.unique(got)) <= set(np.unique(labels))


def test_decimate_keeps_even_pixels_and_level_0_is_the_exemplar(brick_labels):
    np.testing.assert_array_equal(scale_exemplar(brick_labels, 2, "decimate"), brick_labels[::4, ::4])
    for pyramid in ("binomial", "decimate"):
        np.testing.assert_array_equal(scale_exemplar(brick_labels, 0, pyramid), brick_labels)


def test_thin_line_on_odd_row_survives_binomial_not_decimation():
    """Why binomial is the default: brick's one-pixel mortar lines vanish where they fall on odd pixels."""
    img = np.full((16, 16), 2, np.uint8)
    img[5] = 30
    img[15] = np.arange(0, 32, 2)  # the levels in between, as in a quantised image
    assert (scale_exemplar(img, 1, "decimate")[:7] == 2).all()
    rows = scale_exemplar(img, 1, "binomial")
    assert (rows[2:4] == 8).all()  # (2 + 2*2 + 30) / 4 = 9, between levels 8 and 10: the lower
    assert (rows[[0, 1, 4, 5, 6]] == 2).all()


def test_build_scale_uses_the_pyramid(brick_labels):
    for pyramid in ("binomial", "decimate"):
        model = build_scale(brick_labels, (16, 16, 16), MLParams(scales=2, neighborhood=5, pyramid=pyramid), 1)
        np.testing.assert_array_equal(model.exemplar, scale_exemplar(brick_labels, 1, pyramid))


def test_unknown_pyramid_is_refused():
    with pytest.raises(InputError, match="pyramid='gauss'"):
        MLParams(pyramid="gauss")


def scale_starts(labels, shape, params, seed=5) -> list:
    """(model, volume, temperatures) at the start of every scale of a reference run."""
    starts = []

    class Spy(ReferenceBackend):
        def start_scale(self, model, vol, temp, p, sources=None, parent=None):
            starts.append((model, vol.copy(), temp.copy()))
            super().start_scale(model, vol, temp, p, sources, parent)

    run_ml(labels, shape, params, seed, Spy())
    return starts


@pytest.mark.slow
@pytest.mark.parametrize("pyramid", ["binomial", "decimate"])
def test_inserted_slices_show_each_scale_exemplar(brick_labels, pyramid):
    """+in: every scale starts with its own exemplar on the same slices (depths halved), trusted."""
    params = MLParams(neighborhood=3, scales=3, insert_slices=2, views=2, max_sweeps=1, pyramid=pyramid,
                      slice_layout="aligned")
    shape = (20, 24, 16)
    starts = scale_starts(brick_labels[:32, :32], shape, params)
    full_depths = {"front": slice_depths(shape[0], 2, 4), "right": slice_depths(shape[2], 2, 4)}
    for model, vol, temp in starts:
        Z, Y, X = model.shape
        ex = np.tile(model.exemplar, (2, 2))
        right = full_depths["right"] // 2**model.level
        front_cols = np.setdiff1d(np.arange(X), right)  # where the right slices cross, they were written last
        for z in full_depths["front"] // 2**model.level:
            np.testing.assert_array_equal(vol[z][:, front_cols], ex[:Y, front_cols])
            assert (temp[z] == 0).all()
        for x in right:
            np.testing.assert_array_equal(vol[:, :, x].T, ex[:Y, :Z])
            assert (temp[:, :, x] == 0).all()


def _shift_of(slice_, exemplar, step, cols):
    """The (row, col) shift, in multiples of *step*, at which *slice_* is the tiled exemplar (on *cols*)."""
    reps = (-(-(slice_.shape[0] + exemplar.shape[0]) // exemplar.shape[0]),
            -(-(slice_.shape[1] + exemplar.shape[1]) // exemplar.shape[1]))
    tile = np.tile(exemplar, reps)
    rows = slice_.shape[0]
    for r in range(0, exemplar.shape[0], step):
        for c in range(0, exemplar.shape[1], step):
            if np.array_equal(tile[r:r + rows, c:c + slice_.shape[1]][:, cols], slice_[:, cols]):
                return r // step, c // step
    return None


@pytest.mark.slow
def test_staggered_slices_break_the_x_z_symmetry_consistently_across_scales(brick_labels):
    """Staggered +in: the views' slices at different depths, each with its own shift, the same at every scale
    (written whole, seams and all: the seam gap is the next test's)."""
    params = MLParams(neighborhood=3, scales=3, insert_slices=2, views=2, max_sweeps=1, slice_layout="staggered", seam_gap=0)
    shape = (16, 24, 16)
    starts = scale_starts(brick_labels[:32, :32], shape, params)
    depths = inserted_depths(shape, params)
    assert depths["front"].tolist() == [0, 8] and depths["right"].tolist() == [4, 12]
    shifts = []
    for model, vol, temp in starts:
        step = 2 ** (params.scales - 1 - model.level)
        xs, zs = depths["right"] // 2**model.level, depths["front"] // 2**model.level
        Z, Y, X = model.shape
        # where slices of the two views cross, either shows (the next test): look away from the crossings
        found = [_shift_of(vol[z], model.exemplar, step, np.setdiff1d(np.arange(X), xs)) for z in zs]
        found += [_shift_of(vol[:, :, x].T, model.exemplar, step, np.setdiff1d(np.arange(Z), zs)) for x in xs]
        assert all(f is not None for f in found)
        shifts.append(found)
        assert all((temp[z] == 0).all() for z in zs) and all((temp[:, :, x] == 0).all() for x in xs)
    assert shifts[0] == shifts[1] == shifts[2]  # the same full-resolution shifts at every scale
    assert len(set(shifts[0])) > 1  # slices show different parts of the exemplar
    assert not np.array_equal(inserted_depths(shape, MLParams())["front"], depths["right"])


def test_where_two_views_slices_cross_each_shows_at_every_other_crossing():
    """Front slice i and right slice j cross along a line in y: it shows the front slice's
    pixels where i + j is even, the right slice's where it is odd, so that every slice of
    either view keeps about half of its crossings (written in view order, the right view
    took them all, and the front view's slices scored worse: docs/design.md#staggered-slices). Aligned slices
    (the published form) are written as before, the right view's last."""
    from clsolid.core.slices import insert_slices

    ex = np.arange(12 * 16).reshape(12, 16)  # a pixel's value says where it came from
    shape = (40, 28, 36)
    params = MLParams(insert_slices=3, scales=2, views=2, slice_layout="staggered", seam_gap=0)  # shifted: pixels differ
    vol = np.full(shape, -1)
    insert_slices(vol, ex, params, 0, 7, shape)
    depths = inserted_depths(shape, params)
    zs, xs = depths["front"], depths["right"]

    def tiled(plane, free):  # the slice as its own tile of the exemplar, read off a column no crossing touches
        v = plane[0, free[0]]
        r, c = (v // 16) % 12, (v % 16 - free[0]) % 16
        return ex[(np.arange(plane.shape[0])[:, None] + r) % 12, (np.arange(plane.shape[1])[None, :] + c) % 16]

    front = [tiled(vol[z], np.setdiff1d(np.arange(shape[2]), xs)) for z in zs]
    right = [tiled(vol[:, :, x].T, np.setdiff1d(np.arange(shape[0]), zs)) for x in xs]
    kept = np.zeros((len(zs), len(xs)), bool)
    for i, z in enumerate(zs):
        for j, x in enumerate(xs):
            line = vol[z, :, x]
            assert not np.array_equal(front[i][:, x], right[j][:, z])  # the two views' pixels differ here
            kept[i, j] = np.array_equal(line, front[i][:, x])
            assert kept[i, j] or np.array_equal(line, right[j][:, z])
    np.testing.assert_array_equal(kept, (np.add.outer(np.arange(len(zs)), np.arange(len(xs))) % 2) == 0)
    aligned = MLParams(insert_slices=3, scales=2, views=2, slice_layout="aligned", seam_gap=0)  # the published form: as
    vol = np.full(shape, -1)  # it was, the right view's slices (written last) whole
    insert_slices(vol, ex, aligned, 0, 7, shape)
    for x in inserted_depths(shape, aligned)["right"]:
        np.testing.assert_array_equal(vol[:, :, x].T, ex[np.arange(shape[1])[:, None] % 12, np.arange(shape[0]) % 16])


def _away_from_seams(n, shift, size, band):
    """The rule, written out: pixel i shows exemplar row (i + shift) % size; a seam lies before
    every i > 0 that shows row 0; pixels within *band* of one are left out."""
    ok = np.ones(n, bool)
    for i in range(1, n):
        if (i + shift) % size == 0:
            ok[max(0, i - band): i + band] = False
    return ok


@pytest.mark.parametrize("layout", ["staggered", "aligned"])
def test_slices_leave_out_the_seams_where_they_wrap_the_exemplar(layout):
    """seam_gap: a +in slice shows the exemplar at one shift, except the pixels within
    seam_gap of a seam where it wraps, which are left as they were (and not marked inserted)."""
    from clsolid.core.slices import insert_slices

    ex = np.arange(12 * 16).reshape(12, 16)  # a pixel's value says where it came from
    shape = (40, 28, 36)  # slices longer than the exemplar: every one wraps, at any shift
    params = MLParams(insert_slices=3, scales=2, views=2, slice_layout=layout, seam_gap=2)
    vol = np.full(shape, -1)
    mask = insert_slices(vol, ex, params, 0, 7, shape)
    assert ((vol >= 0) == mask).all()
    depths = inserted_depths(shape, params)
    # where two views' slices cross, either may show in the other's gap: look away from the crossings
    free_x, free_z = (np.setdiff1d(np.arange(shape[a]), depths[v]) for a, v in ((2, "right"), (0, "front")))
    planes = [(vol[z], free_x) for z in depths["front"]] + [(vol[:, :, x].T, free_z) for x in depths["right"]]
    gaps = 0
    for plane, cols in planes:
        r, c = np.nonzero(plane[:, cols] >= 0)
        v = plane[:, cols][r[0], c[0]]
        shift = ((v // 16 - r[0]) % 12, (v % 16 - cols[c[0]]) % 16)
        rows_ok = _away_from_seams(plane.shape[0], shift[0], 12, 2)
        cols_ok = _away_from_seams(plane.shape[1], shift[1], 16, 2)
        expected = np.outer(rows_ok, cols_ok)[:, cols]
        np.testing.assert_array_equal(plane[:, cols] >= 0, expected)
        rr, cc = np.nonzero(expected)
        np.testing.assert_array_equal(plane[:, cols][rr, cc], ex[(rr + shift[0]) % 12, (cols[cc] + shift[1]) % 16])
        gaps += (~expected).sum()
    assert gaps > 0
    whole = MLParams(insert_slices=3, scales=2, views=2, slice_layout=layout, seam_gap=0)
    assert insert_slices(np.full(shape, -1), ex, whole, 0, 7, shape).sum() > mask.sum()  # 0: seams written


def test_the_seam_gap_is_taken_where_the_exemplars_seam_shows():
    """seam_gap=None: 2 for an exemplar whose wrap shows (a photograph's edges), 0 for one that
    tiles seamlessly; the ratio is about 1 for a periodic texture and 0 for a constant image."""
    from clsolid.core.slices import SEAM_SHOWS, seam_ratio
    from clsolid.gallery import gallery_exemplar

    rng = np.random.default_rng(1)
    k = np.fft.fftfreq(64)
    smooth = np.exp(-200 * (k[:, None] ** 2 + k[None, :] ** 2))  # a periodic field, features ~5 px
    periodic = np.real(np.fft.ifft2(np.fft.fft2(rng.standard_normal((64, 64))) * smooth))
    ramp = np.add.outer(np.arange(64.0), np.arange(64.0))  # its wrap jumps by 63 where neighbours differ by 1
    assert 0.7 < seam_ratio(periodic) < 1.3 and seam_ratio(ramp) > 30 and seam_ratio(np.ones((8, 8))) == 0
    assert seam_ratio(gallery_exemplar("brick", 64)) > SEAM_SHOWS > seam_ratio(gallery_exemplar("porous50", 64))
    params = MLParams()
    assert params.seam_gap is None
    assert params.for_exemplar(32, False, seam_ratio(ramp)).seam_gap == 2
    assert params.for_exemplar(32, False, seam_ratio(periodic)).seam_gap == 0
    assert MLParams(seam_gap=3).for_exemplar(32, False, 9.0).seam_gap == 3  # given, kept


@pytest.mark.slow
def test_pieced_slices_are_mosaics_of_windows_the_same_at_every_scale():
    """insert_piece: each piece of a +in slice is its own exemplar window, the same one at every scale."""
    labels = np.arange(256).reshape(16, 16)  # every pixel its own label: a value says where it came from
    params = MLParams(neighborhood=3, scales=3, insert_slices=2, views=2, max_sweeps=1, insert_piece=8, pyramid="decimate",
                      balance=0.0)
    shape = (16, 24, 16)
    starts = scale_starts(labels, shape, params)
    depths = inserted_depths(shape, params)
    per_scale = []
    for model, vol, temp in starts:
        f = 2**model.level
        cell = 8 // f
        Z, Y, X = model.shape
        free = np.setdiff1d(np.arange(X), depths["right"] // f)  # the right view's slices cross the front's
        shifts = []
        for z in depths["front"] // f:
            for pr in range(-(-Y // cell)):
                for pc in range(-(-X // cell)):
                    r = np.arange(pr * cell, min(Y, (pr + 1) * cell))
                    c = np.intersect1d(np.arange(pc * cell, min(X, (pc + 1) * cell)), free)
                    v = int(vol[z, r[0], c[0]])
                    s = ((v // 16 - r[0] * f) % 16, (v % 16 - c[0] * f) % 16)  # full-resolution shift
                    assert s[0] % 4 == 0 and s[1] % 4 == 0  # on multiples of 2^(scales-1)
                    window = ((r[:, None] * f + s[0]) % 16) * 16 + (c[None, :] * f + s[1]) % 16
                    np.testing.assert_array_equal(vol[z][np.ix_(r, c)], window)
                    shifts.append(s)
            assert (temp[z] == 0).all()
        per_scale.append(shifts)
    assert per_scale[0] == per_scale[1] == per_scale[2]  # the same full-resolution windows at every scale
    assert len(set(per_scale[0])) > len(depths["front"])  # a slice is more than one window


def test_piece_side_is_checked():
    with pytest.raises(InputError, match="multiple of 2"):
        MLParams(scales=3, insert_piece=6)
    with pytest.raises(InputError, match="insert_piece"):
        MLParams(insert_piece=-4)
    with pytest.raises(InputError, match="insert_piece"):
        MLParams(insert_piece=4.0)
    assert MLParams().insert_piece == 0 and MLParams(scales=6, insert_piece=64).insert_piece == 64
    for bad in (-1, 1.5, True, "2"):
        with pytest.raises(InputError, match="seam_gap"):
            MLParams(seam_gap=bad)
