/* Nearest-neighbourhood search of the fixed-neighbourhood methods: the exact brute force
 * (the K nearest sites of every query) and the distances to given candidate sites.
 *
 * Compile-time constants:
 *   DIM  terms of a neighbourhood (k*k, or k*k + 9 with a parent level)
 *   VW   candidate sites per vector (4, 8 or 16: the device's width, from the probe)
 *   K    sites kept per query by k_nearest (1 for the best match)
 *
 * queries: (n_queries, DIM) float, row-major.
 * table_t: (DIM, n_pad) float, the sites transposed, n_pad a multiple of VW; padding
 *          columns hold 1e19, whose squared distance overflows to +inf and never wins.
 * weights: (DIM,) float, per-term weights of the squared distance (1 for a plain SSD, 0 for
 *          the terms a causal neighbourhood or a left-out centre leaves out). */

#define CAT_(a, b) a##b
#define CAT(a, b) CAT_(a, b)
typedef CAT(float, VW) floatv;
#define VLOAD CAT(vload, VW)
#define VSTORE CAT(vstore, VW)

/* sites[q*K + j], dists[q*K + j]: the query's j-th nearest site and its weighted SSD,
 * nearest first, the lower site index first among equal distances. One work-item per
 * query scans VW sites at a time; lanes are offered in increasing site order and a site
 * enters the list only below every kept distance it passes (strict <), so ties keep the
 * lowest indices. */
__kernel void k_nearest(__global const float *queries, __global const float *table_t,
                        __global const float *weights, int n_queries, int n_pad,
                        __global int *sites, __global float *dists)
{
    const int q = get_global_id(0);
    if (q >= n_queries)
        return;
    float x[DIM], w[DIM];
    for (int d = 0; d < DIM; ++d) {
        x[d] = queries[(size_t)q * DIM + d];
        w[d] = weights[d];
    }
    float top[K];
    int arg[K];
    for (int j = 0; j < K; ++j) {
        top[j] = INFINITY;
        arg[j] = 0;
    }
    float lane[VW];
    for (int c = 0; c < n_pad / VW; ++c) {
        floatv acc = (floatv)(0.0f);
        for (int d = 0; d < DIM; ++d) {
            const floatv e = (floatv)(x[d]) - VLOAD(c, table_t + (size_t)d * n_pad);
            acc = fma((floatv)(w[d]) * e, e, acc);
        }
        VSTORE(acc, 0, lane);
        for (int l = 0; l < VW; ++l) {
            if (lane[l] < top[K - 1]) {
                int j = K - 1;
                while (j > 0 && top[j - 1] > lane[l]) {
                    top[j] = top[j - 1];
                    arg[j] = arg[j - 1];
                    --j;
                }
                top[j] = lane[l];
                arg[j] = c * VW + l;
            }
        }
    }
    for (int j = 0; j < K; ++j) {
        sites[(size_t)q * K + j] = arg[j];
        dists[(size_t)q * K + j] = top[j];
    }
}

/* dists[q*n_cand + j]: the weighted SSD between query q and site cand[q*n_cand + j]
 * (+inf for a negative site: no candidate). One work-item per (query, candidate); the
 * sites are read row by row (table: (n_sites, DIM), row-major), one contiguous row each. */
__kernel void candidate_distances(__global const float *queries, __global const float *table,
                                  __global const float *weights, __global const int *cand,
                                  int n_pairs, int n_cand, __global float *dists)
{
    const int i = get_global_id(0);
    if (i >= n_pairs)
        return;
    const int site = cand[i];
    if (site < 0) {
        dists[i] = INFINITY;
        return;
    }
    __global const float *x = queries + (size_t)(i / n_cand) * DIM;
    __global const float *row = table + (size_t)site * DIM;
    float acc = 0.0f;
    for (int d = 0; d < DIM; ++d) {
        const float e = x[d] - row[d];
        acc = fma(weights[d] * e, e, acc);
    }
    dists[i] = acc;
}
