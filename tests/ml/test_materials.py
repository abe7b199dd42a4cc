"""The user's material, not the majority phase: gallery exemplars grown with the defaults.

At 32^3 (the default 11x11 and 3 scales): phase fractions kept within the gallery's 3
points, no x<->z mirror image, features as tall as wide, and every relaxation reproducible
by seed. At 48^3: the gallery's targets (docs/design.md describes them above its first
section), kopf, exact and accelerated, held to its stricter ones on a subset, and a material
that does not depend on the grey values its phases carry. The thesis's form is checked too,
so that these tests are known to fail where the defect is. All but the slice spacing are
slow-only (whole runs).
"""

import numpy as np
import pytest
from conftest import slow_except

import clsolid
from clsolid.gallery import gallery_exemplar, gallery_info
from clsolid.metrics import mirror_correlation, stretch
from clsolid.ml.params import RELAXATIONS

SHAPE = (32, 32, 32)
FAST: dict = {}
THESIS = dict(views=2, relaxation="icm", balance=0.0, slice_layout="aligned", insert_slices=4, likelihood="exact",
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
    """The mean over three seeds, at most 0.2: one 32^3 block of a material with porous80's
    correlation scatters about 0.10 with its 90th percentile at 0.20 (tools/mirror_noise.py
    --side 32), so one seed alone cannot tell; the thesis's form gives over 0.3 on fibres
    (below)."""
    r = np.mean([mirror_correlation(grown(name, seed)[1].astype(float)) for seed in (1, 2, 3)])
    assert r <= 0.2, f"{name}: correlation with the x<->z mirror is {r:.2f} on average"


@pytest.mark.slow
def test_default_features_are_as_tall_as_wide(grown, device):
    """composite3's particles are round. With the defaults the stretch (clsolid.metrics.stretch:
    height over width of the correlation lengths, against the exemplar's) stays within 1.2
    either way at this 32^3 size (1.11-1.13 at 48^3 in the gallery); with two views and every
    window term alike (shared_weight=1, the thesis) the y axis the two views share counts twice
    and the particles grow over 1.3 times taller than wide (docs/design.md#three-views,
    docs/design.md#shared-axis)."""
    ex, vol = grown("composite3")
    every_term = clsolid.synthesize(ex, SHAPE, rng=1, device=device, **FAST, views=2, shared_weight=1.0)
    for view, ratio in stretch(ex, vol).items():
        assert 1 / 1.2 <= ratio <= 1.2, f"{view}: features {ratio:.2f} times as tall as the exemplar's"
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


# --------------------------------------------------------------------------- the gallery's targets, 48^3
# As tools/gallery.py measures them (seed 1, 64^2 -> 48^3, defaults; the +in slices left out of
# the scores). A target that the defaults miss is a strict expected failure naming the value.
TARGETS = {  # (exemplar, target): None if met, else why not
    ("composite3", "phase"): None, ("lamellae", "phase"): None, ("fibres", "phase"): None,
    ("composite3", "mirror"): None, ("gravel", "mirror"): None,
    # with the shared axis out of the windows (docs/design.md#shared-axis); met on other seeds
    ("lamellae", "mirror"): "0.14 on seed 1 with the shared axis out of the windows; met on other seeds",
    ("composite3", "histogram"): None, ("gravel", "histogram"): None,
    ("composite3", "patch"): None, ("gravel", "patch"): None, ("fibres", "patch"): None,
    ("gravel", "autocorrelation"): None,
    # met on seed 1, missed on some others (docs/design.md#shared-profile)
    ("composite3", "autocorrelation"): None,
    ("fibres", "autocorrelation"): None,  # the 11x11 window carries it (docs/design.md#window-size)
    ("hrtem", "histogram"): None, ("hrtem", "mirror"): None,
    ("hrtem", "patch"): None,  # the fall-off keeps it (test_the_fall_off_is_what_keeps_hrtem_patches)
    ("hrtem", "autocorrelation"): None,
}
LIMITS = {"phase": ("phase_error_pp", 3.0), "mirror": ("mirror_max", 0.1), "histogram": ("histogram_kl", 0.1),
          "patch": ("patch_sw", 0.3), "autocorrelation": ("autocorrelation_l2", 0.3)}


@pytest.fixture(scope="module")
def gallery_runs(device, tool):
    """tools/gallery.py's measurements of one exemplar at 48^3 with the defaults and the views the
    material calls for (two for layered and directional ones, docs/design.md#three-views), once
    per module."""
    gallery, cache = tool("gallery"), {}

    def measured(name, method="ml", **options):
        options = {"views": gallery_info(name).views, **options}
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
def test_defaults_meet_the_gallery_targets_at_48(gallery_runs, name, target):
    key, limit = LIMITS[target]
    value = _value(gallery_runs(name), key)
    assert value <= limit, f"{name}: {target} {value:.2f} > {limit}"


@pytest.mark.slow
def test_the_fall_off_is_what_keeps_hrtem_patches(gallery_runs):
    """hrtem's patch target is met with the grey exemplars' default fall-off and missed
    without it (every term alike, the thesis): the reason for the default
    (docs/design.md#falloff)."""
    with_falloff = _value(gallery_runs("hrtem"), "patch_sw")
    without = _value(gallery_runs("hrtem", falloff=0.0), "patch_sw")
    assert with_falloff <= 0.3 < without, (with_falloff, without)
    assert without - with_falloff > 0.1


# --------------------------------------------------------------------------- kopf's stricter targets, 48^3
# kopf is held to phase fractions within 2 points and histogram <= 0.05 (the others as above:
# patch and autocorrelation <= 0.3 in both constrained views, mirror <= 0.1). As measured by
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
    ("composite4", "phase", "coherence"): None,  # the phase candidates (docs/design.md#coherence-levels)
    ("composite4", "patch", "exact"): None, ("composite4", "patch", "coherence"): None,
    ("composite4", "autocorrelation", "exact"): None,  # docs/design.md#kopf-parent-weight and #phase-codes
    ("composite4", "autocorrelation", "coherence"): None, ("composite4", "mirror", "exact"): None,
    ("fibres", "phase", "exact"): None, ("fibres", "phase", "coherence"): None,
    ("fibres", "patch", "exact"): None, ("fibres", "patch", "coherence"): None,
    ("fibres", "autocorrelation", "exact"): None,  # docs/design.md#kopf-parent-weight
    ("fibres", "autocorrelation", "coherence"): None,
    ("fibres", "mirror", "exact"): None, ("fibres", "mirror", "coherence"): None,
    ("gravel", "histogram", "exact"): None, ("gravel", "histogram", "coherence"): None,
    ("gravel", "patch", "exact"): None, ("gravel", "patch", "coherence"): None,
    ("gravel", "autocorrelation", "exact"): None,
    ("gravel", "autocorrelation", "coherence"): None,  # docs/design.md#coherence-levels
    ("gravel", "mirror", "exact"): None, ("gravel", "mirror", "coherence"): None,
    ("grass", "autocorrelation", "exact"): None,  # docs/design.md#kopf-parent-weight
    ("grass", "autocorrelation", "coherence"): None,  # docs/design.md#index-histogram
    # the index histogram (coherence search only) breaks hrtem's lattice of stripes
    ("hrtem", "autocorrelation", "coherence"): None,  # docs/design.md#index-histogram
    ("hrtem", "autocorrelation", "exact"): "1.9: without the index histogram, a lattice of stripes",
    ("hrtem", "patch", "coherence"): None,  # docs/design.md#exhaustive-first-pass
    ("brick", "patch", "coherence"): None,  # near its limit (docs/design.md#index-histogram)
    ("porous50", "mirror", "coherence"): "0.16 with three views, the largest of the three axis pairs "
                                         "(a real material's block scatters to 0.2; tools/mirror_noise.py)",
    ("channels", "mirror", "coherence"): None,  # docs/design.md#anchor-slices
    ("lamellae", "mirror", "coherence"): "0.14 on seed 1, within the scatter of a real material's 48^3 block "
                                         "(tools/mirror_noise.py)",
}


