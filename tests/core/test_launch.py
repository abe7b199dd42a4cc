"""GPU-shaped runs on the CPU runtimes: work-groups taken from the device's limits (and held to
a GPU's), no local memory, no double precision, launches that do not depend on a
work-group's size or order (docs/design.md#gpu-shaped-launches)."""

import dataclasses
import re

import numpy as np
import pytest

import clsolid
from clsolid.core import programs
from clsolid.core.launch import group_size, kernel_limit
from clsolid.gallery import gallery_exemplar

#: Work-group limits GPUs impose (a quarter of a wavefront to a whole NVIDIA block), and
#: the 32 KiB of local memory the smallest allow.
GPU_GROUPS = (32, 64, 256)
GPU_LOCAL_MEMORY = 32 * 1024


@dataclasses.dataclass
class GPUShaped(clsolid.Device):
    """The same device, treated by clsolid as a GPU: the launch shapes a GPU gets."""

    @property
    def is_cpu(self) -> bool:
        return False


def _capped(device, cap: int):
    """*device* with every work-group held to *cap* work-items (its programs shared)."""
    return dataclasses.replace(device, group_cap=cap, limits={})


def _gpu_shaped(device, cap: int | None = None):
    return GPUShaped(device.device, device.context, device.queue, device.programs, {}, cap)


def test_group_sizes_keep_to_the_device_and_the_kernel(device):
    kernel = programs.build(device, "core/init.cl")["init_random"]
    own = kernel_limit(device, kernel)
    assert 1 <= own <= int(device.device.max_work_group_size)
    for cap in (1, 3, 32, 48, 256):
        capped = _capped(device, cap)
        size = group_size(capped, kernel, 1000)
        assert size <= min(cap, own) and size & (size - 1) == 0  # a power of two within both limits
        assert group_size(capped, kernel, 2) == min(2, size)


ML_KW = dict(scales=2, neighborhood=5, rng=3)


def _ml(device, shape=(12, 14, 16), **backend):
    ex = gallery_exemplar("composite3", 64)[:32, :32]  # three phases: the weighted distance, the pruned sum
    return clsolid.synthesize(ex, shape, device=device, backend=backend or None, **ML_KW)


@pytest.mark.parametrize("local", GPU_GROUPS)
def test_ml_volumes_do_not_depend_on_the_work_group(device, local):
    np.testing.assert_array_equal(_ml(device, local_size=local), _ml(device))


@pytest.mark.each_device
@pytest.mark.parametrize("cap", GPU_GROUPS[:2])
def test_gpu_shaped_runs_give_the_cpu_shaped_volume(device, cap):
    """As a GPU: work-groups of ``local_size`` for every kernel (a CPU takes 4 for those with
    per-item arrays), held to *cap*; the search's queries per work-item a GPU's."""
    gpu = _gpu_shaped(device, cap)
    np.testing.assert_array_equal(_ml(gpu, local_size=256), _ml(device))
    grey = gallery_exemplar("gravel", 64)[:32, :32]
    for method in ("kopf", "wl"):
        kw = dict(method=method, scales=2, neighborhood=5, rng=2, iterations=2)
        np.testing.assert_array_equal(clsolid.synthesize(grey, (10, 12, 14), device=gpu, **kw),
                                      clsolid.synthesize(grey, (10, 12, 14), device=device, **kw))


def test_every_kernel_run_keeps_within_a_gpus_local_memory(device):
    """Every kernel a run of each method builds uses at most 32 KiB of local memory (none: the
    kernels share nothing within a work-group)."""
    import pyopencl as cl

    _ml(device)
    grey = gallery_exemplar("gravel", 64)[:32, :32]
    for method, extra in (("kopf", {}), ("wl", {"search": "coherence"}), ("chen-wang", {})):
        clsolid.synthesize(grey, (10, 12, 14), method=method, device=device, scales=2, neighborhood=5, rng=1,
                           iterations=1, **extra)
    kernels = [k for built in device.programs.values() if isinstance(built, dict) for k in built.values()]
    assert len(kernels) >= 8
    for kernel in kernels:
        used = kernel.get_work_group_info(cl.kernel_work_group_info.LOCAL_MEM_SIZE, device.device)
        assert used <= GPU_LOCAL_MEMORY, kernel.function_name


def test_no_kernel_needs_double_precision():
    """Devices without cl_khr_fp64 (many GPUs, some in float64 at a 64th of the rate) run the
    same kernels: no double, half or fp64 pragma anywhere in them."""
    sources = list(programs.kernel_dir().rglob("*.cl"))
    assert len(sources) >= 6
    for path in sources:
        text = re.sub(r"/\*.*?\*/|//[^\n]*", "", path.read_text(), flags=re.S)  # code, not comments
        assert not re.search(r"\b(double\d*|half\d*)\b|cl_khr_fp(64|16)", text), path.name
