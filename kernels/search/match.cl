/* Nearest-neighbourhood search of the fixed-neighbourhood methods: the exact brute force
 * (the K nearest sites of every query) and the distances to given candidate sites.
 *
 * Compile-time constants:
 *   QDIM terms of a query (k*k, or k*k + 9 with a parent level)
 *   DIM  terms of nonzero weight, those the distance sums (keep: their places in a query)
 *   VW   candidate sites per vector (4, 8 or 16: the device's width, from the probe)
 *   K    sites kept per query by k_nearest (1 for the best match)
 *   QB   queries per work-item of k_nearest
 *   UNIT 1 if every weight is 1 (the multiply is left out), else 0
 *
 * queries: (n_queries, QDIM) float, row-major.
 * table_t: (DIM, n_pad) float, the sites transposed, n_pad a multiple of VW; padding
 *          columns hold 1e19, whose squared distance overflows to +inf and never wins.
 * weights: (DIM,) float, per-term weights of the squared distance (1 for a plain SSD, 0 for
 *          the terms a causal neighbourhood or a left-out centre leaves out). */

#define CAT_(a, b) a##b
#define CAT(a, b) CAT_(a, b)
typedef CAT(float, VW) floatv;
#define VLOAD CAT(vload, VW)
#define VSTORE CAT(vstore, VW)

/* The distance of one term: the weight is 1 on every term the host kept (UNIT = 1, the
 * usual case: terms of weight 0 are dropped before the launch, which changes no sum, since
 * their products are exactly 0), or read per term. */
#if UNIT
#define TERM(e, wd, acc) fma((e), (e), (acc))
#else
#define TERM(e, wd, acc) fma((wd) * (e), (e), (acc))
#endif

/* sites[q*K + j], dists[q*K + j]: the query's j-th nearest site and its weighted SSD,
 * nearest first, the lower site index first among equal distances. One work-item takes
 * QB queries (each table vector loaded once serves all of them) and scans VW sites at a
 * time; a vector's lanes are offered to a query's list only if one of them beats its
 * worst kept distance, and then in increasing site order, a site entering only below
 * every kept distance it passes (strict <), so ties keep the lowest indices. The sums are
 * the same, term by term in the same order, whatever QB is. */
__kernel void k_nearest(__global const float *queries, __global const int *keep,
                        __global const float *table_t, __global const float *weights, int n_queries, int n_pad,
                        __global int *sites, __global float *dists)
{
    const int q0 = get_global_id(0) * QB;
    if (q0 >= n_queries)
        return;
    float x[QB][DIM], w[DIM];
    for (int d = 0; d < DIM; ++d)
        w[d] = weights[d];
    for (int b = 0; b < QB; ++b) {
        const size_t q = (size_t)min(q0 + b, n_queries - 1); /* past the end: a copy, not written */
        for (int d = 0; d < DIM; ++d)
            x[b][d] = queries[q * QDIM + keep[d]];
    }
    float top[QB][K];
    int arg[QB][K];
    for (int b = 0; b < QB; ++b)
        for (int j = 0; j < K; ++j) {
            top[b][j] = INFINITY;
            arg[b][j] = 0;
        }
    float lane[VW];
    for (int c = 0; c < n_pad / VW; ++c) {
        floatv acc[QB];
        for (int b = 0; b < QB; ++b)
            acc[b] = (floatv)(0.0f);
        for (int d = 0; d < DIM; ++d) {
            const floatv t = VLOAD(c, table_t + (size_t)d * n_pad);
            for (int b = 0; b < QB; ++b) {
                const floatv e = (floatv)(x[b][d]) - t;
                acc[b] = TERM(e, (floatv)(w[d]), acc[b]);
            }
        }
        for (int b = 0; b < QB; ++b) {
            if (!any(isless(acc[b], (floatv)(top[b][K - 1]))))
                continue;
            VSTORE(acc[b], 0, lane);
            for (int l = 0; l < VW; ++l) {
                if (lane[l] < top[b][K - 1]) {
                    int j = K - 1;
                    while (j > 0 && top[b][j - 1] > lane[l]) {
                        top[b][j] = top[b][j - 1];
                        arg[b][j] = arg[b][j - 1];
                        --j;
                    }
                    top[b][j] = lane[l];
                    arg[b][j] = c * VW + l;
                }
            }
        }
    }
    for (int b = 0; b < QB && q0 + b < n_queries; ++b)
        for (int j = 0; j < K; ++j) {
            sites[(size_t)(q0 + b) * K + j] = arg[b][j];
            dists[(size_t)(q0 + b) * K + j] = top[b][j];
        }
}

/* Vectors of VW terms a candidate's row takes (the rows are padded with zeros to NV * VW). */
#define NV ((DIM + VW - 1) / VW)

/* dists[q*n_cand + j]: the weighted SSD between query q and site cand[q*n_cand + j]
 * (+inf for a negative site: no candidate). One work-item per query, its terms read once
 * into private vectors; each candidate's row (table: (n_sites, NV * VW), row-major, zero
 * padded, as the weights are) is read VW contiguous terms at a time, and the VW partial
 * sums added at the end (in another order than k_nearest's: equal for integer grey levels,
 * within rounding otherwise; a candidate's distance is only compared with other candidates'). */
__kernel void candidate_distances(__global const float *queries, __global const int *keep,
                                  __global const float *table,
                                  __global const float *weights, __global const int *cand,
                                  int n_queries, int n_cand, __global float *dists)
{
    const int q = get_global_id(0);
    if (q >= n_queries)
        return;
    float xs[NV * VW], ws[NV * VW], lane[VW];
    for (int d = 0; d < NV * VW; ++d) {
        xs[d] = d < DIM ? queries[(size_t)q * QDIM + keep[d]] : 0.0f;
        ws[d] = weights[d];
    }
    floatv x[NV], w[NV];
    for (int v = 0; v < NV; ++v) {
        x[v] = VLOAD(v, xs);
        w[v] = VLOAD(v, ws);
    }
    for (int j = 0; j < n_cand; ++j) {
        const size_t i = (size_t)q * n_cand + j;
        const int site = cand[i];
        float sum = INFINITY;
        if (site >= 0) {
            __global const float *row = table + (size_t)site * (NV * VW);
            floatv acc = (floatv)(0.0f);
            for (int v = 0; v < NV; ++v) {
                const floatv e = x[v] - VLOAD(v, row);
                acc = TERM(e, w[v], acc);
            }
            VSTORE(acc, 0, lane);
            sum = 0.0f;
            for (int l = 0; l < VW; ++l)
                sum += lane[l];
        }
        dists[i] = sum;
    }
}
