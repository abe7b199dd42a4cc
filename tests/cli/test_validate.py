"""``clsolid validate``: a table, a JSON report and a plot; outputs checked before anything grows."""

import json

import numpy as np
import pytest

from clsolid.cli import EXIT_USAGE, main
from clsolid.groundtruth import ground_truth


@pytest.fixture
def real(tmp_path):
    path = tmp_path / "real.npy"
    np.save(path, ground_truth("iso2", 32, seed=0))
    return path


def test_validate_prints_the_table_and_writes_the_report(tmp_path, capsys, device, real):
    config = tmp_path / "small.toml"
    config.write_text("neighborhood = 3\nscales = 2\n")
    code = main(["validate", str(real), "-n", "1", "--shape", "16", "16", "16", "--config", str(config),
                 "--no-tortuosity", "-o", str(tmp_path / "r.json"), "-q"])
    assert code == 0
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["real"]["file"] == str(real) and report["generated"]["shape"] == [16, 16, 16]
    out = capsys.readouterr().out
    assert "phase 0" in out and "S2 along x" in out and "report written" in out


def test_validate_takes_an_rgb_volume(tmp_path, capsys, device):
    phases = ground_truth("iso2", 32, seed=0).astype(bool).astype(int)
    path = tmp_path / "rgb.npy"
    np.save(path, np.array([[200, 90, 40], [30, 60, 170]], np.uint8)[phases])
    config = tmp_path / "small.toml"
    config.write_text("method = \"kopf\"\nneighborhood = 3\nscales = 2\n")
    code = main(["validate", str(path), "-n", "1", "--shape", "16", "16", "16", "--config", str(config),
                 "--no-tortuosity", "--device", device.device.name.strip()[:8], "-q"])
    assert code == 0
    assert "colours cut by the nearest (CIELAB) of (30, 60, 170), (200, 90, 40)" in capsys.readouterr().out


def test_an_unwritable_report_is_refused_before_anything_grows(tmp_path, capsys, real):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["validate", str(real), "-o", str(blocker / "r.json")]) == EXIT_USAGE
    assert "--output" in capsys.readouterr().err


def test_a_misspelt_option_in_the_config_names_the_closest(tmp_path, capsys, real):
    config = tmp_path / "bad.toml"
    config.write_text("neighbourhood = 3\n")
    assert main(["validate", str(real), "--config", str(config), "--device", "reference"]) == EXIT_USAGE
    assert "neighborhood" in capsys.readouterr().err


@pytest.mark.parametrize("text, words", [
    ('method = [{}]\n', "method [{}] is not available"),  # TypeError: unhashable type: 'list'
    ('exemplar = "x.npy"\nshape = [4, 4, 4]\n', "unknown options 'exemplar', 'shape'"),  # given twice: TypeError
])
def test_a_config_of_other_than_the_methods_options_is_refused(tmp_path, capsys, real, text, words):
    config = tmp_path / "bad.toml"
    config.write_text(text)
    out = tmp_path / "r.json"
    assert main(["validate", str(real), "--config", str(config), "--device", "reference", "-o", str(out)]) == EXIT_USAGE
    assert words in capsys.readouterr().err and not out.exists()
