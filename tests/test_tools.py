"""The scripts in tools/ run (at toy sizes; their figures are not checked here)."""


def test_bench_ml_runs_with_tuning(capsys, device, tool):
    tool("bench_ml").main(["--case", "b", "--shape", "8", "8", "8", "--voxels-per-item", "2",
                            "--device", device.device.name.strip()[:8]])
    out = capsys.readouterr().out
    assert "tuning: {'voxels_per_item': 2}" in out and "% of matmul" in out and "end to end" in out


def test_quality_ml_prints_every_seed(capsys, device, tmp_path, tool):
    tool("quality_ml").main(["--seeds", "1", "2", "--shape", "8", "8", "8", "--set", "neighborhood=3",
                              "--set", "pyramid=decimate", "--save", str(tmp_path / "q"),
                              "--device", device.device.name.strip()[:8]])
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines[2:]] == ["1", "2", "mean", "worst"]
    assert (tmp_path / "q_seed2.npy").exists()


def test_relaxations_prints_fractions_per_setting(capsys, device, tool):
    tool("relaxations").main(["--shape", "8", "8", "8", "--neighborhood", "3", "--scales", "1", "--seeds", "1",
                              "--run", "relaxation=gibbs", "--run", "relaxation=annealing,sweeps=2,balance=1",
                              "--device", device.device.name.strip()[:8]])
    lines = capsys.readouterr().out.splitlines()
    assert lines[1] == "exemplar fractions [0.5, 0.3, 0.2]"
    gibbs, annealing = lines[3].split("  "), lines[4].split("  ")
    assert gibbs[0] == '{"relaxation": "gibbs"}' and gibbs[1] == "1"
    fractions = [float(f) for f in gibbs[2].strip("[]").split(",")]
    assert len(fractions) == 3 and abs(sum(fractions) - 1) < 0.01
    assert annealing[-2] == "[2]"  # the annealing run's fixed sweeps
