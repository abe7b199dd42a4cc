"""The package's layers hold: each imports only the layers below it, ml and search never
import each other, and no import cycle exists, lazy imports included (import-linter's
contracts in pyproject.toml)."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_the_import_contracts_are_kept():
    lint = shutil.which("lint-imports") or pytest.fail("lint-imports missing: pip install -e '.[test]'")
    run = subprocess.run([lint, "--no-cache"], cwd=ROOT, capture_output=True, text=True,
                         env={"PYTHONPATH": str(ROOT), "PATH": str(Path(sys.executable).parent)})
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-2000:]
    assert "0 broken" in run.stdout and "2 kept" in run.stdout


def test_every_back_end_and_runner_keeps_its_contract(device):
    from clsolid.ml.contracts import Backend, TileRunner
    from clsolid.ml.opencl import CLBackend
    from clsolid.ml.reference import ReferenceBackend
    from clsolid.ml.tiled import LocalTiles, TiledBackend

    engine = CLBackend(device)
    for backend in (ReferenceBackend(), engine, TiledBackend(LocalTiles(engine), 8)):
        assert isinstance(backend, Backend), type(backend).__name__
    assert isinstance(LocalTiles(engine), TileRunner)


def test_the_probe_runs_each_methods_smoke_test_and_not_the_api():
    from clsolid.core import probe

    assert set(probe.SMOKE_TESTS) >= {"clsolid.ml.smoke:smoke_test", "clsolid.search.smoke:smoke_test"}
    source = (ROOT / "clsolid" / "core" / "probe.py").read_text()
    assert "synthesize" not in source and "..api" not in source
