"""The scripts in tools/ run (at toy sizes; their figures are not checked here)."""

import json

import numpy as np
import pytest


@pytest.mark.slow
def test_bench_ml_runs_with_tuning(capsys, device, tool):
    tool("bench_ml").main(["--case", "b", "--shape", "8", "8", "8", "--voxels-per-item", "2",
                            "--device", device.device.name.strip()[:8]])
    out = capsys.readouterr().out
    assert "tuning: {'voxels_per_item': 2}" in out and "% of matmul" in out and "end to end" in out
    assert "x ICM" in out and "sweeps" in out


def test_bench_ml_builds_the_program_once_for_two_exemplars(capsys, device, monkeypatch, tool):
    import os

    monkeypatch.setenv("POCL_CACHE_DIR", os.environ["POCL_CACHE_DIR"])  # put back after the tool sets its own
    tool("bench_ml").main(["--builds", "composite3", "composite4", "--device", device.device.name.strip()[:8]])
    out = capsys.readouterr().out
    rows = [line.split() for line in out.splitlines() if line.startswith("  composite")]
    assert "GFLOP/s" in out and [row[0] for row in rows] == ["composite3:", "composite4:"]
    assert rows[0][-1] == rows[1][-1]  # as many programs after the second exemplar as after the first


def test_quality_ml_prints_every_seed(capsys, device, tmp_path, tool):
    tool("quality_ml").main(["--seeds", "1", "2", "--shape", "8", "8", "8", "--set", "neighborhood=3",
                              "--set", "pyramid=decimate", "--save", str(tmp_path / "q"),
                              "--device", device.device.name.strip()[:8]])
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines[2:]] == ["1", "2", "mean", "worst"]
    assert (tmp_path / "q_seed2.npy").exists()


def test_compare_devices_reports_each_pair(capsys, tool):
    tool("compare_devices").main(["--shape", "8", "8", "8", "--set", "neighborhood=3", "--set", "scales=1"])
    out = capsys.readouterr().out
    assert "seed 1" in out and ("identical voxels" in out or "nothing to compare" in out)


@pytest.mark.slow
def test_gallery_writes_table_json_and_montage(capsys, device, tmp_path, tool):
    import json

    from PIL import Image

    gallery = tool("gallery")
    assert gallery.main(["--names", "porous80", "hrtem", "--shape", "16", "--set", "neighborhood=3",
                         "--set", "scales=1", "--device", device.device.name.strip()[:8],
                         "-o", str(tmp_path)]) == 0
    progress = capsys.readouterr().err
    assert "porous80 seed 1:" in progress and "hrtem seed 1:" in progress
    table = (tmp_path / "gallery.md").read_text()
    rows = [line for line in table.splitlines() if line.startswith("| ") and "exemplar" not in line]
    assert [r.split("|")[1].strip() for r in rows] == ["porous80", "hrtem"]
    assert "every phase within 3 pp: " in table and "mirror <= 0.1: " in table
    assert "connectedness C2 <= 0.3 (not an issue target): " in table
    report = json.loads((tmp_path / "gallery.json").read_text())
    run = report["runs"]["porous80"][0]
    assert run["phase_error_pp"] >= 0 and report["runs"]["hrtem"][0]["phase_error_pp"] is None
    assert set(run["scores"]) == {"front", "right", "top"} and set(run["mirror"]) == {"zy", "zx", "yx"}  # 3 views
    assert isinstance(run["traces"], list) and "no trace of the inserted slices" in table
    assert "c2_l2" in run["scores"]["front"]
    assert 0 <= run["copy"]["fraction"] <= 1 and run["seconds"] > 0
    with Image.open(tmp_path / "montage.png") as png:
        width, height = png.size
    assert height >= 2 * 128 and width >= 4 * 128


@pytest.mark.slow
def test_bench_search_runs(capsys, device, tool):
    tool("bench_search").main(["--neighborhood", "3", "--queries", "64", "--reference-queries", "8",
                                "--shape", "8", "--iterations", "1", "--device", device.device.name.strip()[:8]])
    out = capsys.readouterr().out
    assert "% of matmul" in out and "candidate distances/s" in out and "same site on 100.00% of 8" in out
    for method in ("wl", "kopf", "chen-wang"):
        assert f"{method}, exact search: brick" in out
    for method, passes, terms in (("wl", 0, "every term"), ("kopf", 1, "16 principal components"),
                                  ("chen-wang", 0, "every term")):  # kopf's defaults on a grey exemplar
        assert f"{method}, coherence search, first {passes} pass(es) exhaustive on {terms}: brick" in out
    assert "end to end" in out


