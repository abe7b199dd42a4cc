"""Specks out of a segmented volume: the rule, its order-independence, and where it applies."""

import numpy as np
import pytest

import clsolid
from clsolid.core.despeckle import despeckle, specks
from clsolid.gallery import gallery_exemplar


def _reference(labels: np.ndarray) -> np.ndarray:
    """The rule voxel by voxel: the colours in turn, each speck taking the phase most of its 6
    face neighbours have (the lowest on a tie), the block wrapping."""
    out = labels.copy()
    Z, Y, X = out.shape

    def cycle(i, n):  # alternate 0 and 1; an odd cycle's last 2
        return 2 if n % 2 and i == n - 1 else i % 2

    for colour in range(3):
        for z, y, x in np.ndindex(Z, Y, X):
            if (cycle(z, Z) + cycle(y, Y) + cycle(x, X)) % 3 != colour:
                continue
            nb = [out[(z - 1) % Z, y, x], out[(z + 1) % Z, y, x], out[z, (y - 1) % Y, x], out[z, (y + 1) % Y, x],
                  out[z, y, (x - 1) % X], out[z, y, (x + 1) % X]]
            if all(n != out[z, y, x] for n in nb):
                values, counts = np.unique(nb, return_counts=True)
                out[z, y, x] = values[np.argmax(counts)]  # unique sorts: the first of the most is the lowest
    return out


@pytest.mark.parametrize("shape, phases, seed", [((6, 7, 8), 2, 0), ((5, 6, 7), 3, 1), ((4, 9, 5), 4, 2)])
def test_despeckle_is_the_rule_voxel_by_voxel(shape, phases, seed):
    labels = np.random.default_rng(seed).integers(0, phases, shape).astype(np.uint8)
    want = _reference(labels)
    changed = despeckle(labels)
    np.testing.assert_array_equal(labels, want)
    assert changed > 0 and specks(labels) == 0


@pytest.mark.parametrize("shape", [(4, 6, 8), (5, 7, 9), (3, 4, 5)])
def test_face_neighbours_never_share_a_colour(shape):
    from clsolid.core.despeckle import colours

    by_z, by_yx = colours(shape)
    c = (by_z[:, None, None] + by_yx[None]) % 3
    for axis in range(3):
        assert np.all(c != np.roll(c, 1, axis))


def test_a_speck_joins_its_neighbours_and_the_block_wraps():
    labels = np.zeros((4, 5, 6), np.int32)
    labels[0, 0, 0] = 2                      # its neighbours across every face wrap around
    labels[2, 2, 2], labels[2, 2, 3] = 1, 1  # a pair: no speck
    assert specks(labels) == 1
    assert despeckle(labels) == 1 and labels[0, 0, 0] == 0 and labels[2, 2, 2] == labels[2, 2, 3] == 1


def test_a_clean_volume_and_a_memory_map_on_disk(tmp_path):
    clean = np.zeros((6, 6, 6), np.uint8)
    clean[:, :3] = 1
    assert despeckle(clean) == 0
    on_disk = np.lib.format.open_memmap(tmp_path / "v.npy", "w+", np.uint8, (6, 6, 6))
    on_disk[:] = clean
    on_disk[3, 4, 4] = 1
    assert despeckle(on_disk) == 1
    on_disk.flush()
    np.testing.assert_array_equal(np.load(tmp_path / "v.npy"), clean)


@pytest.mark.parametrize("method", ["ml", "kopf"])
def test_segmented_volumes_have_no_specks_unless_asked(device, method):
    ex = gallery_exemplar("composite4", 64)  # a thin phase: the most specks of the gallery
    kw = dict(method=method, rng=1, device=device, scales=2, neighborhood=5, full_output=True)
    kept = clsolid.synthesize(ex, (20, 20, 20), despeckle=False, **kw)
    cleaned = clsolid.synthesize(ex, (20, 20, 20), **kw)
    assert specks(kept.volume) > 0 and specks(cleaned.volume) == 0
    assert cleaned.params["despeckle"] and cleaned.timings["despeckled"] == int(np.sum(kept.volume != cleaned.volume))
    for phase in np.unique(ex):  # a speck is one voxel: the fractions barely move
        assert abs(np.mean(kept.volume == phase) - np.mean(cleaned.volume == phase)) < 0.01


def test_grey_volumes_and_old_records_are_left_as_they_were(device):
    grey = gallery_exemplar("gravel", 64)[:40, :40]
    res = clsolid.synthesize(grey, (12, 12, 12), rng=1, device=device, scales=2, neighborhood=5, full_output=True)
    assert "despeckled" not in res.timings
    from clsolid.ml.params import MLParams
    from clsolid.search.params import SearchParams

    assert MLParams.from_dict({"neighborhood": 5}).despeckle is False  # a record before the step ran without
    assert SearchParams.from_dict({"method": "kopf"}).despeckle is False
    assert MLParams().despeckle and SearchParams(method="kopf").despeckle
