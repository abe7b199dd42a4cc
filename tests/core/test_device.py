"""Device probing, skipping devices that cannot compile, the OpenCL vendors directory, type names."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import clsolid
from clsolid.core import icd, probe
from clsolid.cli import main
from clsolid.core.device import CPU_FIX, list_devices, select_device, type_name
from clsolid.errors import DeviceSkippedWarning, KernelBuildError, NoDeviceError

COMPILER_SAYS = "error: unknown target CPU 'generic'"


@pytest.fixture
def fresh_probes(tmp_path, monkeypatch):
    """An empty probe cache, in memory and on disk."""
    monkeypatch.setenv("CLSOLID_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(probe, "_memo", {})
    return tmp_path / "cache" / probe.CACHE_FILE


@pytest.fixture
def broken_compiler(monkeypatch, device):
    """Make every build on *device*'s platform fail as PoCL's LLVM 14 does on a Zen 5 CPU.

    Faked at the pyopencl boundary: ``Program.build`` raises pyopencl's own error.
    Returns the list of the platform names whose builds were attempted.
    """
    import pyopencl as cl

    victim = device.device.platform.name
    real_build = cl.Program.build
    attempts = []

    def build(self, *args, **kwargs):
        platform = self._context.devices[0].platform.name
        attempts.append(platform)
        if platform == victim and fails(kwargs.get("options") or (args[0] if args else [])):
            raise cl.RuntimeError(f"clBuildProgram failed: BUILD_PROGRAM_FAILURE\n\nBuild on <device>:\n\n"
                                  f"{COMPILER_SAYS}\n(options: -w)\n")
        return real_build(self, *args, **kwargs)

    fails = lambda options: True  # noqa: E731 - replaced by tests that break one width only
    monkeypatch.setattr(cl.Program, "build", build)
    _probe_in_process(monkeypatch, device)
    return attempts


def _probe_in_process(monkeypatch, device):
    """Probe *device* in this process, so that a fake ``Program.build`` applies; others as usual."""
    real = probe._in_child
    monkeypatch.setattr(probe, "_in_child", lambda dev, width: (probe.try_device(dev, width)
                                                                if dev == device.device else real(dev, width)))


def _index_of(device) -> str:
    return next(d["index"] for d in list_devices(probe_devices=False)
                if d["platform"] == device.device.platform.name.strip() and d["name"] == device.device.name.strip())


def test_probe_runs_once_then_comes_from_the_cache(fresh_probes, device, broken_compiler):
    dev = device.device
    first = probe.probe(dev)
    assert not first.ok and COMPILER_SAYS in first.message and first.vector_width is None
    tries = len(broken_compiler)
    assert tries >= 1
    probe._memo.clear()  # a new process: only the disk cache is left
    assert probe.probe(dev) == first and len(broken_compiler) == tries
    cached = json.loads(fresh_probes.read_text())
    assert cached[probe.device_key(dev)] == {"ok": False, "message": first.message, "vector_width": None}
    # the key holds the driver version: a new driver is probed again
    assert dev.driver_version.strip() in probe.device_key(dev)


@pytest.mark.slow
def test_working_device_probes_ok(fresh_probes, device):
    assert probe.probe(device.device).ok and probe.probe(device.device).vector_width in probe.VECTOR_WIDTHS


@pytest.mark.slow
def test_a_width_that_breaks_the_compiler_falls_back_to_a_narrower_one(fresh_probes, device, monkeypatch):
    """As PoCL's LLVM 14 aborts on 16-wide vectors on a Zen 4 CPU, and handles 8."""
    import pyopencl as cl

    real_build = cl.Program.build

    def build(self, options=None, *args, **kwargs):
        if any(o == "-DVW=16" for o in options or ()):
            raise cl.RuntimeError("clBuildProgram failed: LLVM ERROR: Cannot emit physreg copy instruction")
        return real_build(self, options, *args, **kwargs)

    monkeypatch.setattr(cl.Program, "build", build)
    _probe_in_process(monkeypatch, device)
    result = probe.probe(device.device)
    assert result.ok and result.vector_width == 8


def test_a_crashing_child_is_an_answer(monkeypatch, device):
    """An abort in the compiler (it kills the process) is reported, not propagated."""
    crashed = subprocess.CompletedProcess([], -6, stdout="", stderr="LLVM ERROR: Cannot emit physreg copy instruction\n")
    monkeypatch.setattr(probe.subprocess, "run", lambda *a, **k: crashed)
    result = probe._in_child(device.device, 16)
    assert not result.ok and "crashed" in result.message and "physreg" in result.message


@pytest.mark.slow
def test_the_child_probe_runs_the_real_kernels(device):
    result = probe._in_child(device.device, probe.probe(device.device).vector_width)
    assert result.ok and result.vector_width == probe.probe(device.device).vector_width


def test_explicit_choice_of_a_broken_device_says_why_and_what_to_do(fresh_probes, device, broken_compiler):
    with pytest.raises(KernelBuildError) as err:
        select_device(_index_of(device))
    text = str(err.value)
    assert device.device.name.strip() in text and COMPILER_SAYS in text
    assert (CPU_FIX if device.is_cpu else "driver") in text


