"""The ETA's forecast (clsolid.ml.forecast): a scale's sweeps and visits replayed from the
temperatures alone, against what the run then does."""

import numpy as np
import pytest
from conftest import slow_except

import clsolid
from clsolid.gallery import gallery_exemplar
from clsolid.ml.forecast import forecast_visits
from clsolid.ml.params import MLParams


@pytest.mark.parametrize("options", slow_except([{}, {"relaxation": "icm"}, {"inherited": "fixed", "views": 3},
                                                 {"sweeps": 3}, {"polish_sweeps": 2},
                                                 {"polish_sweeps": 1, "inherited": "fixed"}], 0, 4))
def test_forecast_replays_every_scales_sweeps_and_visits(device, monkeypatch, options):
    """The temperatures do not depend on the labels: the forecast made at a scale's start
    is the sweeps and visits the run then makes (its polish sweeps too), and the ETA is 0
    exactly at the end."""
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
    kw = dict(neighborhood=5, scales=2, rng=2, device=device, insert_spacing=6, views=2)
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


def _scale_stub(level: int, side: int):
    from types import SimpleNamespace

    return SimpleNamespace(level=level, shape=(side,) * 3, n_sites=10_000, patches=np.zeros((120, 1)),
                           per_view=False)


@pytest.mark.parametrize("searching_sweeps, want", [(1, 10.0), (2, 5.0 + 30.0)])
def test_eta_times_the_sweeps_to_come_without_the_projected_search(searching_sweeps, want):
    """A sweep that searches projected candidates costs several that do not: after it, the ETA
    counts the sweeps still to come at its rate less the search, and less what else such a
    sweep costs more (learnt at the scale before: here its rest cost twice a plain sweep's)."""
    from clsolid.ml.driver import _Clock

    params = MLParams(likelihood="pruned", prune_projected=24, prune_projected_sweeps=searching_sweeps)
    coarse, fine = _scale_stub(1, 8), _scale_stub(0, 16)
    clock = _Clock([coarse, fine], params)
    clock.plan(1, [100, 100, 100])
    clock.eta(0, 1, 3.0, 100, coarse, 1.0, 2.0, 0.0, 2, searched=2.0)  # 1 s besides the search ...
    clock.eta(0, searching_sweeps + 1, 0.5, 100, coarse, 1.0, 2.0, 0.0, 1)  # ... against 0.5 s without
    clock.plan(1, [1000, 1000, 1000])
    # 30 s, 20 of them searching: the next sweeps (1000 visits each) cost (30 - 20) / 2 = 5 s each
    assert clock.eta(1, 1, 30.0, 1000, fine, 1.0, 2.0, 0.0, 2, searched=20.0) == pytest.approx(want)
    # without a search, every sweep to come at this one's rate
    assert clock.eta(1, 2, 6.0, 1000, fine, 1.0, 2.0, 0.0, 1) == pytest.approx(6.0)


def test_eta_counts_the_polish_sweeps_where_nothing_is_forecast():
    """Annealing (no forecast): the sweeps the global temperature still needs, extrapolated from
    its fall, then the polish sweeps, each at the last sweep's time."""
    from clsolid.ml.driver import _Clock

    fine = _scale_stub(0, 16)
    clock = _Clock([fine], MLParams(relaxation="annealing", polish_sweeps=2))
    # halved by the last sweep, 4 times the target: 2 sweeps more, then the 2 polish sweeps
    assert clock.eta(0, 3, 1.5, 1000, fine, 4.0, 8.0, 1.0, 10, polish_left=2) == pytest.approx(6.0)
    assert clock.eta(0, 6, 1.5, 1000, fine, 0.5, 1.0, 1.0, 0, polish_left=1) == pytest.approx(1.5)  # polishing
    assert clock.eta(0, 7, 1.5, 1000, fine, 0.25, 0.5, 1.0, 0, polish_left=0) == 0.0
