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


def test_a_scale_too_large_to_replay_is_forecast_on_a_smaller_block(device, monkeypatch):
    """Above REPLAY_TERMS the replay would cost more than the run (NumPy, one core): the
    finest scale is not replayed; a smaller block with the same structure is, and its
    visits, scaled up, are close to the run's. The volume is the same."""
    from clsolid.ml import driver, forecast

    made, proxied, etas = [], [], []

    def spy(*args, **kwargs):
        made.append(forecast_visits(*args, **kwargs))
        return made[-1]

    def proxy_spy(*args, **kwargs):
        proxied.append(forecast.proxy_visits(*args, **kwargs))
        return proxied[-1]

    monkeypatch.setattr(driver, "forecast_visits", spy)
    monkeypatch.setattr(driver, "proxy_visits", proxy_spy)
    # Spacing 6 (porous80's default is 5): on a block this small the proxy's slice count
    # rounds differently at 5, and it forecasts a fourth sweep where the run stops after three.
    kw = dict(neighborhood=5, scales=2, rng=2, device=device, insert_spacing=6)
    ex = gallery_exemplar("porous80", 64)
    want = clsolid.synthesize(ex, (24, 32, 40), **kw)
    monkeypatch.setattr(forecast, "REPLAY_TERMS", 16**3 * 44)  # the coarse 12x16x20 scale (44 neighbours) only
    got = clsolid.synthesize(ex, (24, 32, 40), progress=lambda i: etas.append(i.eta), full_output=True, **kw)
    assert len(made) == 1 and len(proxied) == 1  # the coarse scale was replayed, the finest on a proxy
    run = got.timings["scales"][1]["visited"]
    assert len(proxied[0]) == len(run)
    assert all(abs(p - r) <= 0.1 * r for p, r in zip(proxied[0], run))
    assert (got.volume == want).all()
    assert etas[-1] == 0.0
