"""The user's material, not the majority phase: gallery exemplars grown small with the defaults.

Fast checks (32^3, the default 11x11 and 3 scales): phase fractions kept (issue 10's 3
points; the slow tests check its other targets at 48^3), no x<->z mirror image, features as
tall as wide, and every relaxation reproducible by seed. The slow tests also hold kopf, exact and accelerated, to
issue 11's targets on a subset, and that a material does not depend on the grey values its
phases carry (it does today: a strict expected failure). The thesis's form is checked too, so
that these tests are known to fail where the defect is.
"""

import numpy as np
import pytest
from conftest import slow_except

import clsolid
from clsolid.gallery import gallery_exemplar
from clsolid.metrics import mirror_correlation, stretch
from clsolid.ml.params import RELAXATIONS

SHAPE = (32, 32, 32)
FAST: dict = {}
THESIS = dict(relaxation="icm", balance=0.0, slice_layout="aligned", insert_slices=4, likelihood="exact",
              shared_weight=1.0, neighborhood=9, distance="squared")
MATERIALS = ("composite3", "fibres", "porous80")


def phase_error_pp(exemplar: np.ndarray, volume: np.ndarray) -> float:
    """Largest difference, in percentage points, between a phase's fraction in the two."""
    phases = np.union1d(np.unique(exemplar), np.unique(volume))
    return float(100 * max(abs(np.mean(exemplar == p) - np.mean(volume == p)) for p in phases))


@pytest.fixture(scope="module")
def grown(device):
    """Each material grown once per device and seed with the defaults: {(name, seed): (exemplar, volume)}."""
    cache = {}

    def grow(name, seed=1):
        if (name, seed) not in cache:
            ex = gallery_exemplar(name, 64)
            cache[name, seed] = ex, clsolid.synthesize(ex, SHAPE, rng=seed, device=device, **FAST)
        return cache[name, seed]

    return grow


@pytest.mark.slow
@pytest.mark.parametrize("name", MATERIALS)
def test_defaults_keep_every_phase_fraction(grown, name):
    ex, vol = grown(name)
    assert set(np.unique(vol)) <= set(np.unique(ex))  # the exemplar's own phase values
    assert phase_error_pp(ex, vol) <= 3.0, f"{name}: a phase is off by {phase_error_pp(ex, vol):.1f} pp"


@pytest.mark.slow
@pytest.mark.parametrize("name", MATERIALS)
def test_defaults_are_not_their_own_mirror_image(grown, name):
    """The mean over three seeds: one 32^3 block of a material with porous80's correlation
    scatters by 0.09 about 0.10, 0.20 at its 90th percentile (tools/mirror_noise.py --side 32),
    and the defaults' seed 1 gives 0.31 (0.12, 0.05 on seeds 2 and 3); the thesis's form
    gives over 0.3 on fibres (below)."""
    r = np.mean([mirror_correlation(grown(name, seed)[1].astype(float)) for seed in (1, 2, 3)])
    assert r <= 0.2, f"{name}: correlation with the x<->z mirror is {r:.2f} on average"


@pytest.mark.slow
def test_default_features_are_as_tall_as_wide(grown, device):
    """composite3's particles are round. With the defaults the stretch (clsolid.metrics.stretch:
    height over width of the correlation lengths, against the exemplar's) stays within 1.15
    either way in both constrained views; with every window term alike (shared_weight=1, the
    thesis) the y axis the two views share counts twice and the particles grow over 1.3 times
    taller than wide. Seeds 1-3 at 32^3 on PoCL: 0.93-1.04 against 1.38-1.52 (1.17-1.23 with
    shared_profile="line")."""
    ex, vol = grown("composite3")
    every_term = clsolid.synthesize(ex, SHAPE, rng=1, device=device, **FAST, shared_weight=1.0)
    for view, ratio in stretch(ex, vol).items():
        assert 1 / 1.15 <= ratio <= 1.15, f"{view}: features {ratio:.2f} times as tall as the exemplar's"
    assert min(stretch(ex, every_term).values()) > 1.3  # the defect the default fixes is there without it


@pytest.mark.slow
def test_the_thesis_form_collapses_and_mirrors(device):
    """The defect the defaults fix is there in the published form (so the tests above can fail)."""
    ex = gallery_exemplar("fibres", 64)
    vol = clsolid.synthesize(ex, SHAPE, rng=1, device=device, **FAST, **THESIS)
    assert mirror_correlation(vol.astype(float)) > 0.3
    assert phase_error_pp(ex, vol) > 10


