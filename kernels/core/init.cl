/* The random start: every voxel takes a random pixel of the coarsest exemplar.
 * Layout as in ml/common.cl: (Z, Y, X) row-major; global id 0 = flat voxel index - first. */
#include <pyopencl-random123/philox.cl>

/* Random exemplar pixels: Philox4x32-10 keyed by the seed, counter (x, y, z, tag). vol holds
 * the n voxels of the block from flat index first on (the whole block, or a run of it). */
__kernel void init_random(__global float *vol, int Z, int Y, int X, long first, int n,
                          uint key0, uint key1, uint tag,
                          __global const float *pixels, uint n_pixels)
{
    int j = get_global_id(0);
    if (j >= n) return;
    long i = first + j;
    int z = (int)(i / ((long)Y * X));
    int rem = (int)(i - (long)z * Y * X);
    int y = rem / X, x = rem - y * X;
    philox4x32_ctr_t c = {{(uint)x, (uint)y, (uint)z, tag}};
    philox4x32_key_t k = {{key0, key1}};
    philox4x32_ctr_t r = philox4x32(c, k);
    vol[j] = pixels[mul_hi(r.v[0], n_pixels)];
}
