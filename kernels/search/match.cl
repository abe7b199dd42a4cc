/* Exact nearest-neighbourhood search (the fixed-neighbourhood methods' brute force).
 *
 * Compile-time constants:
 *   DIM  terms of a neighbourhood (k*k, or k*k + 9 with a parent level)
 *   VW   candidate sites per vector (4, 8 or 16: the device's width, from the probe)
 *
 * queries: (n_queries, DIM) float, row-major.
 * table_t: (DIM, n_pad) float, the candidates transposed, n_pad a multiple of VW; padding
 *          columns hold 1e19, whose squared distance overflows to +inf and never wins.
 * weights: (DIM,) float, per-term weights of the squared distance (1 for a plain SSD, 0 for
 *          the terms a causal neighbourhood leaves out).
 * best_site[q]: the lowest site index of minimal weighted SSD; best_dist[q]: that SSD.
 * One work-item per query scans VW sites at a time; lanes are compared in order with a
 * strict <, and vectors in increasing order, so a tie keeps the lowest index. */

#define CAT_(a, b) a##b
#define CAT(a, b) CAT_(a, b)
typedef CAT(float, VW) floatv;
#define VLOAD CAT(vload, VW)
#define VSTORE CAT(vstore, VW)

__kernel void best_match(__global const float *queries, __global const float *table_t,
                         __global const float *weights, int n_queries, int n_pad,
                         __global int *best_site, __global float *best_dist)
{
    const int q = get_global_id(0);
    if (q >= n_queries)
        return;
    float x[DIM], w[DIM];
    for (int d = 0; d < DIM; ++d) {
        x[d] = queries[(size_t)q * DIM + d];
        w[d] = weights[d];
    }
    float best = INFINITY;
    int arg = 0;
    float lane[VW];
    for (int c = 0; c < n_pad / VW; ++c) {
        floatv acc = (floatv)(0.0f);
        for (int d = 0; d < DIM; ++d) {
            const floatv e = (floatv)(x[d]) - VLOAD(c, table_t + (size_t)d * n_pad);
            acc = fma((floatv)(w[d]) * e, e, acc);
        }
        VSTORE(acc, 0, lane);
        for (int l = 0; l < VW; ++l) {
            if (lane[l] < best) {
                best = lane[l];
                arg = c * VW + l;
            }
        }
    }
    best_site[q] = arg;
    best_dist[q] = best;
}
