"""The search methods' anchor slices (``insert_spacing``; clsolid.search.driver): exemplar
slices held at the coarse levels, noise at the finest, and what they are for: blocks that
are not their own x <-> z mirror image."""

import numpy as np
import pytest

import clsolid
from clsolid import InputError, metrics
from clsolid.cli import main
from clsolid.core.slices import inserted_depths
from clsolid.gallery import gallery_exemplar
from clsolid.presets import PRESETS
from clsolid.search.driver import _anchor, level_shapes
from clsolid.search.params import SearchParams


def test_kopf_anchors_by_default_and_the_others_do_not():
    assert SearchParams(method="kopf").insert_spacing == 5.0
    assert SearchParams(method="wl").insert_spacing == 0.0 and SearchParams(method="chen-wang").insert_spacing == 0.0
    assert SearchParams(method="kopf", insert_spacing=0).insert_slices == 0  # no slices at all
    assert SearchParams(method="wl", insert_spacing=4).insert_slices is None  # as many as the spacing says
    for name, preset in PRESETS.items():  # the thesis's experiments: its form
        if preset.method == "kopf":
            assert preset.options["insert_spacing"] == 0.0, name


@pytest.mark.parametrize("bad", [-1, 0.5, True, float("inf"), "6"])
def test_a_bad_spacing_is_refused(bad):
    with pytest.raises(InputError, match="insert_spacing"):
        SearchParams(method="kopf", insert_spacing=bad)


def test_coarse_levels_hold_exemplar_slices_and_the_finest_starts_them_from_noise():
    ex = gallery_exemplar("composite3", 64).astype(np.float64)
    params = SearchParams(method="kopf", scales=3)
    shape = (24, 20, 32)
    depths = inserted_depths(shape, params)
    coarse_shape = level_shapes(shape, 3)[1]
    vol = np.full(coarse_shape, -1.0)
    voxels, values = _anchor(params, vol, ex[::2, ::2], 1, 5, shape)
    planes = np.zeros(coarse_shape, bool)
    planes[depths["front"] // 2] = True
    planes[:, :, depths["right"] // 2] = True
    planes[:, depths["top"] // 2] = True
    np.testing.assert_array_equal(np.sort(voxels), np.flatnonzero(planes))  # every slice, nothing else
    np.testing.assert_array_equal(vol.ravel()[voxels], values)
    assert set(np.unique(values)) <= set(np.unique(ex[::2, ::2]))
    fine = np.full(shape, -1.0)
    assert _anchor(params, fine, ex, 0, 5, shape) is None  # nothing held at the finest level
    d = depths["front"][0]
    assert (fine[d] >= 0).all() and (fine[d + 1] >= 0).all()  # the slice and its up-sampled twin: noise
    assert set(np.unique(fine[fine >= 0])) <= set(np.unique(ex))
    away = [np.setdiff1d(np.arange(n), np.r_[depths[v], depths[v] + 1])
            for n, v in zip(shape, ("front", "top", "right"))]
    assert (fine[np.ix_(*away)] == -1).all()  # elsewhere the start is untouched
    assert _anchor(SearchParams(method="kopf", insert_spacing=0), fine, ex, 1, 5, shape) is None


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2])
def test_anchors_keep_kopf_from_growing_its_own_mirror_image(seed):
    """With two views and without anchors kopf settles into sheets along the x = z diagonal (both
    views' slices then show the same 2D texture; docs/design.md#anchor-slices): on porous50 at 24^3 the
    mirror correlation is over 0.25 without them and under a third of that with the
    default's. lamellae is not tested here: a 24^3 block holds too few of its bands for the
    anchors to decide; its mirror at 48^3 is in tests/ml/test_materials.py."""
    ex = gallery_exemplar("porous50", 64)
    mirror = {}
    for spacing in (0, None):
        vol = clsolid.synthesize(ex, (24, 24, 24), method="kopf", rng=seed, insert_spacing=spacing, views=2)
        mirror[spacing] = next(iter(metrics.mirror_correlations(vol, [(0, 2)]).values()))
    assert mirror[0] > 0.25 and mirror[None] < mirror[0] / 3, mirror


def test_the_command_line_passes_the_spacing(tmp_path):
    out = tmp_path / "v.npy"
    base = ["synth", "brick", "-o", str(out), "--shape", "8", "8", "8", "--scales", "2", "--neighborhood", "3",
            "--iterations", "1", "--levels", "8", "-q"]
    assert main([*base, "--method", "wl", "--insert-spacing", "4"]) == 0  # not refused as the likelihood's
    assert main([*base, "--method", "kopf", "--insert-spacing", "0"]) == 0
    import json

    assert json.loads((tmp_path / "v.json").read_text())["params"]["insert_spacing"] == 0.0
