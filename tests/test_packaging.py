"""The kernels are found in a source checkout and shipped inside the wheel."""

import subprocess
import sys
import zipfile
from pathlib import Path

from clsolid import _kernels

ROOT = Path(__file__).resolve().parents[1]


def test_kernel_loader_finds_the_sources():
    assert (_kernels.kernel_dir() / "ml.cl").is_file()
    assert _kernels.read_source("ml.cl").startswith('#line 1 "kernels/ml.cl"')


def test_wheel_contains_the_kernels(tmp_path):
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q",
                    "-w", str(tmp_path), str(ROOT)], check=True)
    wheel = next(tmp_path.glob("clsolid-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    assert {"clsolid/kernels/ml.cl", "clsolid/kernels/init.cl"} <= set(names)
    assert "clsolid/cli.py" in names
