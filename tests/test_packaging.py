"""The kernels are found in a source checkout and shipped inside the wheel."""

import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

import clsolid
from clsolid.core import programs
from clsolid.ml.opencl import SOURCES

ROOT = Path(__file__).resolve().parents[1]


def test_kernel_loader_finds_the_sources():
    for name in SOURCES:
        assert (programs.kernel_dir() / name).is_file()
        assert programs.read_source(name).startswith(f'#line 1 "kernels/{name}"')


@pytest.mark.slow  # builds a wheel with pip (seconds); the loader's source layout is checked above
def test_wheel_contains_the_kernels(tmp_path):
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q",
                    "-w", str(tmp_path), str(ROOT)], check=True)
    wheel = next(tmp_path.glob("clsolid-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    assert {*(f"clsolid/kernels/{name}" for name in SOURCES), "clsolid/kernels/core/init.cl",
            "clsolid/kernels/search/match.cl", "clsolid/kernels/search/gather.cl", "clsolid/search/match.py",
            "clsolid/search/block.py", "clsolid/kernels/tensor/tensor.cl", "clsolid/tensor/opencl.py"} <= set(names)
    packages = {str(d.relative_to(ROOT)) for d in (ROOT / "clsolid").rglob("__init__.py")}
    assert packages <= set(names)  # every package listed in pyproject.toml
    assert {f"clsolid/presets/{p.name}" for p in (ROOT / "clsolid" / "presets").glob("*.toml")} <= set(names)
    version = next(n for n in names if n.endswith(".dist-info/METADATA"))
    assert f"Version: {clsolid.__version__}" in zipfile.ZipFile(wheel).read(version).decode()
