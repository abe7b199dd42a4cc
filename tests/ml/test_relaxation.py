"""Stochastic relaxations (Gibbs, annealing) and the balance term: kernels against the
float64 reference, determinism by seed, the law of the Gibbs draws, parameters and CLI."""

import json

import numpy as np
import pytest
from conftest import random_state, slow_except

import clsolid
from clsolid import InputError, metrics
from clsolid.gallery import gallery_exemplar
from clsolid.balance import score_stride
from clsolid.ml.opencl import CLBackend
from clsolid.ml.model import build_scale
from clsolid.ml.params import MLParams
from clsolid.core.philox import TAG_INIT, relax_tag, unit_float, voxel_words
from clsolid.ml.reference import ReferenceBackend, normalise, relax
from clsolid.ml.driver import label_fractions, run_ml

# Whole runs without the balance: its bias is fitted to the scores of each set, float32 on
# the device and float64 in the reference, and a near-flat fit turns their last-bit
# differences into different biases, then different draws. The balance is compared one
# step at a time (the scores it sees) and by its outcome (test_balance_runs_alike).
CASES = [  # (relaxation, neighborhood, views, heuristic, shape, extra parameters)
    ("gibbs", 3, 2, "h2-product", (12, 12, 12), {}),
    ("gibbs", 3, 3, "h2-min", (12, 12, 12), {}),
    ("gibbs", 3, 3, "h1-mean", (8, 10, 12), {}),
    ("annealing", 5, 2, "h2-product", (12, 12, 12), dict(sweeps=3)),
    ("annealing", 3, 3, "h1-mean", (8, 10, 12), dict(sweeps=3)),
    ("annealing", 3, 2, "h1-lowest", (12, 12, 12), dict(sweeps=3, anneal_start=0.5, anneal_cooling=0.5)),
    ("icm", 3, 2, "h2-product", (12, 12, 12), {}),
    ("gibbs", 3, 2, "h1-highest", (12, 12, 12), {}),
    ("annealing", 3, 2, "h2-max", (12, 12, 12), dict(sweeps=3)),
    ("annealing", 3, 2, "h2-product", (12, 12, 12), dict(sweeps=3, polish_sweeps=1)),
]


@pytest.mark.parametrize("relaxation, k, views, heuristic, shape, extra", slow_except(CASES, 0))
def test_whole_run_matches_reference(device, small_labels, relaxation, k, views, heuristic, shape, extra):
    params = MLParams(neighborhood=k, views=views, heuristic=heuristic, scales=2, insert_slices=1,
                      relaxation=relaxation, balance=0.0, **extra)
    ref, ref_t, _ = run_ml(small_labels, shape, params, 11, ReferenceBackend())
    got, got_t, _ = run_ml(small_labels, shape, params, 11, CLBackend(device))
    agree = np.mean(ref == got)
    assert agree >= 0.99, f"only {agree:.3%} of voxels agree with the float64 reference"
    assert [s["sweeps"] for s in got_t["scales"]] == [s["sweeps"] for s in ref_t["scales"]]


@pytest.mark.parametrize("relaxation", slow_except(["icm", "gibbs", "annealing"], 1))
def test_balance_runs_alike(device, small_labels, relaxation):
    """With the balance, the device and the reference both end at the exemplar's label
    fractions, where the same run without it does not."""
    extra = dict(sweeps=4) if relaxation == "annealing" else {}
    labels = np.unique(small_labels)
    want = label_fractions(small_labels, labels)
    err = {}
    for beta in (0.0, 1.0):
        params = MLParams(neighborhood=3, scales=2, relaxation=relaxation, balance=beta, **extra)
        for name, backend in (("ref", ReferenceBackend()), ("cl", CLBackend(device))):
            vol = run_ml(small_labels, (12, 12, 12), params, 11, backend)[0]
            err[name, beta] = np.abs(label_fractions(vol, labels) - want).max()
    # Annealing's accept/reject is not a draw from the biased law the balance fits: it only
    # halves the error there, hence the looser bound.
    bound = 0.06 if relaxation == "annealing" else 0.02
    assert err["ref", 1.0] < bound and err["cl", 1.0] < bound, err
    assert min(err["ref", 0.0], err["cl", 0.0]) > 1.5 * max(err["ref", 1.0], err["cl", 1.0]), err


@pytest.mark.slow
@pytest.mark.parametrize("name, balance, bound", [("porous50", 0.0, 0.5), ("composite3", 0.0, 0.5),
                                                  ("porous50", 1.0, 0.6), ("composite3", 1.0, 1.0)])
