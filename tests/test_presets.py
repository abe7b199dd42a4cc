"""Presets named after the thesis's experiments: valid settings, the CLI's use of them."""

import json

import pytest

from clsolid.cli import build_parser, main
from clsolid.cli.synth import SOURCES, resolve
from clsolid.core.options import names
from clsolid.errors import InputError
from clsolid.ml.params import MLParams
from clsolid.presets import PRESETS, get_preset
from clsolid.search.params import SearchParams

THESIS_NAMES = {"ch5_np_common", "ch5_np_11", "ch5_ml_common", "ch5_compare", "ch6_hrtem_np",
                "ch6_hrtem_ml", "ch5_views"}


def _params(preset):
    opts = dict(preset.options)
    if preset.method == "ml":
        return MLParams(**opts)
    return SearchParams(method=preset.method, **{k: v for k, v in opts.items() if k != "levels"})


def test_every_thesis_experiment_has_a_valid_preset():
    assert set(PRESETS) == THESIS_NAMES
    for preset in PRESETS.values():
        params = _params(preset)  # validates every option
        assert preset.source.startswith("Urs thesis, §") and preset.departures and preset.path.is_file()
        assert preset.keywords()["shape"] == preset.shape and preset.keywords()["method"] == preset.method
        assert params.neighborhood == preset.options["neighborhood"]


def test_presets_follow_the_thesis_numbers():
    common = get_preset("ch5_np_common")
    assert (common.method, common.shape, common.options["neighborhood"], common.options["scales"],
            common.options["iterations"], common.options["levels"]) == ("kopf", (64, 64, 64), 7, 3, 10, 32)
    assert get_preset("ch5_np_11").options["neighborhood"] == 11
    hrtem = get_preset("ch6_hrtem_np")
    assert hrtem.shape == (128, 128, 128) and hrtem.exemplar_size == 128 and hrtem.options["scales"] == 5
    ml = get_preset("ch6_hrtem_ml")
    assert (ml.options["relaxation"], ml.options["balance"], ml.options["heuristic"]) == ("icm", 0.0, "h2-product")
    assert get_preset("ch5_ml_common").options["upsampling"] == "8/8"


def test_unknown_preset_is_refused():
    with pytest.raises(InputError, match="ch5_np_common"):
        get_preset("ch9")
    with pytest.raises(SystemExit):
        build_parser().parse_args(["synth", "-o", "x.npy", "--preset", "ch9"])


def _settings(argv):
    args = vars(build_parser().parse_args(["synth", *argv]))
    args.pop("command")
    return resolve(args)


def test_every_preset_option_is_a_synth_flag():
    flags = {name for _, cls in SOURCES for name in names(cls)}
    for preset in PRESETS.values():
        assert set(preset.options) | {"method", "shape", "builtin_size"} <= flags, preset.name


def test_preset_becomes_the_defaults_and_explicit_flags_win():
    run = _settings(["-o", "x.npy", "--preset", "ch5_compare", "--neighborhood", "5"])
    options = run.method_options
    assert options["neighborhood"] == 5  # given: wins
    assert (options["relaxation"], options["balance"], options["upsampling"], options["bandwidth_factor"]) == (
        "icm", 0.0, "1/8", 1.0)
    assert tuple(run.command.shape) == (64, 64, 64)
    plain = _settings(["-o", "x.npy"])
    assert "relaxation" not in plain.method_options and plain.command.preset is None  # no leak between runs


def test_preset_for_another_method_is_refused():
    with pytest.raises(InputError, match="is for --method wl, kopf, chen-wang"):
        _settings(["-o", "x.npy", "--preset", "ch5_np_common", "--method", "ml"])
    with pytest.raises(InputError, match="is for --method ml"):
        _settings(["-o", "x.npy", "--preset", "ch5_compare", "--method", "kopf"])


def test_a_search_preset_serves_every_search_method():
    run = _settings(["-o", "x.npy", "--preset", "ch5_np_common", "--method", "chen-wang"])
    options = run.method_options
    assert (run.command.method, options["neighborhood"], options["iterations"], options["levels"]) == (
        "chen-wang", 7, 10, 32)


def test_preset_runs_and_is_recorded(tmp_path, device):
    out = tmp_path / "v.npy"
    code = main(["synth", "gravel", "-o", str(out), "--preset", "ch5_ml_common", "--shape", "8", "8", "8",
                 "--scales", "2", "--insert-slices", "2", "--seed", "1", "-q"])
    assert code == 0
    meta = json.loads(out.with_suffix(".json").read_text())
    assert meta["preset"] == "ch5_ml_common"
    params = meta["params"]
    assert (params["neighborhood"], params["relaxation"], params["upsampling"], params["insert_slices"],
            params["scales"]) == (7, "icm", "8/8", 2, 2)


def test_every_search_preset_turns_kopfs_departures_off():
    """The thesis's NP_K: no histogram specification, balance, anchor slices, heavier parent or phase codes."""
    thesis = {"specify": False, "balance": 0.0, "insert_spacing": 0.0, "parent_weight": 1.0, "distance": "squared",
              "search": "exact"}
    for preset in PRESETS.values():
        if preset.method != "ml":
            assert {k: preset.options.get(k) for k in thesis} == thesis, preset.name