def test_gallery_counts_a_blended_voxel_for_its_nearest_level(tool):
    from types import SimpleNamespace

    import numpy as np

    res = SimpleNamespace(labels=None, level_values=np.array([0, 128, 255], np.uint8),  # uint8, as exemplars
                          volume=np.array([10.0, 130.0, 250.0, 200.0, 63.9]), exemplar_labels=np.zeros(2, np.uint8))
    assert tool("gallery").level_indices(res)[0].tolist() == [0, 1, 2, 2, 0]


def test_eta_tool_reports_the_error(capsys, tool):
    tool("eta").main(["--names", "porous80", "--shape", "16", "--set", "neighborhood=5", "--set", "scales=2"])
    out = capsys.readouterr().out
    assert "porous80:" in out and "ETA error after the first:" in out and " %" in out


def test_eta_tool_can_measure_the_fallback_and_leaves_the_library_as_it_was(capsys, tool):
    from clsolid.ml import forecast

    library = forecast.REPLAY_TERMS
    tool("eta").main(["--names", "porous80", "--shape", "16", "--set", "neighborhood=5", "--set", "scales=2",
                      "--replay-terms", "0"])
    out = capsys.readouterr().out
    assert "replayed up to 0 terms a sweep" in out and "porous80:" in out
    assert forecast.REPLAY_TERMS == library


def test_prune_check_tool_compares_the_pruned_lcpdf(capsys, tool):
    tool("prune_check").main(["--names", "porous80", "--shape", "16", "--voxels", "50", "--counts", "4", "9999",
                              "--set", "neighborhood=5", "--set", "scales=2", "--temperature", "0.9"])
    out = capsys.readouterr().out
    assert "porous80" in out and "nearest    4: TV" in out
    assert "nearest 9999: TV 0.000 (99 %: 0.000), same level 100.0%" in out  # more than the sites: the exact sum


@pytest.mark.slow
def test_prune_check_pca_with_every_axis_finds_the_nearest_sites(capsys, tool):
    # all 24 axes of a 5x5 window: the projected distance is the distance (fall-off weights
    # included), so its nearest 16 give the exact sum's; one axis does not
    tool("prune_check").main(["--names", "gravel", "--shape", "16", "--voxels", "60", "--counts", "16",
                              "--pca", "1", "24", "--set", "neighborhood=5", "--set", "scales=2"])
    out = capsys.readouterr().out
    assert "view 1, PCA 24, nearest   16: TV 0.000 (99 %: 0.000), same level 100.0%" in out
    assert "view 1, PCA  1, nearest   16: TV 0.000" not in out and "view 1, nearest   16: TV 0.000" in out


@pytest.mark.slow
def test_prune_error_reports_every_sweep(capsys, device, tool):
    tool("prune_error").main(["--names", "porous50", "--shape", "12", "--sample", "20", "--set", "scales=2",
                              "--device", device.device.name.strip()[:8]])
    out = capsys.readouterr().out
    assert "porous50:" in out and "pruned" in out and "scale 0 sweep 1:" in out


@pytest.mark.slow
def test_prune_error_measures_projected_candidates(capsys, device, tool):
    # more candidates than sites: the projected set is every site, so the exact sum
    tool("prune_error").main(["--names", "gravel", "--shape", "12", "--sample", "20", "--set", "scales=2",
                              "--set", "neighborhood=5", "--pca", "4", "99999",
                              "--device", device.device.name.strip()[:8]])
    out = capsys.readouterr().out
    assert "gravel:" in out and "PCA: TV 0.0000 (99 %: 0.000), same mode 100.0%" in out


