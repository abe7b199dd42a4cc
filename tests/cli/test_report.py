"""Tests of clsolid.report: the ``evaluate`` command, its table, JSON, plots and tracks."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest
import tifffile
from PIL import Image
from scipy import ndimage as ndi

from clsolid.errors import InputError
from clsolid.cli import EXIT_MISSING, EXIT_OK, EXIT_USAGE, main
from clsolid.report import (format_table, format_track, load_exemplar, load_volume, plot_report, plot_track,
                            validate_track)

EXIT_INPUT, EXIT_NO_MATPLOTLIB = EXIT_USAGE, EXIT_MISSING

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def run(argv: list[str]) -> int:
    return main(["evaluate", *(str(a) for a in argv)])


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A small grey exemplar (.npy and .png) and volume (.tif and .npy) of one random field."""
    rng = np.random.default_rng(0)
    field = ndi.gaussian_filter(rng.standard_normal((32, 40, 40)), 1.5, mode="wrap")
    grey = np.clip(np.round(field / field.std() * 40 + 128), 0, 255).astype(np.uint8)
    d = tmp_path_factory.mktemp("evaluate")
    np.save(d / "ex.npy", grey[0])
    Image.fromarray(grey[1]).save(d / "ex.png")
    tifffile.imwrite(d / "vol.tif", grey[:, :24, :24].copy())
    np.save(d / "vol.npy", grey[:, :24, :24])
    return d


@pytest.fixture(scope="module")
def report(files, tmp_path_factory):
    out = tmp_path_factory.mktemp("out") / "report.json"
    argv = [files / "ex.npy", files / "vol.tif", "-o", out, "--repeats", "3", "--max-slices", "8",
            "--constrained", "front", "right"]
    assert run(argv) == EXIT_OK
    return json.loads(out.read_text())


@pytest.fixture()
def no_matplotlib(monkeypatch):
    for name in ("matplotlib", "matplotlib.figure", "matplotlib.backends", "matplotlib.backends.backend_agg"):
        monkeypatch.setitem(sys.modules, name, None)


def test_constrained_views_default_to_the_sidecars_then_the_exemplars_then_all():
    from clsolid.cli.evaluate import _constrained

    assert _constrained({"params": {"views": 2}}, {}) == ("front", "right")
    assert _constrained({"params": {"views": "front+top"}}, {"right": "r.tif"}) == ("front", "top")
    assert _constrained(None, {"front": "f.tif", "top": "t.tif"}) == ("front", "top")
    assert _constrained(None, {}) == ("front", "right", "top")


def test_evaluate_prints_a_table_and_writes_json(files, capsys, tmp_path):
    out = tmp_path / "r.json"
    rc = run([files / "ex.png", files / "vol.npy", "-o", out, "--views", "front", "top",
              "--constrained", "front", "--repeats", "2", "--seed", "3"])
    text = capsys.readouterr().out
    assert rc == EXIT_OK
    assert "histogram_kl" in text and "front*" in text and "top" in text and "top*" not in text
    assert "kurtosis (excess)" in text and f"report written to {out}" in text
    rep = json.loads(out.read_text())
    assert list(rep["views"]) == ["front", "top"]
    assert rep["settings"]["seed"] == 3 and rep["files"]["exemplar"].endswith("ex.png")


def test_report_json_holds_every_reference(report):
    d = report["views"]["right"]["distances"]["autocorrelation_l2"]
    assert d["floor"]["halves"]["n"] == 3 and d["ceiling"]["n"] == 3
    assert report["views"]["right"]["constrained"] is True
    assert report["views"]["top"]["constrained"] is False


def test_format_table_marks_constrained_and_uninformative(report):
    table = format_table(report)
    lines = table.splitlines()
    assert lines[1].split()[:4] == ["metric", "units", "floor", "ceiling"]
    assert "front*" in lines[1] and "right*" in lines[1] and "top*" not in lines[1]
    assert "n/i" in table and "uninformative" in table
    report = json.loads(json.dumps(report))
    d = report["views"]["front"]["distances"]["histogram_kl"]
    d.update(value=None)
    assert "n/m" in format_table(report)


@pytest.mark.parametrize("argv, message", [
    (["missing.npy", "vol.tif"], "does not exist"),
    (["ex.npy"], "EXEMPLAR and VOLUME"),
    (["ex.npy", "vol.tif", "--levels", "1"], "levels"),
    (["ex.npy", "vol.tif", "--max-slices", "-1"], "max-slices"),
    (["vol.tif", "vol.tif"], "must be one 2D image"),
    (["ex.npy", "ex.npy"], "expected (Z, Y, X)"),
    (["ex.npy", "vol.txt"], "unsupported extension"),
])
def test_input_errors_exit_2_without_traceback(files, capsys, argv, message):
    (files / "vol.txt").write_text("not a volume")
    rc = run([files / a if not a.startswith("-") and not a[0].isdigit() else a for a in argv])
    err = capsys.readouterr().err
    assert rc == EXIT_INPUT
    assert message in err and "Traceback" not in err