@pytest.mark.slow
@pytest.mark.parametrize("relaxation", RELAXATIONS)
def test_every_relaxation_is_reproducible_by_seed(device, relaxation):
    ex = gallery_exemplar("composite3", 64)

    def grow(seed):
        return clsolid.synthesize(ex, (16, 16, 16), rng=seed, device=device, relaxation=relaxation,
                                  neighborhood=5, scales=2)

    a = grow(3)
    np.testing.assert_array_equal(a, grow(3))
    assert np.mean(a != grow(4)) > 0.05


# --------------------------------------------------------------------------- issue 10's targets, 48^3
# Measured with tools/gallery.py (seed 1, 64^2 -> 48^3, defaults; the +in slices left out of
# the scores). A target that the defaults miss is a strict expected failure naming the value.
TARGETS = {  # (exemplar, target): None if met, else why not
    ("composite3", "phase"): None, ("lamellae", "phase"): None, ("fibres", "phase"): None,
    ("composite3", "mirror"): None, ("gravel", "mirror"): None,
    # 0.14 on seed 1 since the shared axis left the windows (shared_weight=0; 0.10 before): seeds 2-6
    # 0.07, 0.06, 0.05, 0.02, -0.01 (docs/choices.md); 0.14 with shared_profile="direction" too
    ("lamellae", "mirror"): "0.14 on seed 1 (shared_weight=0; 0.10 with every term alike); seeds 2-6 met",
    ("composite3", "histogram"): None, ("gravel", "histogram"): None,
    ("composite3", "patch"): None, ("gravel", "patch"): None, ("fibres", "patch"): None,
    ("gravel", "autocorrelation"): None,
    # 0.26 weighted until the decision's exact path went vector-wise (same law, other last bits);
    # 0.34 with plain mismatches, -0.04 squared
    # 0.298 (seed 1) since the +in slices share their crossings (0.30+ before): on the limit, a coin
    # flip by seed (seeds 1-4: worst 0.33); with the shared axis out of the windows 0.36 on seed 1,
    # met on seeds 2, 4 and 6 of 1-6; with the terms weighed by their direction (shared_profile)
    # 0.24 on seed 1, met on seeds 1, 4 and 6 (0.37, 0.35, 0.34 on 2, 3, 5: docs/choices.md)
    ("composite3", "autocorrelation"): None,
    ("fibres", "autocorrelation"): None,  # -0.07/-0.11 at 11x11; 0.28/0.31 at 9x9
    ("hrtem", "histogram"): None, ("hrtem", "mirror"): None,
    ("hrtem", "patch"): None,  # 0.15/0.14 with the fall-off (sigma 3); 0.29/0.37 without
    ("hrtem", "autocorrelation"): None,  # 0.19/0.15
}
LIMITS = {"phase": ("phase_error_pp", 3.0), "mirror": ("mirror_max", 0.1), "histogram": ("histogram_kl", 0.1),
          "patch": ("patch_sw", 0.3), "autocorrelation": ("autocorrelation_l2", 0.3)}


@pytest.fixture(scope="module")
def gallery_runs(device, tool):
    """tools/gallery.py's measurements of one exemplar at 48^3 with the defaults, once per module."""
    gallery, cache = tool("gallery"), {}

    def measured(name, method="ml", **options):
        key = (name, method, tuple(sorted(options.items())))
        if key not in cache:
            cache[key] = gallery.run_one(name, 64, 48, 1, method, options, device)[0]
        return cache[key]

    return measured


def _value(run: dict, key: str) -> float:
    if key in ("phase_error_pp", "mirror_max"):
        return run[key]
    return max(run["scores"][view][key] for view in run["constrained"])


@pytest.mark.slow
@pytest.mark.parametrize("name, target", [
    pytest.param(name, target, marks=[] if why is None else pytest.mark.xfail(strict=True, reason=why))
    for (name, target), why in TARGETS.items()])
def test_issue_10_targets_at_48(gallery_runs, name, target):
    key, limit = LIMITS[target]
    value = _value(gallery_runs(name), key)
    assert value <= limit, f"{name}: {target} {value:.2f} > {limit}"