def test_polish_sweeps_clear_isolated_voxels(device, name, balance, bound):
    """Gibbs volumes hold voxels that no face neighbour is like; an argmax sweep after the
    finest scale's relaxation clears most of them. With the balance on, as by default, fewer:
    to keep the phase fractions it flips some of the least certain voxels, isolated or not."""
    exemplar = gallery_exemplar(name, 64)
    isolated, fractions = np.zeros(2), np.unique(exemplar, return_counts=True)[1] / exemplar.size
    for seed in (1, 2, 3):  # a few dozen such voxels a block: summed over seeds
        for polish in (0, 1):
            res = clsolid.synthesize(exemplar, (24, 24, 24), neighborhood=5, scales=2, balance=balance, views=2,
                                     polish_sweeps=polish, rng=seed, device=device, output="labels",
                                     despeckle=False)  # the polish alone, before the last step clears the rest
            isolated[polish] += metrics.isolated_fraction(res)
            if balance:
                assert np.abs(np.bincount(res.ravel(), minlength=fractions.size) / res.size - fractions).max() < 0.02
    assert isolated[1] < bound * isolated[0], isolated


def _fragile(relaxation, code, logl, labels, x, words, t_in, bias, eps=1e-3, tries=4):
    """Voxels whose reference decision changes when the log LCPDFs move by ~eps (float32's
    error is far smaller): near a draw's, an acceptance's or a tie's boundary."""
    want = relax(relaxation, code, logl, labels, x, words, t_in, bias)
    rng = np.random.default_rng(0)
    out = np.zeros(want.shape, bool)
    for _ in range(tries):
        moved = logl + rng.uniform(-eps, eps, logl.shape)
        out |= relax(relaxation, code, moved, labels, x, words, t_in, bias) != want
    return out


@pytest.mark.each_device
# the default run keeps every heuristic with gibbs draws, and annealing with the default heuristic
@pytest.mark.parametrize("relaxation, heuristic", slow_except(
    [(r, h) for r in ("gibbs", "annealing") for h in ("h2-product", "h2-min", "h2-max", "h1-lowest", "h1-highest",
                                                      "h1-mean")], 0, 1, 2, 3, 4, 5, 6))
def test_one_step_decides_as_the_reference(device, small_labels, relaxation, heuristic):
    """Fixed state, one conflict-free set per launch: every voxel not at a boundary matches."""
    shape = (16, 16, 16)
    params = MLParams(neighborhood=5, views=3, scales=1, heuristic=heuristic, relaxation=relaxation)
    model = build_scale(small_labels, shape, params, 0)
    vol, temp = random_state(model, seed=2)
    if relaxation == "annealing":
        temp[:] = 0.0  # the driver's state under annealing
    bias = np.linspace(-0.5, 0.5, model.labels.size)
    seed, tag, t_in = 5, relax_tag(0, 3), 0.7
    cl_b, ref = CLBackend(device), ReferenceBackend()
    agree, n, fragile = 0, 0, 0
    for colour in range(3):
        voxels = np.flatnonzero(model.colour.ravel() == colour)
        for b in (cl_b, ref):
            b.start_scale(model, vol, temp, params)
            b.start_sweep(seed, tag, t_in, bias)
        logl = ref.lcpdf(voxels)
        z, y, x = np.unravel_index(voxels, shape)
        near = _fragile(relaxation, params.heuristic_code, logl, model.labels, vol.ravel()[voxels],
                        voxel_words(seed, z, y, x, tag), t_in, bias)
        for b in (cl_b, ref):
            b.update(voxels)
        got, want = cl_b.volume().ravel()[voxels], ref.volume().ravel()[voxels]
        np.testing.assert_array_equal(got[~near], want[~near])
        rows = voxels[voxels % score_stride(shape) == 0] // score_stride(shape)  # what the balance sees
        np.testing.assert_allclose(cl_b.scores()[rows], ref.scores()[rows], rtol=1e-4, atol=2e-3)
        agree, n, fragile = agree + np.sum(got == want), n + voxels.size, fragile + near.sum()
        np.testing.assert_allclose(cl_b.temperature(), ref.temperature(), atol=1e-6)
    assert fragile < 0.05 * n and agree >= 0.98 * n
    changed = np.mean(ref.volume() != vol)
    assert changed > 0.01  # the step did something


def _run(device, labels, seed, relaxation, **backend):
    params = MLParams(neighborhood=5, scales=2, relaxation=relaxation, sweeps=3)
    return run_ml(labels, (12, 16, 20), params, seed, CLBackend(device, **backend))[0]