@pytest.mark.slow
@pytest.mark.parametrize("scratch", [False, True], ids=["in-memory", "scratch"])
def test_bench_scale_prints_a_row_per_run(capsys, device, tool, scratch, tmp_path):
    bench = tool("bench_scale")
    bench.main(["--cases", "64:8", "--names", "porous50", "--tile", "5", "--device",
                device.device.name.strip()[:8]] + (["--scratch", str(tmp_path)] if scratch else []))
    out = capsys.readouterr().out
    assert "GFLOP/s" in out and "| porous50 | 64² → 8³ | exact |" in out and "| porous50 | 64² → 8³ | pruned |" in out
    assert "tiles of 5" in out and out.count("| yes |") == 2  # a tiled run is the one-piece run
    if scratch:
        assert list(tmp_path.iterdir()) == []  # its files gone
        with pytest.raises(SystemExit):
            bench.main(["--scratch", str(tmp_path)])  # needs --tile


@pytest.mark.slow
def test_bench_scale_runs_tiles_alone_and_says_every_sweep(capsys, device, tool):
    bench = tool("bench_scale")
    bench.main(["--cases", "64:8", "--names", "porous50", "--likelihoods", "pruned", "--tile", "5", "--tiled-only",
                "--verbose", "--device", device.device.name.strip()[:8]])
    captured = capsys.readouterr()
    assert "| porous50 | 64² → 8³, tiles of 5 | pruned |" in captured.out and "same volume" not in captured.out
    assert "scale 1/" in captured.err and "visits" in captured.err
    with pytest.raises(SystemExit):
        bench.main(["--tiled-only"])  # needs --tile


def test_gallery_isolated_share_is_over_the_exemplars_of_at_least_one_pixel(tool):
    """A clean exemplar has no isolated pixel: its share counts as one pixel's, so a volume
    with one isolated voxel in 64 against a 64-pixel exemplar scores 1; grey levels count a
    voxel unlike every neighbour by more than the exemplar's steps."""
    from types import SimpleNamespace

    isolated = tool("gallery").isolated
    exemplar = np.zeros((8, 8), np.uint8)
    exemplar[:, 4:] = 1
    volume = np.zeros((4, 4, 4), np.uint8)
    volume[1, 1, 1] = 1
    res = SimpleNamespace(labels=volume, exemplar_labels=exemplar, exemplar=exemplar, volume=volume)
    assert isolated(res, True) == {"volume": 1 / 64, "exemplar": 0.0, "ratio": 1.0}
    grey = SimpleNamespace(exemplar=np.add.outer(np.arange(8.0), np.arange(8.0)), volume=np.zeros((4, 4, 4)))
    grey.volume[1, 1, 1] = 100.0
    assert isolated(grey, False) == {"volume": 1 / 64, "exemplar": 0.0, "ratio": 1.0}


def test_gallery_counts_targets_seed_by_seed(tool):
    """With several seeds the table shows each exemplar's worst seed, and the counts come both
    from those worst cells and from each seed's own runs."""
    gallery = tool("gallery")

    def run(mirror, patch, seed):
        scores = {v: {key: None for key, _ in gallery.SCORES} for v in gallery.VIEWS}
        for v in gallery.VIEWS:
            scores[v]["patch_sw"] = patch
        return {"phase_error_pp": 0.5, "scores": scores, "mirror_max": mirror, "mirror_chance": 0.05,
                "copy": {"fraction": 0.5, "view": "front", "index": 3, "inserted": False, "chance": 0.4},
                "seconds": 1.0, "constrained": ["front", "right"], "seed": seed}

    runs = {"porous80": [run(0.05, 0.1, 1), run(0.2, 0.1, 2)],   # the mirror missed on seed 2 only
            "inclusions": [run(0.15, 0.1, 1), run(0.05, 0.5, 2)]}  # the mirror on seed 1, patches on seed 2
    rows = {name: gallery.summarise(r) for name, r in runs.items()}
    settings = {"method": "ml", "size": 64, "shape": 48, "seeds": [1, 2], "options": {}, "device": "x"}
    table = gallery.markdown(rows, settings, runs)
    assert "- mirror <= 0.1: 0/2\n" in table and "- patch <= 0.3: 1/2\n" in table  # worst cells
    assert "Seed by seed (1, 2):" in table
    assert "- mirror <= 0.1: 1/2 · 1/2\n" in table and "- patch <= 0.3: 2/2 · 1/2\n" in table
    assert "Seed by seed" not in gallery.markdown(rows, dict(settings, seeds=[1]), runs)
    assert "2 pp" not in table  # the stricter targets are kopf's alone


