import numpy as np
import pytest

from clsolid.core.philox import TAG_INIT, bounded, philox4x32, seed_key, voxel_uint32

# Random123's published known-answer vectors for philox4x32, 10 rounds.
KAT = [
    ([0, 0, 0, 0], [0, 0], [0x6627E8D5, 0xE169C58D, 0xBC57AC4C, 0x9B00DBD8]),
    ([0xFFFFFFFF] * 4, [0xFFFFFFFF] * 2, [0x408F276D, 0x41C83B0E, 0xA20BC7C6, 0x6D5451FD]),
    ([0x243F6A88, 0x85A308D3, 0x13198A2E, 0x03707344], [0xA4093822, 0x299F31D0],
     [0xD16CFE09, 0x94FDCCEB, 0x5001E420, 0x24126EA1]),
]


@pytest.mark.parametrize("ctr, key, expected", KAT)
def test_numpy_philox_matches_known_answers(ctr, key, expected):
    out = philox4x32(np.array(ctr, np.uint32), np.array(key, np.uint32))
    assert out.tolist() == expected


def test_numpy_philox_vectorises():
    ctrs = np.array([k[0] for k in KAT], np.uint32)
    keys = np.array([k[1] for k in KAT], np.uint32)
    assert philox4x32(ctrs, keys).tolist() == [k[2] for k in KAT]


@pytest.mark.each_device
def test_kernel_philox_matches_known_answers(device):
    import pyopencl as cl

    from clsolid.core import programs

    src = """
    #include <pyopencl-random123/philox.cl>
    __kernel void kat(__global const uint *c, __global const uint *k, __global uint *out) {
        int i = get_global_id(0);
        philox4x32_ctr_t ctr = {{c[4*i], c[4*i+1], c[4*i+2], c[4*i+3]}};
        philox4x32_key_t key = {{k[2*i], k[2*i+1]}};
        philox4x32_ctr_t r = philox4x32(ctr, key);
        for (int j = 0; j < 4; ++j) out[4*i+j] = r.v[j];
    }"""
    prg = cl.Program(device.context, src).build(options=programs.include_options())
    c = np.array([k[0] for k in KAT], np.uint32)
    k = np.array([k[1] for k in KAT], np.uint32)
    mf = cl.mem_flags
    cb = cl.Buffer(device.context, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=c)
    kb = cl.Buffer(device.context, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=k)
    out = np.empty_like(c)
    ob = cl.Buffer(device.context, mf.WRITE_ONLY, out.nbytes)
    prg.kat(device.queue, (len(KAT),), None, cb, kb, ob)
    cl.enqueue_copy(device.queue, out, ob)
    assert out.tolist() == [k[2] for k in KAT]


@pytest.mark.each_device
def test_init_kernel_matches_numpy(device):
    from clsolid.ml.opencl import CLBackend
    from clsolid.ml.reference import ReferenceBackend

    pixels = np.arange(37, dtype=np.float64) * 2
    shape = (5, 7, 9)
    for seed in (0, 12345, 2**63 + 11):
        a = CLBackend(device).init_volume(shape, seed, pixels)
        b = ReferenceBackend().init_volume(shape, seed, pixels)
        np.testing.assert_array_equal(a, b)


def test_streams_differ_by_seed_and_are_uniform():
    a = voxel_uint32(1, (8, 8, 8), TAG_INIT)
    b = voxel_uint32(2, (8, 8, 8), TAG_INIT)
    assert np.mean(a == b) < 0.01
    counts = np.bincount(bounded(voxel_uint32(3, (32, 32, 32), TAG_INIT), 8).ravel(), minlength=8)
    assert counts.min() > 0.9 * 32**3 / 8  # multiply-high maps uniformly onto [0, 8)
    assert seed_key(2**32 + 5).tolist() == [5, 1]
