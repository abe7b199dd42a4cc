"""The command-line runner: outputs, sidecar, progress, exit codes."""

import json

import numpy as np
import pytest
from conftest import slow_except

from clsolid.cli import EXIT_MEMORY, EXIT_NO_DEVICE, EXIT_OUTPUT, EXIT_USAGE, main
from clsolid.volumeio import load_volume

FAST = ["--shape", "8", "10", "12", "--neighborhood", "3", "--scales", "2", "--levels", "8", "--seed", "3"]


def test_synth_writes_volume_sidecar_preview_and_track(tmp_path, capsys, device):
    out = tmp_path / "v.tif"
    code = main(["synth", "brick", "-o", str(out), *FAST, "--voxel-size", "2", "0.5", "0.5",
                 "--preview", str(tmp_path / "p.png"), "--track", str(tmp_path / "t.json"),
                 "--device", device.device.name.strip()[:8]])
    assert code == 0
    vol, info = load_volume(out)
    assert vol.shape == (8, 10, 12) and vol.dtype == np.float32  # brick's level means, as ImageJ floats
    assert info["voxel_size"] == pytest.approx((2.0, 0.5, 0.5))
    meta = json.loads((tmp_path / "v.json").read_text())
    assert meta["seed"] == 3 and meta["params"]["neighborhood"] == 3 and meta["params"]["levels"] == 8
    assert meta["versions"]["clsolid"] and meta["device"]
    assert len(meta["timings"]["scales"]) == 2 and meta["timings"]["scales"][0]["sweep_seconds"]
    assert (tmp_path / "p.png").stat().st_size > 100
    assert meta["written"] == "values" and not meta["values_exact"] and len(meta["level_values"]) == 8
    assert set(np.unique(vol)) <= set(np.float32(meta["level_values"]))
    assert not (tmp_path / "v_exemplar.tif").exists()
    track = json.loads((tmp_path / "t.json").read_text())
    assert len(track["records"]) == sum(s["sweeps"] for s in meta["timings"]["scales"])
    assert {"autocorrelation_front", "histogram_kl_right"} <= set(track["records"][0]["indicators"])
    err = capsys.readouterr().err
    assert "scale 2/2" in err and "sweep" in err and "ETA" in err and "wrote" in err
    assert "p.png" in err and "t.json" in err


def test_indices_flag_writes_level_indices(tmp_path, device):
    assert main(["synth", "brick", "-o", str(tmp_path / "v.npy"), *FAST, "-q", "--indices"]) == 0
    vol = np.load(tmp_path / "v.npy")
    assert vol.dtype == np.uint8 and vol.max() < 8
    assert json.loads((tmp_path / "v.json").read_text())["written"] == "indices"


def test_evaluate_compares_like_with_like_through_the_sidecar(tmp_path, capsys, device):
    """No extra exemplar file: evaluate reads how the volume was written from its sidecar."""
    for flag in ([], ["--indices"]):
        out = tmp_path / f"v{len(flag)}.npy"
        assert main(["synth", "brick", "-o", str(out), *FAST, "-q", *flag]) == 0
        assert main(["evaluate", "brick", str(out), "--repeats", "2", "-o", str(tmp_path / "r.json")]) == 0
        report = json.loads((tmp_path / "r.json").read_text())
        assert report["settings"]["levels"] == (None if flag else 8)
        # a like-with-like histogram: the volume only holds the exemplar's levels
        assert report["views"]["front"]["distances"]["histogram_kl"]["value"] < 1.0
    assert "level means of 8 levels" in capsys.readouterr().out