def test_gallery_counts_kopfs_own_targets(tool):
    """`kopf` is also held to stricter targets: phases within 2 points, histogram <= 0.05."""
    gallery = tool("gallery")
    scores = {v: {key: None for key, _ in gallery.SCORES} for v in gallery.VIEWS}
    for v in gallery.VIEWS:
        scores[v]["histogram_kl"] = 0.07  # within the common 0.1, not kopf's stricter 0.05
    row = {"phase_error_pp": 1.5, "scores": scores, "mirror": 0.0, "mirror_chance": 0.0, "stretch": 1.0,
           "copy": {"fraction": 0.5}, "seconds": 1.0, "constrained": ["front", "right"]}
    other = dict(row, phase_error_pp=2.5)  # within 3 points, not 2
    counts = {label: count for label, count, _ in gallery.target_counts({"a": row, "b": other}, "kopf")}
    stricter = "(kopf's stricter target)"
    assert counts["every phase within 3 pp"] == "2/2" and counts[f"every phase within 2 pp {stricter}"] == "1/2"
    assert counts["histogram <= 0.1"] == "2/2" and counts[f"histogram <= 0.05 {stricter}"] == "0/2"
    assert not any(stricter in label for label, _, _ in gallery.target_counts({"a": row}, "ml"))


def test_gallery_compares_two_galleries_in_every_view(tool, tmp_path):
    """--compare: one row per exemplar in both, each cell the worst seed before -> after, the
    scores' worst view taken over all three views; the counts of exemplars within each limit."""
    import json

    gallery = tool("gallery")

    def run(top_autocorr, isolated):
        scores = {v: {key: 0.1 for key, _ in gallery.SCORES} for v in gallery.VIEWS}
        scores["top"]["autocorrelation_l2"] = top_autocorr
        return {"scores": scores, "mirror_max": 0.05, "stretch_max": 0.8, "isolated": {"ratio": isolated}}

    settings = {"method": "ml", "seeds": [1, 2], "options": {}}
    before = {"settings": settings, "runs": {"porous50": [run(0.2, 9.0), run(0.9, 4.0)], "gone": [run(0.1, 1.0)]}}
    after = {"settings": dict(settings, options={"views": 3}), "runs": {"porous50": [run(0.1, 1.2), run(0.2, 1.0)]}}
    for name, data in (("b.json", before), ("a.json", after)):
        (tmp_path / name).write_text(json.dumps(data))
    assert gallery.main(["--compare", str(tmp_path / "b.json"), str(tmp_path / "a.json"), "-o", str(tmp_path)]) == 0
    text = (tmp_path / "compare.md").read_text()
    row = next(line for line in text.splitlines() if line.startswith("| porous50"))
    assert "| 0.90 → 0.20 |" in row and "| 9.0 → 1.2 |" in row and "| 1.25 → 1.25 |" in row  # stretch 0.8: 1.25x
    assert "gone" not in text
    assert "- autocorr, worst view: 0/1 → 1/1" in text and "- isolated: 0/1 → 1/1" in text
    assert gallery.main(["--compare", str(tmp_path / "b.json"), str(tmp_path / "nothing.json"),
                         "-o", str(tmp_path)]) == 2