@pytest.mark.parametrize("relaxation", slow_except(["gibbs", "annealing"], 0))
def test_same_seed_same_volume_whatever_the_work_group(device, small_labels, relaxation):
    a = _run(device, small_labels, 3, relaxation)
    b = _run(device, small_labels, 3, relaxation, local_size=1, voxels_per_item=2, max_batch=97)
    np.testing.assert_array_equal(a, b)
    c = _run(device, small_labels, 4, relaxation)
    assert np.mean(a != c) > 0.2  # stochastic relaxations keep the seeds apart


@pytest.mark.each_device
def test_gibbs_draws_follow_the_combined_lcpdf(device, small_labels):
    """Repeated Gibbs updates of one set on a fixed state: label frequencies match the
    normalised product of the views' LCPDFs (a pooled chi-square, loose bound)."""
    shape = (12, 12, 12)
    params = MLParams(neighborhood=3, scales=1, relaxation="gibbs", bandwidth=3.0)
    model = build_scale(small_labels, shape, params, 0)
    vol, temp = random_state(model, seed=4)
    voxels = np.flatnonzero(model.colour.ravel() == 0)
    cl_b, ref = CLBackend(device), ReferenceBackend()
    for b in (cl_b, ref):
        b.start_scale(model, vol, temp, params)
    p = np.exp(normalise(ref.lcpdf(voxels).sum(axis=0)))  # (m, L)
    draws = 300
    counts = np.zeros_like(p)
    for sweep in range(1, draws + 1):
        # a voxel's own value and temperature never enter its LCPDF: every draw sees the same law
        cl_b.start_sweep(9, relax_tag(0, sweep), 1.0, np.zeros(model.labels.size))
        cl_b.update(voxels)
        got = cl_b.volume().ravel()[voxels]
        counts[np.arange(voxels.size), np.searchsorted(model.labels, got)] += 1
    expected = draws * p
    assert (counts[expected == 0] == 0).all()  # nothing drawn outside the support
    big = expected >= 5
    rest_obs, rest_exp = counts[~big].sum(), expected[~big].sum()
    chi2 = np.sum((counts[big] - expected[big]) ** 2 / expected[big]) + (rest_obs - rest_exp) ** 2 / max(rest_exp, 1)
    dof = big.sum() - voxels.size + 1
    assert dof > 50  # the LCPDFs are spread enough for the test to mean something
    assert chi2 / dof < 1.3, f"chi2/dof = {chi2 / dof:.2f}"  # ~1 +- 0.02 for a correct sampler
    # an argmax would fail it: the ICM choice puts all the mass on one label
    icm = np.zeros_like(p)
    icm[np.arange(voxels.size), p.argmax(axis=1)] = draws
    assert np.sum((icm[big] - expected[big]) ** 2 / expected[big]) / dof > 10


def test_annealing_schedule_and_visits(device, small_labels):
    params = MLParams(neighborhood=3, scales=2, relaxation="annealing", insert_slices=1)
    _, timings, _ = run_ml(small_labels, (8, 8, 8), params, 1, CLBackend(device))
    for s in timings["scales"]:
        assert s["initial_temperature"] == 1.0
        assert s["sweeps"] == 14  # 0.8^14 <= 5 % < 0.8^13
        np.testing.assert_allclose(s["temperatures"], 0.8 ** np.arange(1, 15))
        assert s["visited"] == [int(np.prod(s["shape"]))] * 14  # trusted voxels too
    fixed = MLParams(neighborhood=3, scales=2, relaxation="annealing", inherited="fixed", sweeps=2)
    _, timings, _ = run_ml(small_labels, (8, 8, 8), fixed, 1, CLBackend(device))
    assert [s["sweeps"] for s in timings["scales"]] == [2, 2]
    assert timings["scales"][1]["visited"][0] < 8**3 * 7 / 8  # inherited and inserted voxels skipped


def test_fixed_sweeps_apply_to_icm(device, small_labels):
    params = MLParams(neighborhood=3, scales=1, sweeps=3, stop_fraction=0.1)
    _, timings, _ = run_ml(small_labels, (8, 8, 8), params, 1, CLBackend(device))
    assert timings["scales"][0]["sweeps"] == 3