@pytest.mark.parametrize("method", ["ml", "kopf"])
def test_evaluate_leaves_out_the_inserted_slices_named_by_the_sidecar(tmp_path, capsys, device, method):
    """+in (and kopf's anchor) slices start as exemplar copies: evaluate skips them unless asked."""
    from clsolid.api import inserted_slices

    out = tmp_path / "v.npy"
    assert main(["synth", "brick", "-o", str(out), *FAST, "-q", "--method", method]) == 0
    params = json.loads(out.with_suffix(".json").read_text())["params"]
    inserted = inserted_slices(params, np.load(out).shape)
    assert inserted["front"].size and inserted["right"].size and inserted["top"].size  # three views: all have them
    for keep in ([], ["--keep-inserted"]):
        assert main(["evaluate", "brick", str(out), "--repeats", "2", "--max-slices", "0",
                     "-o", str(tmp_path / "r.json"), *keep]) == 0
        views = json.loads((tmp_path / "r.json").read_text())["views"]
        for view in ("front", "right", "top"):
            used = set(views[view]["slice_indices"])
            assert used.isdisjoint(inserted[view].tolist()) != bool(keep)
    assert "leaving out the +in slices" in capsys.readouterr().out


def test_same_seed_same_file(tmp_path, device):
    for name in ("a.npy", "b.npy"):
        assert main(["synth", "-o", str(tmp_path / name), *FAST, "-q", "--device", "0:0"]) == 0
    np.testing.assert_array_equal(np.load(tmp_path / "a.npy"), np.load(tmp_path / "b.npy"))


# the default run keeps a recorded default, an auto value resolved, flags of several values and of several options
@pytest.mark.parametrize("argv, key, expected", slow_except([
    ([], "bandwidth_factor", [0.2, 0.2]),
    (["--bandwidth-factor", "0.5"], "bandwidth_factor", [0.5, 0.5]),
    (["--bandwidth-factor", "0.3", "2"], "bandwidth_factor", [0.3, 2.0]),
    (["--bandwidth", "3"], "bandwidth", [3.0, 3.0]),
    ([], "pyramid", "binomial"),
    (["--pyramid", "decimate"], "pyramid", "decimate"),
    ([], "likelihood", "exact"),  # brick is grey: auto sums exactly
    (["--likelihood", "pruned", "--prune-similar", "4", "--prune-sample", "32", "--prune-min-weight", "0.1"],
     "likelihood", "pruned"),
    ([], "distance", "squared"),  # brick is grey: auto squares the differences
    ([], "prune_similar", 8),  # resolved and recorded: 8 without projected candidates
    (["--likelihood", "pruned", "--prune-projected", "4"], "prune_similar", 1),  # 1 with them
    (["--likelihood", "pruned", "--prune-projected", "4", "--prune-projected-sweeps", "2"],
     "prune_projected_sweeps", 2),
    (["--distance", "mismatch"], "distance", "mismatch"),
    ([], "insert_piece", 0),  # each +in slice one exemplar window
    (["--insert-piece", "4"], "insert_piece", 4),
    ([], "seam_gap", 2),  # +in slices leave out the seams where they wrap the exemplar
    (["--seam-gap", "0"], "seam_gap", 0),
    ([], "falloff", 3.0),  # brick is grey: auto weighs the terms by a Gaussian of sigma 3
    (["--falloff", "0"], "falloff", 0.0),
    ([], "shared_weight", 1.0),  # brick is grey: every term alike
    (["--shared-weight", "0.25"], "shared_weight", 0.25),
    ([], "shared_profile", "direction"),
    (["--shared-weight", "0", "--shared-profile", "line"], "shared_profile", "line"),
    ([], "region", 0),  # set by set over the whole block
    (["--region", "6"], "region", 6),
], 0, 2, 7, 10, 17, 22))
def test_method_options_reach_the_sidecar(tmp_path, device, argv, key, expected):
    assert main(["synth", "-o", str(tmp_path / "v.npy"), *FAST, "-q", *argv]) == 0
    params = json.loads((tmp_path / "v.json").read_text())["params"]
    assert params[key] == (expected if isinstance(expected, str) else pytest.approx(expected))
    if key == "bandwidth":
        assert params["bandwidth_effective"] == pytest.approx(expected)
    if "--prune-similar" in argv:
        assert (params["prune_similar"], params["prune_sample"], params["prune_min_weight"]) == (4, 32, 0.1)


