"""Wei-Levoy on structure tensor fields (clsolid.search.tensorfield): the device against the
float64 reference, seeds, exemplar tensors only, the causal wavefronts, and an orientation
structure kept."""

import numpy as np
import pytest

from clsolid.errors import InputError
from clsolid.gallery import gallery_exemplar
from clsolid.metrics.axes import correlation_length
from clsolid.metrics.orientation import OrientationField, orientation_correlation
from clsolid.search.match import causal_weights, square_offsets
from clsolid.search.tensorfield import _waves, synthesize_field, tensor_pyramid
from clsolid.tensor import coherence, orientation, structure_tensor


@pytest.fixture(scope="module")
def hrtem_field():
    return structure_tensor(gallery_exemplar("hrtem", 64).astype(np.float64))


def _lengths(field, periodic):
    f = OrientationField(orientation(field)[None], coherence(field)[None])
    return [correlation_length(orientation_correlation(f, a, field.shape[a - 1] // 2, periodic)) for a in (1, 2)]


@pytest.mark.parametrize("scheme, metric", [("random", "ED"), ("causal", "SO"), ("random", "LE")])
def test_the_device_grows_the_references_field(device, hrtem_field, scheme, metric):
    kw = dict(neighborhood=5, levels=2, iterations=1, scheme=scheme, metric=metric, seed=3)
    ref = synthesize_field(hrtem_field[:32, :32], (16, 16), device="reference", **kw)
    got = synthesize_field(hrtem_field[:32, :32], (16, 16), device=device, **kw)
    # float32 sums can swap two near-equal matches, and every pixel after reads the swap
    assert np.mean(np.all(ref == got, axis=-1)) >= 0.95


def test_a_seed_gives_one_field_of_exemplar_tensors(device, hrtem_field):
    kw = dict(neighborhood=5, levels=2, iterations=1, device=device)
    a = synthesize_field(hrtem_field, (24, 24), seed=1, **kw)
    assert np.array_equal(a, synthesize_field(hrtem_field, (24, 24), seed=1, **kw))
    assert not np.array_equal(a, synthesize_field(hrtem_field, (24, 24), seed=2, **kw))
    finest = {tuple(t) for t in tensor_pyramid(hrtem_field, 2)[0].reshape(-1, 3).tolist()}
    assert {tuple(t) for t in a.reshape(-1, 3).tolist()} <= finest


@pytest.mark.parametrize("scheme", ["random", "causal"])
def test_the_grown_field_keeps_the_orientation_structure(device, hrtem_field, scheme):
    """The orientation's own correlation length: the exemplar's about 3.5 pixels, a shuffled
    field's 0.5; the grown field's near the exemplar's (0.8-1.0 of it measured)."""
    out = synthesize_field(hrtem_field, (48, 48), neighborhood=5, levels=2, iterations=2, scheme=scheme, seed=1,
                           device=device)
    want = _lengths(hrtem_field, periodic=False)
    got = _lengths(out, periodic=True)
    shuffled = _lengths(np.random.default_rng(0).permutation(hrtem_field.reshape(-1, 3)).reshape(hrtem_field.shape),
                        periodic=False)
    assert all(0.6 * w <= g <= 1.5 * w for g, w in zip(got, want)), (got, want)
    assert all(g > 3 * s for g, s in zip(got, shuffled))


def test_a_causal_pixel_comes_after_what_it_reads():
    shape, k = (10, 12), 5
    waves = _waves(shape, k // 2)
    wave_of = np.empty(shape[0] * shape[1], np.int64)
    for i, pixels in enumerate(waves):
        wave_of[pixels] = i
    assert np.array_equal(np.sort(np.concatenate(waves)), np.arange(shape[0] * shape[1]))
    reads = square_offsets(k)[causal_weights(k) > 0]
    for r in range(shape[0]):
        for c in range(shape[1]):
            for dr, dc in reads:
                rr, cc = r + dr, c + dc
                if 0 <= rr < shape[0] and 0 <= cc < shape[1]:  # a read that does not wrap
                    assert wave_of[rr * shape[1] + cc] < wave_of[r * shape[1] + c]


@pytest.mark.parametrize("kw, words", [
    ({"scheme": "spiral"}, "scheme"),
    ({"shape": (3, 40)}, "shape"),
    ({"exemplar_field": np.zeros((8, 8))}, "tensors"),
    ({"metric": "XY"}, "metric"),
])
def test_bad_arguments_are_refused(hrtem_field, kw, words):
    args = {"exemplar_field": hrtem_field, "shape": (16, 16), "device": "reference", **kw}
    with pytest.raises(InputError, match=words):
        synthesize_field(**args)
