"""The command line and the API come from one declaration per option."""

import argparse
import contextlib
import io
import json

import numpy as np
import pytest
from conftest import slow_except

from clsolid.cli import build_parser, main
from clsolid.cli.synth import ADVANCED_GROUPS, GROUPS, SOURCES
from clsolid.core.options import declared, names, reference_markdown
from clsolid.errors import EXIT_CODES, ClsolidError

def _synth_parser(show_all=True):
    parser = build_parser(show_all)
    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices["synth"]


def test_every_field_has_one_flag_and_no_flag_lacks_a_field():
    flags = {a.dest for a in _synth_parser()._actions if a.dest not in ("help", "help_all")}
    with_flag = {f.name for _, cls in SOURCES for f, spec in declared(cls) if spec.flag is not None}
    without = {(cls.__name__, f.name) for _, cls in SOURCES for f, spec in declared(cls) if spec.flag is None}
    assert flags == with_flag  # one flag per declared name, and nothing else
    # a search method's own name is what --method says; a Dask client is an object (--scheduler, --workers make one)
    assert without == {("SearchParams", "method"), ("BackendOptions", "client")}


def test_every_field_is_in_the_option_reference():
    for who, cls in SOURCES:
        page = reference_markdown(cls, who)
        for name in names(cls):
            assert f"| `{name}` |" in page, (who, name)


def _help(*argv):
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit) as info:
        main(["synth", *argv])
    assert info.value.code == 0
    return out.getvalue()


def test_the_first_help_group_is_short_and_the_tuning_groups_wait_for_help_all():
    text = _help("--help")
    essentials = text.split(f"{GROUPS['essentials']}:")[1].split("\n\n")[0]
    flags = [line.split()[0] for line in essentials.splitlines() if line.startswith("  ") and
             line.strip().startswith(("-", "exemplar"))]
    assert 8 <= len(flags) <= 12 and "--seed" in " ".join(flags) and "--preview" in " ".join(flags)
    for group in ADVANCED_GROUPS:
        assert GROUPS[group] not in text
    assert "--xi" not in text and "--prune-projected-probe" not in text
    full = _help("--help-all")
    assert all(GROUPS[group] in full for group in ADVANCED_GROUPS)
    assert "--xi" in full and "--prune-projected-probe" in full and "--vector-width" in full


def test_every_error_class_has_a_documented_exit_status():
    def subclasses(cls):
        for sub in cls.__subclasses__():
            yield sub
            yield from subclasses(sub)

    for cls in subclasses(ClsolidError):
        assert cls.exit_code in EXIT_CODES, cls
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit):
        main(["--help"])
    assert all(f"  {code:>3}  " in out.getvalue() for code in EXIT_CODES)


def test_a_misspelt_flag_names_the_closest(capsys):
    with pytest.raises(SystemExit) as info:
        main(["synth", "-o", "x.npy", "--relaxaton", "icm"])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "--relaxation" in err and len(err.strip().splitlines()) == 1


def test_a_missing_output_is_one_line(capsys):
    assert main(["synth", "brick"]) == 2
    err = capsys.readouterr().err
    assert "-o/--output is required" in err and len(err.strip().splitlines()) == 1


FAST = ["--shape", "6", "8", "10", "--neighborhood", "3", "--scales", "2", "--levels", "4", "--seed", "5", "-q"]


@pytest.mark.parametrize("method", slow_except(["ml", "kopf"], 0))
def test_a_sidecar_as_config_grows_the_same_volume(tmp_path, device, method):
    first = tmp_path / "first.npy"
    assert main(["synth", "brick", "-o", str(first), *FAST, "--method", method,
                 "--device", ":".join(device_spec(device))]) == 0
    again = tmp_path / "again.npy"
    assert main(["synth", "--config", str(first.with_suffix(".json")), "-o", str(again), "-q",
                 "--device", ":".join(device_spec(device))]) == 0
    np.testing.assert_array_equal(np.load(first), np.load(again))
    changed = tmp_path / "changed.npy"  # a flag given wins over the config
    assert main(["synth", "--config", str(first.with_suffix(".json")), "-o", str(changed), "-q", "--seed", "6",
                 "--device", ":".join(device_spec(device))]) == 0
    assert json.loads(changed.with_suffix(".json").read_text())["seed"] == 6
    assert not np.array_equal(np.load(first), np.load(changed))


def device_spec(device):
    """The ``platform:device`` indices of *device*."""
    import pyopencl as cl

    for p, platform in enumerate(cl.get_platforms()):
        for d, dev in enumerate(platform.get_devices()):
            if dev.int_ptr == device.device.int_ptr:
                return str(p), str(d)
    raise LookupError(device)