@pytest.mark.slow
def test_the_fall_off_is_what_keeps_hrtem_patches(gallery_runs):
    """hrtem's patch target (seed 1) is met with the grey exemplars' default fall-off and
    missed without it (every term alike, the thesis): the reason for the default."""
    with_falloff = _value(gallery_runs("hrtem"), "patch_sw")
    without = _value(gallery_runs("hrtem", falloff=0.0), "patch_sw")
    assert with_falloff <= 0.3 < without, (with_falloff, without)
    assert without - with_falloff > 0.1


# --------------------------------------------------------------------------- issue 11's kopf targets, 48^3
# Issue 11 asks kopf for phase fractions within 2 points, histogram <= 0.05, patch and
# autocorrelation <= 0.3 in both constrained views, mirror <= 0.1. Measured with
# tools/gallery.py --method kopf (its default coherence search, and --set search='"exact"'), seed 1,
# 64^2 -> 48^3, with kopf's defaults (the histogram specified after every pass, the phases balanced,
# anchor slices at the coarse levels, the parent square weighed 4x, phases compared by weighted mismatches:
# specify=True, balance=1, insert_spacing=5, parent_weight=4, distance="auto"; the coherence search's first
# pass exhaustive on grey exemplars, exact_passes=None).
KOPF_LIMITS = {**LIMITS, "phase": ("phase_error_pp", 2.0), "histogram": ("histogram_kl", 0.05)}
KOPF_TARGETS = {  # (exemplar, target, search): None if met, else why not
    ("composite3", "phase", "exact"): None, ("composite3", "phase", "coherence"): None,
    ("composite3", "histogram", "exact"): None, ("composite3", "histogram", "coherence"): None,
    ("composite3", "patch", "exact"): None, ("composite3", "patch", "coherence"): None,
    ("composite3", "autocorrelation", "exact"): None, ("composite3", "autocorrelation", "coherence"): None,
    ("composite3", "mirror", "exact"): None, ("composite3", "mirror", "coherence"): None,
    ("composite4", "phase", "exact"): None,
    ("composite4", "phase", "coherence"): None,  # 0.0; 3.5 before the search's phase candidates
    ("composite4", "patch", "exact"): None, ("composite4", "patch", "coherence"): None,  # -0.03; 0.43 before
    ("composite4", "autocorrelation", "exact"): None,  # 0.11; 0.40 before the parent weight and codes
    ("composite4", "autocorrelation", "coherence"): None, ("composite4", "mirror", "exact"): None,
    ("fibres", "phase", "exact"): None, ("fibres", "phase", "coherence"): None,
    ("fibres", "patch", "exact"): None, ("fibres", "patch", "coherence"): None,
    ("fibres", "autocorrelation", "exact"): None,  # 0.28; 0.52 with the parent square weighed 1
    ("fibres", "autocorrelation", "coherence"): None,
    ("fibres", "mirror", "exact"): None, ("fibres", "mirror", "coherence"): None,
    ("gravel", "histogram", "exact"): None, ("gravel", "histogram", "coherence"): None,
    ("gravel", "patch", "exact"): None, ("gravel", "patch", "coherence"): None,
    ("gravel", "autocorrelation", "exact"): None,
    ("gravel", "autocorrelation", "coherence"): None,  # 0.25; 0.36 before the coarser levels searched every site
    ("gravel", "mirror", "exact"): None, ("gravel", "mirror", "coherence"): None,
    ("grass", "autocorrelation", "exact"): None,  # 0.14; 1.17 with the parent square weighed 1
    ("grass", "autocorrelation", "coherence"): None,  # -0.06; 0.23 without the index histogram
    # the index histogram (coherence search only) breaks hrtem's lattice of stripes
    ("hrtem", "autocorrelation", "coherence"): None,  # 0.06; 2.03 without the index histogram
    ("hrtem", "autocorrelation", "exact"): "1.9: a lattice of stripes (docs/gallery.md)",
    ("hrtem", "patch", "coherence"): None,  # 0.07/0.04; 0.50/0.20 without the first pass exhaustive (exact_passes=0)
    ("brick", "patch", "coherence"): None,  # 0.28 (0.24 with exact_passes=0; 0.31 without the index histogram)
    ("porous50", "mirror", "coherence"): None,  # 0.03
    ("channels", "mirror", "coherence"): None,  # 0.03; 0.10 with anchors every 6
    ("lamellae", "mirror", "coherence"): "0.14 (-0.06-0.14 over seeds 1-8, 0.31 at worst with anchors every 6; "
                                         "a real material's 48^3 block: 0.064 +- 0.048, docs/gallery.md)",
}