def test_automatic_choice_skips_a_broken_device(fresh_probes, device, broken_compiler):
    # the other platforms' devices that really compile (on a Zen 5 PoCL's LLVM 14 cannot)
    others = [d for d in list_devices() if d["platform"] != device.device.platform.name.strip() and d["compiles"]]
    if not others:  # no other platform works: the error says how to get one that does
        with pytest.raises(NoDeviceError, match="pip install") as err:
            select_device(None)
        assert COMPILER_SAYS in str(err.value)
        return
    with pytest.warns(DeviceSkippedWarning, match="cannot compile") as caught:
        chosen = select_device(None)
    assert chosen.device.platform.name != device.device.platform.name
    assert any(COMPILER_SAYS in str(w.message) for w in caught)
    # and a synthesis runs on the device that works
    vol = clsolid.synthesize("brick", (6, 6, 6), neighborhood=3, scales=1, levels=4, rng=1, device=chosen)
    assert vol.shape == (6, 6, 6)


def test_devices_command_shows_compiles_driver_and_opencl_c(fresh_probes, device, broken_compiler, capsys):
    assert main(["devices"]) == 0
    out = capsys.readouterr().out
    assert "compiles" in out and "OpenCL C" in out and "driver" in out
    assert COMPILER_SAYS in out and " NO " in out
    listed = {d["index"]: d for d in list_devices()}
    assert listed[_index_of(device)]["compiles"] is False
    assert device.device.driver_version.strip()[:24] in out


def test_type_names_are_words_whatever_other_bits_are_set():
    import pyopencl as cl

    t = cl.device_type
    assert type_name(t.CPU) == "CPU" and type_name(t.CPU | t.DEFAULT) == "CPU"
    assert type_name(t.GPU | t.DEFAULT) == "GPU" and type_name(t.ACCELERATOR) == "ACCELERATOR"
    assert type_name(0) == "OTHER"


# ----------------------------------------------------------------------- the vendors directory


@pytest.fixture
def fake_system(tmp_path, monkeypatch):
    """A system vendors directory holding a GPU's ICD, and a pip-installed Intel library."""
    vendors = tmp_path / "etc-vendors"
    vendors.mkdir()
    (vendors / "nvidia.icd").write_text("libnvidia-opencl.so.1\n")
    (vendors / "README").write_text("not an ICD")
    lib = tmp_path / "lib" / icd.INTEL_LIBRARY
    lib.parent.mkdir()
    lib.write_bytes(b"")
    monkeypatch.setenv("OPENCL_VENDOR_PATH", str(vendors))
    monkeypatch.setenv("CLSOLID_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("OCL_ICD_VENDORS", raising=False)
    monkeypatch.setattr(icd, "_applied", None)
    monkeypatch.setattr(icd, "intel_cpu_library", lambda: lib)
    return lib


def test_vendors_directory_keeps_the_gpu_and_adds_intel(fake_system):
    folder = Path(icd.ensure_vendors())
    assert os.environ["OCL_ICD_VENDORS"] == str(folder)
    assert folder.parent == Path(os.environ["CLSOLID_CACHE_DIR"])
    files = {f.name: f.read_text().strip() for f in folder.iterdir()}
    assert files == {"nvidia.icd": "libnvidia-opencl.so.1", "clsolid-intel-cpu.icd": str(fake_system)}
    # the same entries give the same directory; a new system ICD gives a new one
    assert icd.write_vendor_dir(icd.vendor_entries(fake_system, icd.system_icds()), folder.parent) == folder
    (Path(os.environ["OPENCL_VENDOR_PATH"]) / "amd.icd").write_text("libamdocl64.so\n")
    assert icd.write_vendor_dir(icd.vendor_entries(fake_system, icd.system_icds()), folder.parent) != folder


def test_a_users_own_vendors_setting_is_left_alone(fake_system, monkeypatch):
    monkeypatch.setenv("OCL_ICD_VENDORS", "/opt/my/vendors")
    assert icd.ensure_vendors() is None and os.environ["OCL_ICD_VENDORS"] == "/opt/my/vendors"


def test_nothing_changes_without_a_pip_installed_intel_runtime(fake_system, monkeypatch):
    monkeypatch.setattr(icd, "intel_cpu_library", lambda: None)
    assert icd.ensure_vendors() is None and "OCL_ICD_VENDORS" not in os.environ


def test_the_real_loader_still_sees_every_platform(tmp_path):
    """In a fresh process with an extra (absent) GPU ICD, the platforms seen are a superset.

    The GPU's library does not exist here, so the loader skips it; what matters is that
    PoCL (found by pyopencl's own loader) and the Intel runtime (when pip installed it)
    are both listed once clsolid has written its vendors directory.
    """
    vendors = tmp_path / "vendors"
    vendors.mkdir()
    (vendors / "gpu.icd").write_text("libno-such-gpu-opencl.so\n")
    env = {k: v for k, v in os.environ.items() if k != "OCL_ICD_VENDORS"}
    env.update(OPENCL_VENDOR_PATH=str(vendors), CLSOLID_CACHE_DIR=str(tmp_path / "cache"))
    code = ("import os, json, clsolid.core.platforms as d; names = [p.name for p in d.platforms()]; "
            "print(json.dumps([names, os.environ.get('OCL_ICD_VENDORS')]))")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    names, folder = json.loads(out.stdout.strip().splitlines()[-1])
    pocl_bundled = any("Portable" in p for p in names)
    if icd.intel_cpu_library() is not None:
        assert any("Intel" in n for n in names) and folder is not None
        assert "gpu.icd" in os.listdir(folder)
    assert pocl_bundled or any("Intel" in n for n in names)
    assert len(names) == len(set(names))  # nothing listed twice


def test_probe_kernel_result_is_checked(fresh_probes, device, monkeypatch):
    """A device that builds but computes nonsense is not used either."""
    monkeypatch.setattr(probe, "_expected", lambda n, a: np.full(n, -1.0, np.float32))
    result = probe.try_device(device.device, None)
    assert not result.ok and "returned" in result.message