def test_a_toml_config_sets_options_and_flags_win(tmp_path, device):
    config = tmp_path / "run.toml"
    config.write_text('method = "ml"\nshape = [6, 8, 10]\nneighborhood = 3\nscales = 2\nlevels = 4\n'
                      'relaxation = "icm"\nseed = 2\n\n[about]\nsource = "a test"\n')
    out = tmp_path / "v.npy"
    dev = ":".join(device_spec(device))
    assert main(["synth", "--config", str(config), "-o", str(out), "-q", "--balance", "0.5", "--device", dev]) == 0
    params = json.loads(out.with_suffix(".json").read_text())["params"]
    assert (params["relaxation"], params["balance"], params["neighborhood"], np.load(out).shape) == (
        "icm", 0.5, 3, (6, 8, 10))
    config.write_text('relaxaton = "icm"\n')
    assert main(["synth", "--config", str(config), "-o", str(out), "-q"]) == 2


_SIDECAR = {"exemplar": "ex.npy", "seed": 3, "params": {"method": "ml", "shape": [5, 5, 5], "scales": 1}}


@pytest.mark.parametrize("change, words", [
    ({"seed": None}, "lacks 'seed'"),  # KeyError: 'seed'
    ({"params": {"method": "ml", "scales": 1}}, "lacks params 'shape'"),  # KeyError: 'shape'
    ({"voxel_size_from": "--voxel-size"}, "lacks 'voxel_size'"),  # KeyError: 'voxel_size'
    ({"params": {"method": ["ml"], "shape": [5, 5, 5]}}, "method ['ml'] is not available"),  # unhashable list
    ({"exemplar": []}, "exemplar=[] must be a file or a built-in name"),  # Path([]) on the pixel size: TypeError
])
def test_an_incomplete_sidecar_as_config_is_refused(tmp_path, capsys, change, words):
    meta = {k: v for k, v in {**_SIDECAR, **change}.items() if v is not None}
    config = tmp_path / "run.json"
    config.write_text(json.dumps(meta))
    out = tmp_path / "again.npy"
    assert main(["synth", "--config", str(config), "-o", str(out), "--device", "reference", "-q"]) == 2
    assert words in capsys.readouterr().err and not out.exists()


@pytest.mark.parametrize("text, words", [
    (b"\xe3\x83G\xf8", "not valid TOML"),  # not UTF-8: tomllib's UnicodeDecodeError
    (b"checkpoint = []\n", "checkpoint=[] must be a folder path"),  # Path([]): TypeError
    (b"preview = 3\n", "preview=3 must be a .png file"),
    (b'method = ["ml"]\n', "method ['ml'] is not available"),  # unhashable list: TypeError
])
def test_a_toml_config_of_the_wrong_types_is_refused(tmp_path, capsys, text, words):
    config = tmp_path / "run.toml"
    config.write_bytes(text)
    out = tmp_path / "v.npy"
    assert main(["synth", "brick", "--config", str(config), "-o", str(out), "--device", "reference", "-q"]) == 2
    assert words in capsys.readouterr().err and not out.exists()


def test_a_config_of_another_method_is_refused(tmp_path, capsys):
    config = tmp_path / "run.toml"
    config.write_text('method = "ml"\nrelaxation = "icm"\n')
    assert main(["synth", "--config", str(config), "-o", str(tmp_path / "v.npy"), "--method", "kopf"]) == 2
    assert "relaxation" in capsys.readouterr().err


@pytest.mark.parametrize("flag, name", [("-o", "x.tif"), ("--preview", "p.png"), ("--track", "t.json")])
def test_an_output_the_system_refuses_fails_before_the_run(tmp_path, capsys, flag, name):
    """A folder that takes no new files (Linux's /proc takes none, even from root) is refused at once."""
    import os

    if not os.path.isdir("/proc"):
        pytest.skip("no /proc here")
    args = ["synth", "brick", "-o", str(tmp_path / "v.tif"), *FAST]
    if flag == "-o":
        args[3] = f"/proc/{name}"
    else:
        args += [flag, f"/proc/{name}"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "does not take new files" in err and "sweep" not in err and "Traceback" not in err


def test_evaluate_checks_its_outputs_first(tmp_path, capsys):
    import os

    if not os.path.isdir("/proc"):
        pytest.skip("no /proc here")
    np.save(tmp_path / "v.npy", np.zeros((4, 4, 4)))
    assert main(["evaluate", "brick", str(tmp_path / "v.npy"), "-o", "/proc/r.json"]) == 2
    assert "does not take new files" in capsys.readouterr().err


def test_a_constant_exemplar_warns_on_the_command_line(tmp_path, capsys, device):
    np.save(tmp_path / "flat.npy", np.full((16, 16), 3, np.uint8))
    assert main(["synth", str(tmp_path / "flat.npy"), "-o", str(tmp_path / "v.npy"), *FAST]) == 0
    assert "clsolid: warning: the exemplar is constant" in capsys.readouterr().err
