"""The block on the device (clsolid.search.block): the exhaustive search of voxels whose
queries the device gathers finds what the matcher finds on NumPy's gathers."""

import numpy as np
import pytest

from clsolid.core.views import VIEW_SETS
from clsolid.gallery import gallery_exemplar
from clsolid.search.block import DeviceBlock
from clsolid.search.codes import phase_codes
from clsolid.search.features import centre_weights, exemplar_features, voxel_features
from clsolid.search.match import CLMatcher
from clsolid.search.pyramid import gaussian_pyramid

# Every test here that takes a device checks a kernel against the reference: on every device.
pytestmark = pytest.mark.each_device


@pytest.mark.parametrize("parent, centre", [(False, False), (True, False), (True, True)])
def test_the_device_gathers_the_queries_numpy_gathers(device, parent, centre):
    """Every view, voxels whose squares wrap round the block (all of them, in an odd-sided
    block), launches of fewer queries than the set (each reads its own part of the voxels),
    the parent's square from a coarser block (then another), and the centre term in or out: the same sites
    and distances as the matcher's search of voxel_features' rows."""
    rng = np.random.default_rng(5)
    pyr = gaussian_pyramid(gallery_exemplar("gravel", 64)[:24, :28].astype(np.float64), 2)
    k, shape = 5, (7, 9, 11)
    table, _ = exemplar_features(pyr[0], pyr[1] if parent else None, k)
    matcher = CLMatcher(device, table, max_batch=100)
    block = DeviceBlock(matcher)
    vol = np.round(rng.random(shape) * 255)
    coarse = np.round(rng.random((4, 5, 6)) * 255) if parent else None
    w = centre_weights(k, parent, centre)
    voxels = rng.permutation(vol.size)[:333]
    calls = [(view, coarse) for view in VIEW_SETS[3]]
    if parent:  # another coarser block (a new level's): sent anew
        calls.append(("front", np.round(rng.random((4, 5, 6)) * 255)))
    for view, parent_block in calls:
        got = block.best(view, voxels, vol, parent_block, k, w)
        want = matcher.best(voxel_features(vol, parent_block, voxels, view, k), w)
        np.testing.assert_array_equal(got[0], want[0])
        np.testing.assert_array_equal(got[1], want[1])


def test_phase_codes_and_a_new_block_and_parent(device):
    """kopf's weighted mismatch: the block sent as its phases' codes (the matcher compares
    codes); then a larger block (room made again)."""
    phases = gallery_exemplar("composite3", 64)[:30, :30]
    codes = phase_codes(phases)
    k = 3
    table, _ = exemplar_features(codes.encode(phases).astype(np.float64), None, k)
    matcher = CLMatcher(device, table, mismatch=k * k)
    block = DeviceBlock(matcher)
    rng = np.random.default_rng(2)
    w = centre_weights(k, False, centre=False)
    for shape in ((4, 5, 6), (8, 8, 8)):
        vol = codes.encode(rng.choice(np.unique(phases), size=shape))
        voxels = np.arange(vol.size)
        got = block.best("right", voxels, vol, None, k, w)
        want = matcher.best(voxel_features(vol, None, voxels, "right", k), w)
        np.testing.assert_array_equal(got[0], want[0])
        np.testing.assert_array_equal(got[1], want[1])


def test_a_program_of_two_files_is_built_as_one_and_named_by_both(device):
    """coherence_best (match.cl) uses gather.cl's voxel_query: built after it, in one
    program; a failed build names both files."""
    from clsolid.core import programs
    from clsolid.errors import KernelBuildError

    ok = dict(QDIM=9, DIM=8, VW=4, K=1, UNIT=1, NMIS=0, QB=1, KSIDE=3, PARENT=0, SIMILAR=4, SPREAD=0)
    kernels = programs.build(device, ("search/gather.cl", "search/match.cl"), ok)
    assert {"voxel_queries", "coherence_best", "k_nearest"} <= set(kernels)
    with pytest.raises(KernelBuildError, match="kernels/search/match.cl \\+ kernels/search/gather.cl"):
        programs.build(device, ("search/match.cl", "search/gather.cl"), ok)  # voxel_query used before it is defined