@pytest.mark.slow
@pytest.mark.parametrize("name, target, search", [
    pytest.param(*key, marks=[] if why is None else pytest.mark.xfail(strict=True, reason=why))
    for key, why in KOPF_TARGETS.items()])
def test_issue_11_kopf_targets_at_48(gallery_runs, name, target, search):
    key, limit = KOPF_LIMITS[target]
    value = _value(gallery_runs(name, "kopf", search=search), key)
    assert value <= limit, f"{name}, {search} search: {target} {value:.2f} > {limit}"


@pytest.mark.slow
def test_the_index_histogram_is_what_breaks_hrtems_lattice(gallery_runs):
    """kopf's coherence search with the index histogram (the default) against without it:
    hrtem's autocorrelation 0.06 against 2.03 (seed 1; docs/choices.md)."""
    key, limit = KOPF_LIMITS["autocorrelation"]
    assert _value(gallery_runs("hrtem", "kopf", search="coherence"), key) <= limit
    assert _value(gallery_runs("hrtem", "kopf", search="coherence", index_histogram=False), key) > 3 * limit


@pytest.mark.slow
def test_the_parent_weight_is_what_keeps_kopfs_grass_blades(gallery_runs):
    """kopf's parent square weighed 4x (the default) against 1 (the thesis's equal weights):
    grass's autocorrelation 0.14 against 1.17 (seed 1, the exact search, as measured)."""
    key, limit = KOPF_LIMITS["autocorrelation"]
    assert _value(gallery_runs("grass", "kopf", search="exact"), key) <= limit
    assert _value(gallery_runs("grass", "kopf", search="exact", parent_weight=1.0), key) > 2 * limit


# --------------------------------------------------------------------------- phases are names, not grey levels
@pytest.mark.slow
def test_a_material_does_not_depend_on_the_values_of_its_phases(device):
    """Which grey value a segmented phase carries is the user's arbitrary choice; the volume's
    statistics should not depend on it. They did while phases were compared as grey levels
    (composite4: C2 0.60 against 0.36 with two values swapped; distance="squared" still does)."""
    from clsolid.api import inserted_slices
    from clsolid.metrics import evaluate

    ex = gallery_exemplar("composite4", 64)
    swapped = np.array([0, 255, 170, 85], np.uint8)[np.searchsorted([0, 85, 170, 255], ex)]
    scores = []
    for exemplar in (ex, swapped):
        res = clsolid.synthesize(exemplar, (48, 48, 48), rng=1, device=device, full_output=True)
        vol = np.asarray(res.volume)
        report = evaluate(exemplar, vol, views=["front", "right"], reference_repeats=3, max_slices=16,
                          exclude=inserted_slices(res.params, vol.shape))
        scores.append(max(report["views"][v]["distances"]["c2_l2"]["score"] for v in ("front", "right")))
    assert abs(scores[0] - scores[1]) <= 0.1, f"C2 {scores[0]:.2f} against {scores[1]:.2f} with the values swapped"


@pytest.mark.parametrize("name, levels, spacing", slow_except([("porous50", 32, 5.0), ("composite4", 32, 5.0),
                                                               ("gravel", 32, 6.0), ("composite3", 2, 6.0)], 0))
def test_slice_spacing_follows_the_exemplar(device, name, levels, spacing):
    """+in slices every 5 voxels on categorical exemplars, every 6 on grey ones (docs/choices.md),
    whole exemplar windows on both; a spacing or piece given is kept."""
    ex = gallery_exemplar(name, 64)
    kw = dict(rng=1, device=device, scales=1, neighborhood=3, levels=levels, max_sweeps=1, full_output=True)
    params = clsolid.synthesize(ex, (8, 8, 8), **kw).params
    assert (params["insert_spacing"], params["insert_piece"]) == (spacing, 0)
    params = clsolid.synthesize(ex, (8, 8, 8), insert_spacing=9, insert_piece=4, **kw).params
    assert (params["insert_spacing"], params["insert_piece"]) == (9.0, 4)