@pytest.mark.slow
@pytest.mark.parametrize("name, target, search", [
    pytest.param(*key, marks=[] if why is None else pytest.mark.xfail(strict=True, reason=why))
    for key, why in KOPF_TARGETS.items()])
def test_kopf_meets_its_stricter_targets_at_48(gallery_runs, name, target, search):
    key, limit = KOPF_LIMITS[target]
    value = _value(gallery_runs(name, "kopf", search=search), key)
    assert value <= limit, f"{name}, {search} search: {target} {value:.2f} > {limit}"


@pytest.mark.slow
def test_the_index_histogram_is_what_breaks_hrtems_lattice(gallery_runs):
    """kopf's coherence search with the index histogram (the default) against without it:
    hrtem's autocorrelation within its target, and over three times it (docs/design.md#index-histogram)."""
    key, limit = KOPF_LIMITS["autocorrelation"]
    assert _value(gallery_runs("hrtem", "kopf", search="coherence"), key) <= limit
    assert _value(gallery_runs("hrtem", "kopf", search="coherence", index_histogram=False), key) > 3 * limit


@pytest.mark.slow
def test_the_parent_weight_is_what_keeps_kopfs_grass_blades(gallery_runs):
    """kopf's parent square weighed 4x (the default) against 1 (the thesis's equal weights), the
    exact search: grass's autocorrelation within its target, and over twice it
    (docs/design.md#kopf-parent-weight)."""
    key, limit = KOPF_LIMITS["autocorrelation"]
    assert _value(gallery_runs("grass", "kopf", search="exact"), key) <= limit
    assert _value(gallery_runs("grass", "kopf", search="exact", parent_weight=1.0), key) > 2 * limit


# --------------------------------------------------------------------------- phases are names, not grey levels
@pytest.mark.slow
def test_a_material_does_not_depend_on_the_values_of_its_phases(device):
    """Which grey value a segmented phase carries is the user's arbitrary choice; the volume's
    statistics should not depend on it, as they do when phases are compared as grey levels
    (distance="squared"; docs/design.md#phase-distance)."""
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
    """+in slices every 5 voxels on categorical exemplars, every 6 on grey ones (docs/design.md#slice-spacing),
    whole exemplar windows on both; a spacing or piece given is kept."""
    ex = gallery_exemplar(name, 64)
    kw = dict(rng=1, device=device, scales=1, neighborhood=3, levels=levels, max_sweeps=1, full_output=True)
    params = clsolid.synthesize(ex, (8, 8, 8), **kw).params
    assert (params["insert_spacing"], params["insert_piece"]) == (spacing, 0)
    params = clsolid.synthesize(ex, (8, 8, 8), insert_spacing=9, insert_piece=4, **kw).params
    assert (params["insert_spacing"], params["insert_piece"]) == (9.0, 4)