def test_gallery_merges_runs_split_by_exemplar(tool, tmp_path, capsys):
    """--merge: the table of two runs over different exemplars is the table of one run over
    both, and so for two runs over different seeds; runs with other settings, or measuring an
    exemplar with one seed twice, are refused."""
    import json

    gallery = tool("gallery")

    def run(mirror, seed=1):
        scores = {v: {key: 0.1 for key, _ in gallery.SCORES} for v in gallery.VIEWS}
        return {"phase_error_pp": 0.5, "scores": scores, "mirror_max": mirror, "mirror_chance": 0.05,
                "copy": {"fraction": 0.5, "view": "front", "index": 3, "inserted": False, "chance": 0.4},
                "seconds": 1.0, "constrained": ["front", "right"], "seed": seed}

    settings = {"method": "ml", "size": 64, "shape": 48, "seeds": [1], "options": {}, "device": "cpu"}
    parts = {"a": {"porous80": [run(0.05)]}, "b": {"inclusions": [run(0.2)], "grains": [run(0.0)]}}
    paths = []
    for key, runs in parts.items():
        gallery.write_report(tmp_path / key, settings, runs)
        paths.append(str(tmp_path / key / "gallery.json"))
    assert gallery.main(["--merge", *paths, "-o", str(tmp_path / "ab")]) == 0
    gallery.write_report(tmp_path / "one", settings, {**parts["a"], **parts["b"]})
    assert (tmp_path / "ab" / "gallery.md").read_text() == (tmp_path / "one" / "gallery.md").read_text()
    merged = json.loads((tmp_path / "ab" / "gallery.json").read_text())
    assert list(merged["runs"]) == ["porous80", "inclusions", "grains"]
    assert "- mirror <= 0.1: 2/3\n" in (tmp_path / "ab" / "gallery.md").read_text()
    capsys.readouterr()
    assert gallery.main(["--merge", paths[0], paths[0], "-o", str(tmp_path / "aa")]) == 2
    assert "porous80 with seed 1 measured in more than one" in capsys.readouterr().err
    gallery.write_report(tmp_path / "c", dict(settings, shape=32), {"grains": [run(0.0)]})
    assert gallery.main(["--merge", paths[0], str(tmp_path / "c" / "gallery.json"), "-o", str(tmp_path / "ac")]) == 2
    assert "shape differ" in capsys.readouterr().err
    assert not (tmp_path / "aa").exists() and not (tmp_path / "ac").exists()
    later = {"porous80": [run(0.3, seed=2)], "grains": [run(0.0, seed=2)]}  # seed 2 after seed 1
    gallery.write_report(tmp_path / "d", dict(settings, seeds=[2]), later)
    assert gallery.main(["--merge", str(tmp_path / "d" / "gallery.json"), paths[0], "-o", str(tmp_path / "ad")]) == 0
    both = {"porous80": [run(0.05), run(0.3, seed=2)], "grains": [run(0.0, seed=2)]}
    gallery.write_report(tmp_path / "two", dict(settings, seeds=[1, 2]), both)
    assert (tmp_path / "ad" / "gallery.md").read_text() == (tmp_path / "two" / "gallery.md").read_text()


def test_mirror_noise_spread_of_white_noise(tool):
    """White noise: only the diagonal plane's voxels are their own mirror, so the mean is
    1/side; the rest are independent pairs, so the spread is sqrt(2/N) (N voxels)."""
    import numpy as np

    noise = tool("mirror_noise")
    side = 16
    r = noise.mirror_spread(np.random.default_rng(5).standard_normal((64, 64)), side, samples=200, seed=1)
    assert r.mean() == pytest.approx(1 / side, abs=0.006)
    assert r.std() == pytest.approx(np.sqrt(2 / side**3), rel=0.2)


def test_mirror_noise_covariance_holds_the_exemplars_sections(tool):
    """Every vertical section of the modelled material has the exemplar's correlation
    (symmetrised in x), and so does every direction about y (here: along z)."""
    import numpy as np

    rng = np.random.default_rng(2)
    ex = np.cumsum(np.cumsum(rng.standard_normal((32, 32)), axis=0), axis=1)  # long-range, anisotropic
    cov = tool("mirror_noise").section_covariance(ex, 12)
    a = ex - ex.mean()
    acf = np.real(np.fft.ifft2(np.abs(np.fft.fft2(a)) ** 2))
    acf /= acf[0, 0]
    sym = 0.5 * (acf + acf[:, (-np.arange(32)) % 32])
    assert np.allclose(cov[0, :3, :3], sym[[0, 1, 2]][:, :3])  # (dy, dx) for dz = 0
    assert np.allclose(cov[:3, :3, 0].T, sym[[0, 1, 2]][:, :3])  # (dy, dz) for dx = 0
    assert np.allclose(cov[0, -1, :3], sym[-1, :3])  # negative dy wraps