def test_colour_exemplars_are_rgb_and_grey_ones_in_rgb_grey(tmp_path):
    rgb = np.zeros((20, 20, 3), dtype=np.uint8)
    rgb[..., 0] = 200
    Image.fromarray(rgb).save(tmp_path / "c.png")
    assert load_exemplar(tmp_path / "c.png").shape == (20, 20, 3)
    rgb[..., 1] = rgb[..., 2] = 200
    Image.fromarray(rgb).save(tmp_path / "g.png")
    assert load_exemplar(tmp_path / "g.png").shape == (20, 20)


def test_singleton_axes_are_dropped(tmp_path):
    np.save(tmp_path / "e.npy", np.zeros((1, 20, 20)))
    np.save(tmp_path / "v.npy", np.zeros((1, 8, 9, 10)))
    assert load_exemplar(tmp_path / "e.npy").shape == (20, 20)
    assert load_volume(tmp_path / "v.npy").shape == (8, 9, 10)


def test_plot_without_matplotlib_is_a_missing_dependency(files, capsys, no_matplotlib, tmp_path):
    rc = run([files / "ex.npy", files / "vol.tif", "--plot", tmp_path / "r.png"])
    err = capsys.readouterr().err
    assert rc == EXIT_NO_MATPLOTLIB
    assert 'pip install "clsolid[report]"' in err and "pip install matplotlib" in err
    assert not (tmp_path / "r.png").exists()


def test_plot_report(report, tmp_path):
    pytest.importorskip("matplotlib")
    plot_report(report, tmp_path / "r.png")
    assert (tmp_path / "r.png").read_bytes()[:8] == PNG_MAGIC


@pytest.mark.slow
def test_plot_report_with_phase_curves(tmp_path):
    pytest.importorskip("matplotlib")
    from clsolid.metrics import evaluate

    rng = np.random.default_rng(1)
    field = ndi.gaussian_filter(rng.standard_normal((24, 32, 32)), 2.0, mode="wrap") > 0.05
    rep = evaluate(field[0].astype(float), field[:, :16, :16].astype(float), reference_repeats=2)
    plot_report(rep, tmp_path / "p.png")
    assert (tmp_path / "p.png").read_bytes()[:8] == PNG_MAGIC


# --------------------------------------------------------------------------- tracks

TRACK = {"records": [
    {"scale": s, "sweep": w, "indicators": {"changed_fraction": 0.5 / (w + 1) / (s + 1), "energy": 10.0 - w}}
    for s in range(3) for w in range(4)
] + [{"scale": 2, "sweep": 4, "indicators": {"energy": None}}]}


def test_validate_track_accepts_the_documented_form():
    assert len(validate_track(TRACK)) == 13
    text = format_track(TRACK)
    assert "changed_fraction scale 0" in text and "over 4 sweeps" in text


@pytest.mark.parametrize("track, match", [
    ([], "records"), ({"records": [1]}, "records\\[0\\]"),
    ({"records": [{"scale": 1.5, "sweep": 0, "indicators": {}}]}, "scale"),
    ({"records": [{"scale": 0, "sweep": True, "indicators": {}}]}, "sweep"),
    ({"records": [{"scale": 0, "sweep": 0}]}, "indicators"),
    ({"records": [{"scale": 0, "sweep": 0, "indicators": {"e": "x"}}]}, "indicators\\['e'\\]"),
])
def test_validate_track_names_the_problem(track, match):
    with pytest.raises(InputError, match=match):
        validate_track(track)


def test_track_only_prints_a_summary(tmp_path, capsys):
    path = tmp_path / "track.json"
    path.write_text(json.dumps(TRACK))
    assert run(["--track", path]) == EXIT_OK
    assert "energy scale 2" in capsys.readouterr().out
    (tmp_path / "bad.json").write_text("{not json")
    assert run(["--track", tmp_path / "bad.json"]) == EXIT_INPUT
    assert "not valid JSON" in capsys.readouterr().err


def test_track_plot_without_matplotlib_exits_3(tmp_path, no_matplotlib):
    path = tmp_path / "track.json"
    path.write_text(json.dumps(TRACK))
    assert run(["--track", path, "--plot", tmp_path / "t.png"]) == EXIT_NO_MATPLOTLIB


def test_plot_track(tmp_path):
    pytest.importorskip("matplotlib")
    plot_track(TRACK, tmp_path / "t.png")
    assert (tmp_path / "t.png").read_bytes()[:8] == PNG_MAGIC
    plot_track({"records": []}, tmp_path / "empty.png")
    assert (tmp_path / "empty.png").exists()


def test_report_and_track_plots_together(files, tmp_path):
    pytest.importorskip("matplotlib")
    path = tmp_path / "track.json"
    path.write_text(json.dumps(TRACK))
    rc = run([files / "ex.npy", files / "vol.tif", "--views", "front", "--repeats", "2",
              "--plot", tmp_path / "r.png", "--track", path])
    assert rc == EXIT_OK
    assert (tmp_path / "r.png").exists() and (tmp_path / "r_track.png").exists()