def test_quiet_is_quiet(tmp_path, capsys, device):
    assert main(["synth", "-o", str(tmp_path / "v.npy"), *FAST, "-q"]) == 0
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("argv, code, words", [
    (["--levels", "1"], EXIT_USAGE, "levels"),
    (["--neighborhood", "4"], EXIT_USAGE, "neighborhood"),
    (["--bandwidth-factor", "0.5", "1", "1", "1"], EXIT_USAGE, "bandwidth_factor"),
    (["--bandwidth", "2", "--bandwidth-factor", "0.5"], EXIT_USAGE, "not both"),
    (["--device", "no-such-device-anywhere"], EXIT_NO_DEVICE, "no OpenCL device matches"),
])
def test_user_errors_get_exit_codes_and_no_traceback(tmp_path, capsys, argv, code, words, device):
    base = ["synth", "-o", str(tmp_path / "v.npy"), "--shape", "8", "8", "8", "--scales", "1", "-q"]
    assert main(base + argv) == code
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err


def test_bad_choice_is_a_usage_error(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:  # argparse's own exit, with its usage line
        main(["synth", "-o", str(tmp_path / "v.npy"), "--pyramid", "gauss"])
    assert exit_info.value.code == EXIT_USAGE
    assert "--pyramid: invalid choice: 'gauss'" in capsys.readouterr().err


def test_bad_output_extension(tmp_path, capsys):
    assert main(["synth", "-o", str(tmp_path / "v.raw"), "-q"]) == EXIT_USAGE
    assert ".tif" in capsys.readouterr().err


def test_out_of_memory_exit_code(tmp_path, capsys, device, monkeypatch):
    from clsolid.core.device import Device

    monkeypatch.setattr(Device, "max_alloc", property(lambda self: 1 << 16))
    assert main(["synth", "-o", str(tmp_path / "v.npy"), "--shape", "64", "64", "64", "-q"]) == EXIT_MEMORY
    assert "max_mem_alloc_size" in capsys.readouterr().err


def test_devices_lists_a_table(capsys, device):
    assert main(["devices"]) == 0
    out = capsys.readouterr().out
    assert "platform / name" in out and device.device.name.strip() in out


def _calibrated_exemplar(tmp_path):
    """A 24 x 24 TIFF whose pixels are 0.25 nm high and 0.5 nm wide (ImageJ calibration)."""
    from clsolid.gallery import gallery_exemplar
    import tifffile

    path = tmp_path / "ex.tif"
    tifffile.imwrite(path, gallery_exemplar("porous50", 64)[:24, :24].astype(np.uint8), imagej=True,
                     resolution=(2.0, 4.0), metadata={"unit": "nm"})
    return path


def test_output_takes_the_exemplars_pixel_size(tmp_path, capsys, device):
    ex = _calibrated_exemplar(tmp_path)
    assert main(["synth", str(ex), "-o", str(tmp_path / "v.tif"), *FAST, "-q"]) == 0
    _, info = load_volume(tmp_path / "v.tif")
    assert info["voxel_size"] == pytest.approx((0.5, 0.25, 0.5)) and info["unit"] == "nm"  # Z and X: the width
    meta = json.loads((tmp_path / "v.json").read_text())
    assert meta["voxel_size_from"] == "exemplar" and meta["unit"] == "nm"
    assert "from the exemplar: 0.5 0.25 0.5 nm" in capsys.readouterr().err
    # --voxel-size wins; without a unit it is um
    assert main(["synth", str(ex), "-o", str(tmp_path / "w.tif"), *FAST, "-q", "--voxel-size", "3"]) == 0
    _, info = load_volume(tmp_path / "w.tif")
    assert info["voxel_size"] == pytest.approx((3.0, 3.0, 3.0)) and info["unit"] == "um"
    assert json.loads((tmp_path / "w.json").read_text())["voxel_size_from"] == "--voxel-size"


def test_unit_without_voxel_size_is_usage_error(tmp_path, capsys):
    ex = _calibrated_exemplar(tmp_path)
    assert main(["synth", str(ex), "-o", str(tmp_path / "v.tif"), *FAST, "--unit", "nm"]) == EXIT_USAGE
    assert "--unit is the unit of --voxel-size" in capsys.readouterr().err
    assert not (tmp_path / "v.tif").exists()


def test_uncalibrated_exemplar_gives_no_voxel_size(tmp_path, device):
    assert main(["synth", "brick", "-o", str(tmp_path / "v.tif"), *FAST, "-q"]) == 0
    _, info = load_volume(tmp_path / "v.tif")
    assert info["voxel_size"] is None
    assert json.loads((tmp_path / "v.json").read_text())["voxel_size_from"] is None


def test_ome_exemplar_in_default_micrometres_is_written(tmp_path, device):
    from clsolid.gallery import gallery_exemplar
    import tifffile

    ex = tmp_path / "ex.ome.tif"
    tifffile.imwrite(ex, gallery_exemplar("porous50", 64)[:24, :24].astype(np.uint8), ome=True,
                     metadata={"axes": "YX", "PhysicalSizeX": 0.2, "PhysicalSizeY": 0.2})
    assert main(["synth", str(ex), "-o", str(tmp_path / "v.tif"), *FAST, "-q"]) == 0
    _, info = load_volume(tmp_path / "v.tif")
    assert info["voxel_size"] == pytest.approx((0.2, 0.2, 0.2)) and info["unit"] == "\\u00B5m"
    assert main(["synth", str(ex), "-o", str(tmp_path / "v.ome.tif"), *FAST, "-q"]) == 0  # OME in, OME out
    back, info = load_volume(tmp_path / "v.ome.tif")
    assert info["voxel_size"] == pytest.approx((0.2, 0.2, 0.2)) and info["unit"] == "\u00b5m"
    np.testing.assert_array_equal(back, load_volume(tmp_path / "v.tif")[0])


@pytest.mark.parametrize("name, flags, needle", [
    ("v.tif", ["--voxel-size", "-1"], "voxel_size must be a positive"),
    ("v.tif", ["--voxel-size", "1", "--unit", "a=b"], "unit must be"),
    ("v.ome.tif", ["--voxel-size", "1", "--unit", "furlong"], "OME-XML's length units"),
])
def test_bad_calibration_fails_before_the_run(tmp_path, capsys, name, flags, needle):
    assert main(["synth", "brick", "-o", str(tmp_path / name), *FAST, *flags]) == EXIT_USAGE
    err = capsys.readouterr().err
    assert needle in err and "sweep" not in err  # refused before the first sweep, not after the run


@pytest.mark.parametrize("flag", ["-o", "--preview", "--track", "--checkpoint"])
def test_unwritable_output_fails_before_the_run(tmp_path, capsys, flag):
    (tmp_path / "a_file").write_text("")
    bad = tmp_path / "a_file" / {"--preview": "p.png", "-o": "x.tif", "--track": "t.json"}.get(flag, "ck")
    args = ["synth", "brick", "-o", str(tmp_path / "v.tif"), *FAST]
    args = [str(bad) if a == str(tmp_path / "v.tif") and flag == "-o" else a for a in args]
    if flag != "-o":
        args += [flag, str(bad)]
    assert main(args) == EXIT_USAGE
    err = capsys.readouterr().err
    assert "its folder cannot be made" in err and "sweep" not in err


def test_output_that_is_a_folder_fails_before_the_run(tmp_path, capsys):
    (tmp_path / "v.tif").mkdir()
    assert main(["synth", "brick", "-o", str(tmp_path / "v.tif"), *FAST]) == EXIT_USAGE
    assert "is a folder" in capsys.readouterr().err


def test_volume_is_rescued_when_the_output_fails_late(tmp_path, capsys, monkeypatch, device):
    import clsolid.volumeio

    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(clsolid.volumeio, "save_volume", full_disk)
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    assert main(["synth", "brick", "-o", str(tmp_path / "v.tif"), *FAST, "-q", "--indices"]) == EXIT_OUTPUT
    err = capsys.readouterr().err
    assert "No space left on device" in err and "the volume is saved in" in err
    rescued = list(tmp_path.glob("clsolid-rescued-seed3-*.npy"))
    assert len(rescued) == 1 and np.load(rescued[0]).shape == (8, 10, 12)


# -- a full disk while writing --------------------------------------------------------------


def _run_beside_a_full_disk(tmp_path, capsys, monkeypatch, full_disk, fills, *flags) -> tuple[int, str, np.ndarray]:
    """The exit status and stderr of ``synth`` into ``tmp_path/out``, where *fills* (folder
    name -> (room, file name)) makes files run out of space; and the uninterrupted volume."""
    assert main(["synth", "brick", "-o", str(tmp_path / "whole.npy"), *FAST, "-q"]) == 0
    for folder in ("out", "tmp"):
        (tmp_path / folder).mkdir()
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path / "tmp"))
    for folder, (room, name) in fills.items():
        full_disk(tmp_path / folder, room, name)
    capsys.readouterr()
    code = main(["synth", "brick", *FAST, "-q", *flags])
    return code, capsys.readouterr().err, np.load(tmp_path / "whole.npy")


