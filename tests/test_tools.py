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


def test_compare_devices_reports_each_pair(capsys, tool):
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))  # it reuses quality_ml's helpers
    try:
        tool("compare_devices").main(["--shape", "8", "8", "8", "--set", "neighborhood=3", "--set", "scales=1"])
    finally:
        sys.path.pop(0)
    out = capsys.readouterr().out
    assert "seed 1" in out and ("identical voxels" in out or "nothing to compare" in out)
