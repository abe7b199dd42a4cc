"""Validation against a real 3D volume: a section in, volumes out, 3D properties compared."""

import json

import numpy as np
import pytest

from clsolid.errors import InputError
from clsolid.groundtruth import ground_truth, isotropic_field
from clsolid.validation import ColourCut, format_validation, plot_validation, segment, validate

SMALL = dict(neighborhood=3, scales=2)


@pytest.fixture(scope="module")
def real():
    return isotropic_field(24, seed=0, correlation_length=3.0, fractions=(0.4, 0.35, 0.25))


@pytest.fixture(scope="module")
def report(real, device):
    return validate(real, n=2, shape=(12, 12, 12), device=device, **SMALL)


def test_the_report_holds_every_phase_and_property_beside_the_real_band(real, report):
    assert report["band_count"] == 8 and report["generated"]["seeds"] == [0, 1]
    assert set(report["phases"]) == {"0", "1", "2"} and len(report["volumes"]) == 2
    for key, rows in report["phases"].items():
        real_fraction = float(np.mean(real == int(key)))
        assert rows["fraction"]["real"] == pytest.approx(real_fraction)
        # the generator keeps its exemplar's phases: the section's fraction, give or take a slice's spread
        section_fraction = float(np.mean(real[12] == int(key)))
        assert report["section"][key]["fraction"] == pytest.approx(section_fraction)
        assert len(report["section"][key]["s2"]) == 2  # along the section's y and x
        assert abs(rows["fraction"]["generated"] - section_fraction) < 0.05
        assert len(rows["s2"]["error"]) == 3 and len(rows["connected"]["real"]) == 3
        assert ("tortuosity" in rows) == (real_fraction > 0.25)
    json.dumps(report, allow_nan=False)  # JSON as it stands
    table = format_validation(report)
    assert all(f"phase {k}: the section's fraction" in table for k in "012") and "S2 along z" in table and "tortuosity x" in table


def test_a_grey_real_volume_is_cut_at_its_own_levels_and_so_are_the_grown_ones(device):
    rng = np.random.default_rng(0)
    grey = isotropic_field(24, seed=1, correlation_length=3.0) * 100.0 + rng.normal(0, 10, (24, 24, 24))
    labels, thresholds = segment(grey, 2)
    assert len(thresholds) == 1 and 20 < thresholds[0] < 80 and set(np.unique(labels)) == {0, 1}
    report = validate(grey, n=1, shape=(12, 12, 12), device=device, tortuosity=False, **SMALL)
    assert report["real"]["thresholds"] == pytest.approx(thresholds)
    assert set(report["phases"]) == {"0", "1"} and "tortuosity" not in report["phases"]["0"]
    assert "grey levels cut at" in format_validation(report)


@pytest.mark.parametrize("method", ["ml", "kopf"])
def test_an_rgb_real_volume_is_cut_by_its_colours_and_grown_in_colour(device, method):
    """Two phases drawn in two noisy colours: the cut finds the phases again, and the grown
    colour volumes are cut by the same colours (their fractions near the section's)."""
    phases = isotropic_field(24, seed=2, correlation_length=3.0, fractions=(0.55, 0.45))
    rng = np.random.default_rng(0)
    colours = np.array([[190, 120, 60], [40, 70, 160]])
    rgb = np.clip(colours[phases] + rng.integers(-12, 13, phases.shape + (3,)), 0, 255).astype(np.uint8)
    cut = ColourCut(rgb, 2)
    assert np.array_equal(cut(rgb), phases if cut.colours[0, 2] < 100 else 1 - phases)
    report = validate(rgb, n=1, shape=(12, 12, 12), method=method, device=device, tortuosity=False, **SMALL)
    assert report["real"]["shape"] == [24, 24, 24] and len(report["real"]["colours"]) == 2
    for key, rows in report["phases"].items():
        assert abs(rows["fraction"]["generated"] - report["section"][key]["fraction"]) < 0.1
    assert "colours cut by the nearest" in format_validation(report)


def test_a_segmented_real_volume_keeps_its_values():
    labels = ground_truth("iso2", 32, seed=0) * 255
    same, thresholds = segment(labels, 2)
    assert thresholds is None and same is labels


def test_the_plot_shows_s2_per_axis(tmp_path, report):
    pytest.importorskip("matplotlib")
    plot_validation(report, tmp_path / "s2.png")
    assert (tmp_path / "s2.png").stat().st_size > 1000


def test_the_three_sections_each_constrain_their_view(device):
    """An anisotropic field, long along x, short along z: with its three sections the grown
    volumes are long along x and short along z too, and the report gives the lengths."""
    real = ground_truth("aniso2", 48, seed=0)
    report = validate(real, n=1, shape=(24, 24, 24), device=device, sections="all", tortuosity=False,
                      neighborhood=7, scales=2)
    assert report["real"]["section"].startswith("front z = 24, right x = 24, top y = 24")
    real_z, real_y, real_x = report["correlation_length"]["real"]
    z, y, x = report["correlation_length"]["generated"]
    assert real_z < real_y < real_x and z < y
    assert x is None or y < x  # None: beyond half the block's side, longer still
    assert "correlation length z / y / x" in format_validation(report)


def test_the_correlation_length_error_is_relative(report):
    lengths = report["correlation_length"]
    for g, r, e in zip(lengths["generated"], lengths["real"], lengths["error"]):
        assert e == pytest.approx(g / r - 1.0)


@pytest.mark.parametrize("kw, match", [(dict(n=0), "n=0"), (dict(shape=(16, 16)), "three sides"),
                                       (dict(shape=(16, 16, 64)), "does not fit"), (dict(classes=1), "classes=1"),
                                       (dict(sections="some"), "sections='some'")])
def test_bad_arguments_are_refused_before_anything_grows(kw, match):
    with pytest.raises(InputError, match=match):
        validate(ground_truth("iso2", 32, seed=0), device="reference", **kw)