@pytest.mark.slow
@pytest.mark.parametrize("name", ["v.tif", "v.ome.tif", "v.npy"])
def test_a_full_disk_midway_through_the_volume_leaves_no_output_and_rescues_it(tmp_path, capsys, monkeypatch,
                                                                              full_disk, device, name):
    """Out of space halfway through the volume's planes: no file at -o (nor a partial one
    beside it), exit status 7, and the message names the file the volume was saved in, which
    holds the volume."""
    import re
    from pathlib import Path

    out = tmp_path / "out" / name
    code, err, whole = _run_beside_a_full_disk(tmp_path, capsys, monkeypatch, full_disk,
                                               {"out": (8 * 10 * 12 * 4 // 2, name)}, "-o", str(out))
    assert code == EXIT_OUTPUT and "No space left on device" in err
    rescued = Path(re.search(r"the volume is saved in (\S+\.npy)", err).group(1))
    assert rescued.parent == tmp_path / "tmp" and np.array_equal(np.load(rescued), whole)
    assert not list(out.parent.iterdir()) and list((tmp_path / "tmp").iterdir()) == [rescued]


@pytest.mark.slow
def test_a_full_disk_where_the_volume_would_be_rescued_too_says_so(tmp_path, capsys, monkeypatch, full_disk,
                                                                    device):
    """The output and the temporary folder both full: exit status 7 (not a crash), a message
    naming both failures and the way back, and no partial file in either folder."""
    code, err, _ = _run_beside_a_full_disk(tmp_path, capsys, monkeypatch, full_disk,
                                           {"out": (100, "v.npy"), "tmp": (100, "")}, "-o",
                                           str(tmp_path / "out" / "v.npy"))
    assert code == EXIT_OUTPUT and "nor could the volume be saved in" in err and "--seed" in err
    assert not list((tmp_path / "out").iterdir()) and not list((tmp_path / "tmp").iterdir())


@pytest.mark.slow
@pytest.mark.parametrize("name, kept", [("v.json", ["v.tif"]), ("p.png", ["v.json", "v.tif"])])
def test_a_full_disk_while_writing_the_sidecar_or_preview_keeps_the_volume(tmp_path, capsys, monkeypatch, full_disk,
                                                                           device, name, kept):
    """The volume written, then no room for its sidecar (or the preview, written after it):
    exit status 7, the message says where the volume is, which holds it, and the file that
    failed is not there, not even in part."""
    out = tmp_path / "out" / "v.tif"
    code, err, whole = _run_beside_a_full_disk(tmp_path, capsys, monkeypatch, full_disk, {"out": (0, name)}, "-o",
                                               str(out), "--preview", str(tmp_path / "out" / "p.png"))
    assert code == EXIT_OUTPUT and f"the volume is in {out}" in err and "No space left on device" in err
    assert np.array_equal(load_volume(out)[0], whole.astype(np.float32))  # ImageJ's float samples
    assert sorted(p.name for p in out.parent.iterdir()) == kept


def test_synth_grows_a_colour_png_into_an_rgb_tif_and_regrows_it(tmp_path, capsys, device):
    from PIL import Image
    from skimage import data

    Image.fromarray(np.ascontiguousarray(data.coffee()[180:212, 300:332])).save(tmp_path / "c.png")
    out = tmp_path / "v.tif"
    argv = ["synth", str(tmp_path / "c.png"), "-o", str(out), *FAST, "--device", device.device.name.strip()[:8]]
    assert main([*argv, "--preview", str(tmp_path / "p.png"), "-q"]) == 0
    vol, _ = load_volume(out)
    assert vol.shape == (8, 10, 12, 3) and vol.dtype == np.uint8
    meta = json.loads((tmp_path / "v.json").read_text())
    palette = np.array(meta["level_values"])
    assert palette.shape == (8, 3) and meta["params"]["likelihood"] == "pruned"
    assert {tuple(c) for c in vol.reshape(-1, 3).tolist()} <= {tuple(c) for c in palette.tolist()}
    assert np.asarray(Image.open(tmp_path / "p.png")).shape[-1] == 3  # the preview in colour
    assert main(["synth", "--config", str(tmp_path / "v.json"), "-o", str(tmp_path / "again.npy"), "-q",
                 "--device", device.device.name.strip()[:8]]) == 0
    np.testing.assert_array_equal(np.load(tmp_path / "again.npy"), vol)
    capsys.readouterr()
    assert main(["evaluate", str(tmp_path / "c.png"), str(out), "--repeats", "2", "-o", str(tmp_path / "r.json")]) == 0
    assert "a palette of 8 colours" in capsys.readouterr().out
    report = json.loads((tmp_path / "r.json").read_text())
    assert all("colour_histogram_kl" in v["distances"] for v in report["views"].values())


def test_synth_grows_a_colour_png_with_kopf_and_regrows_it(tmp_path, capsys, device):
    from PIL import Image
    from skimage import data

    Image.fromarray(np.ascontiguousarray(data.coffee()[180:212, 300:332])).save(tmp_path / "c.png")
    out = tmp_path / "k.tif"
    dev = ["--device", device.device.name.strip()[:8]]
    assert main(["synth", str(tmp_path / "c.png"), "-o", str(out), "--method", "kopf", "--shape", "8", "10", "12",
                 "--levels", "8", "--scales", "2", "--iterations", "2", "-q", *dev]) == 0
    vol, _ = load_volume(out)
    assert vol.shape == (8, 10, 12, 3) and vol.dtype == np.uint8
    palette = np.array(json.loads((tmp_path / "k.json").read_text())["level_values"])
    assert {tuple(c) for c in vol.reshape(-1, 3).tolist()} <= {tuple(c) for c in palette.tolist()}
    assert main(["synth", "--config", str(tmp_path / "k.json"), "-o", str(tmp_path / "again.npy"), "-q", *dev]) == 0
    np.testing.assert_array_equal(np.load(tmp_path / "again.npy"), vol)


def test_a_16_bit_colour_run_to_an_imagej_tif_is_refused_before_it_starts(tmp_path, capsys):
    import tifffile

    rgb = np.random.default_rng(0).integers(0, 65536, (24, 24, 3)).astype(np.uint16)
    tifffile.imwrite(tmp_path / "c.tif", rgb, photometric="rgb")
    out = tmp_path / "v.tif"
    assert main(["synth", str(tmp_path / "c.tif"), "-o", str(out), *FAST, "--device", "reference"]) == EXIT_USAGE
    assert "8-bit samples only" in capsys.readouterr().err and not out.exists()
    assert not out.with_suffix(".json").exists()
