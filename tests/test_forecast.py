"""The ETA's forecast (clsolid.ml.forecast): a scale's sweeps and visits replayed from the
temperatures alone, against what the run then does."""

import pytest

import clsolid
from clsolid.gallery import gallery_exemplar
from clsolid.ml.forecast import forecast_visits


@pytest.mark.parametrize("options", [{}, {"relaxation": "icm"}, {"inherited": "fixed", "views": 3},
                                     {"sweeps": 3}])
def test_forecast_replays_every_scales_sweeps_and_visits(device, monkeypatch, options):
    """The temperatures do not depend on the labels: the forecast made at a scale's start
    is the sweeps and visits the run then makes, and the ETA is 0 exactly at the end."""
    from clsolid.ml import driver

    made, etas = [], []

    def spy(*args, **kwargs):
        made.append(forecast_visits(*args, **kwargs))
        return made[-1]

    monkeypatch.setattr(driver, "forecast_visits", spy)
    res = clsolid.synthesize(gallery_exemplar("porous80", 64), (16, 16, 16), neighborhood=5, scales=2,
                             rng=2, device=device, full_output=True, progress=lambda i: etas.append(i.eta),
                             **options)
    assert made == [scale["visited"] for scale in res.timings["scales"]]
    assert etas[-1] == 0.0 and all(e > 0 for e in etas[len(made[0]):-1])


def test_a_scale_too_large_to_replay_is_not_replayed(device, monkeypatch):
    """Above REPLAY_TERMS the replay would cost more than the run (NumPy, one core): the
    finest scale is not replayed, its ETA is extrapolated, and the volume is the same."""
    from clsolid.ml import driver, forecast

    made, etas = [], []

    def spy(*args, **kwargs):
        made.append(forecast_visits(*args, **kwargs))
        return made[-1]

    monkeypatch.setattr(driver, "forecast_visits", spy)
    kw = dict(neighborhood=5, scales=2, rng=2, device=device)
    ex = gallery_exemplar("porous80", 64)
    want = clsolid.synthesize(ex, (16, 16, 16), **kw)
    monkeypatch.setattr(forecast, "REPLAY_TERMS", 8**3 * 100)  # the coarse 8^3 scale (45 neighbours) only
    got = clsolid.synthesize(ex, (16, 16, 16), progress=lambda i: etas.append(i.eta), **kw)
    assert len(made) == 1  # the coarse scale was replayed, the finest was not
    assert (got == want).all()
    assert etas[-1] == 0.0