def test_mirror_noise_places_a_gallery_run_in_the_spread(capsys, tmp_path, tool):
    import json

    (tmp_path / "gallery.json").write_text(json.dumps({"runs": {"grains": [{"mirror": {"zx": 0.5}},
                                                                           {"mirror": {"zx": 0.2}}]}}))
    tool("mirror_noise").main(["--names", "grains", "porous80", "--side", "12", "--samples", "8",
                               "--gallery", str(tmp_path / "gallery.json")])
    out = capsys.readouterr().out
    assert "| grains | " in out and "| 0.50 (+" in out and out.rstrip().endswith("| – |")


@pytest.mark.slow
def test_photo_windows_stay_inside_the_photograph_and_are_scored(capsys, tool):
    import numpy as np

    photo_windows = tool("photo_windows")
    photo = np.arange(40 * 40).reshape(40, 40)
    stack = photo_windows.windows(photo, 16, 50, seed=3)
    assert stack.shape == (50, 16, 16)
    r, c = np.divmod(stack[:, 0, 0], 40)  # each window's corner
    assert (r <= 24).all() and (c <= 24).all()
    np.testing.assert_array_equal(stack, [photo[i: i + 16, j: j + 16] for i, j in zip(r, c)])  # never wrapped
    away = photo_windows.windows(photo, 16, 50, seed=3, away=True)
    assert (np.divmod(away[:, 0, 0], 40)[0] >= 20).all()
    photo_windows.main(["--names", "gravel", "tissue", "--sides", "24", "--seeds", "1"])
    rows = [line.split("|") for line in capsys.readouterr().out.splitlines()[-2:]]
    assert [r[1].strip() for r in rows] == ["gravel", "tissue"] and rows[0][2].strip() == "24²"
    assert abs(float(rows[0][5])) < 1.0 and abs(float(rows[1][6])) < 1.0  # gravel's patch, tissue's autocorrelation


@pytest.mark.slow
def test_material_windows_of_a_generated_exemplar_come_from_new_draws(capsys, tool):
    from clsolid.gallery import gallery_draw, gallery_exemplar

    photo_windows = tool("photo_windows")
    stack = photo_windows.drawn_windows("porous50", 64, 24, draws=3, seed=2)
    assert stack.shape == (photo_windows.COUNT, 24, 24)
    draws = [gallery_draw("porous50", 64, 2 * 3 + 1 + j) for j in range(3)]
    ex = gallery_exemplar("porous50", 64)

    def found_in(w, img):
        return any((img[i: i + 24, j: j + 24] == w).all() for i in range(41) for j in range(41))
    owner = [next(j for j, d in enumerate(draws) if found_in(w, d)) for w in stack]
    assert owner == [0] * 6 + [1] * 5 + [2] * 5  # 16 windows, spread over the three draws
    assert not any(found_in(w, ex) for w in stack[:3])  # not pieces of the exemplar
    photo_windows.main(["--names", "porous50", "--size", "64", "--sides", "24", "--seeds", "1"])
    row = capsys.readouterr().out.splitlines()[-1].split("|")
    assert row[1].strip() == "porous50" and abs(float(row[5])) < 0.5 and abs(float(row[8])) < 0.5  # patch, C2 near 0


@pytest.mark.slow
def test_validate_truths_tool_tables_each_truth_method_and_phase(tmp_path, capsys, tool, device):
    tool("validate_truths").main(["--names", "iso2", "--methods", "kopf", "--side", "32", "-n", "1",
                                  "--device", device.device.name.strip()[:8], "-o", str(tmp_path)])
    table = (tmp_path / "validation.md").read_text()
    assert table.count("| iso2 | kopf |") == 2 and "S2 error z / y / x" in table
    report = json.loads((tmp_path / "iso2-kopf.json").read_text())
    assert report["real"]["ground_truth"]["side"] == 32 and report["generated"]["shape"] == [16, 16, 16]


def test_orientation_lengths_prints_a_row_per_run(capsys, device, tool):
    tool("orientation_lengths").main(["--names", "hrtem", "--methods", "kopf", "--shape", "12", "--set", "scales=2",
                                      "--set", "neighborhood=5", "--device", device.device.name.strip()[:8]])
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("hrtem")]
    assert len(rows) == 1 and "front" in rows[0] and "right" in rows[0]