def test_the_thesis_form_ignores_the_annealing_schedule(device, small_labels):
    """ICM without balance on aligned slices (the thesis's form) does not see the annealing knobs."""
    defaults = MLParams()
    assert (defaults.relaxation, defaults.balance, defaults.slice_layout) == ("gibbs", 1.0, "staggered")
    thesis = dict(neighborhood=3, scales=2, relaxation="icm", balance=0.0, slice_layout="aligned")
    a = run_ml(small_labels, (8, 10, 12), MLParams(**thesis), 5, CLBackend(device))[0]
    b = run_ml(small_labels, (8, 10, 12), MLParams(**thesis, anneal_start=3.0, anneal_cooling=0.5), 5,
               CLBackend(device))[0]
    np.testing.assert_array_equal(a, b)


def test_upsampling_follows_the_relaxation_unless_given():
    """1/8 for ICM and Gibbs (thesis), 8/8 for annealing (TIP14), an explicit choice wins."""
    assert MLParams().upsampling == MLParams(relaxation="gibbs").upsampling == "1/8"
    assert MLParams(relaxation="annealing").upsampling == "8/8"
    assert MLParams(relaxation="annealing", upsampling="1/8").upsampling == "1/8"
    assert MLParams(upsampling="8/8").to_dict()["upsampling"] == "8/8"


def test_relaxation_tags_and_floats():
    assert relax_tag(0, 1) == (1 << 28) | 1 and relax_tag(2, 5) == (1 << 28) | (2 << 20) | 5
    assert TAG_INIT not in {relax_tag(lv, s) for lv in range(8) for s in range(64)}
    with pytest.raises(ValueError):
        relax_tag(0, 1 << 20)
    u = np.array([0, 255, 256, 0xFFFFFFFF], np.uint32)
    assert unit_float(u).tolist() == [0.0, 0.0, 2.0**-24, 1.0 - 2.0**-24]
    assert np.float32(unit_float(u)[-1]) < 1.0  # exact in float32 too


@pytest.mark.parametrize("kwargs, word", [
    (dict(relaxation="metropolis"), "relaxation"), (dict(anneal_start=0), "anneal_start"),
    (dict(anneal_start=float("inf")), "anneal_start"), (dict(anneal_cooling=1.0), "anneal_cooling"),
    (dict(anneal_cooling=0), "anneal_cooling"), (dict(sweeps=0), "sweeps"), (dict(sweeps=2.5), "sweeps"),
    (dict(balance=-1), "balance"), (dict(balance=1.5), "balance"), (dict(balance=True), "balance"),
    (dict(balance="1"), "balance"),
])
def test_bad_relaxation_parameters_name_themselves(kwargs, word):
    with pytest.raises(InputError, match=word):
        MLParams(**kwargs)


@pytest.mark.parametrize("argv, expected", [
    ([], dict(relaxation="gibbs", anneal_start=1.0, anneal_cooling=0.8, sweeps=None, balance=1.0, upsampling="1/8",
              slice_layout="staggered")),
    (["--relaxation", "icm", "--balance", "0", "--slice-layout", "aligned"],
     dict(relaxation="icm", balance=0.0, slice_layout="aligned")),
    (["--relaxation", "annealing", "--anneal-start", "2", "--anneal-cooling", "0.5", "--sweeps", "2"],
     dict(relaxation="annealing", anneal_start=2.0, anneal_cooling=0.5, sweeps=2, upsampling="8/8")),
    (["--relaxation", "annealing", "--upsampling", "1/8"], dict(relaxation="annealing", upsampling="1/8")),
    (["--relaxation", "gibbs", "--balance", "0.5"], dict(relaxation="gibbs", balance=0.5)),
])
def test_cli_relaxation_reaches_the_sidecar(tmp_path, device, argv, expected):
    from clsolid.cli import main

    fast = ["--shape", "8", "8", "8", "--neighborhood", "3", "--scales", "2", "--levels", "8", "--seed", "3", "-q"]
    assert main(["synth", "-o", str(tmp_path / "v.npy"), *fast, *argv]) == 0
    meta = json.loads((tmp_path / "v.json").read_text())
    assert {k: meta["params"][k] for k in expected} == expected
    if "--sweeps" in argv:
        assert [s["sweeps"] for s in meta["timings"]["scales"]] == [2, 2]


def test_cli_refuses_a_bad_relaxation(tmp_path, capsys):
    from clsolid.cli import EXIT_USAGE, main

    with pytest.raises(SystemExit) as exit_info:
        main(["synth", "-o", str(tmp_path / "v.npy"), "--relaxation", "metropolis"])
    assert exit_info.value.code == EXIT_USAGE
    assert "--relaxation: invalid choice" in capsys.readouterr().err
