/* Exact nearest-neighbourhood search (the fixed-neighbourhood methods' brute force).
 *
 * queries: (n_queries, DIM) float, row-major; table: (n_sites, DIM) float, row-major
 * (one row per exemplar site with a complete neighbourhood); weights: (DIM,) float, the
 * per-term weights of the squared distance (1 for a plain SSD, 0 for terms a causal
 * neighbourhood leaves out).
 * best_site[q] = the lowest site index of minimal weighted SSD; best_dist[q] = that SSD.
 * One work-item per query scans every site: the table (a few MB at most) stays in cache.
 * DIM is a compile-time constant so the inner loop unrolls. */

__kernel void best_match(__global const float *queries, __global const float *table,
                         __global const float *weights, int n_queries, int n_sites,
                         __global int *best_site, __global float *best_dist)
{
    const int q = get_global_id(0);
    if (q >= n_queries)
        return;
    float x[DIM];
    for (int d = 0; d < DIM; ++d)
        x[d] = queries[(size_t)q * DIM + d];
    float best = INFINITY;
    int arg = 0;
    for (int s = 0; s < n_sites; ++s) {
        __global const float *row = table + (size_t)s * DIM;
        float acc = 0.0f;
        for (int d = 0; d < DIM; ++d) {
            const float e = x[d] - row[d];
            acc = fma(weights[d] * e, e, acc);
        }
        if (acc < best) { /* strict: a tie keeps the lower index */
            best = acc;
            arg = s;
        }
    }
    best_site[q] = arg;
    best_dist[q] = best;
}
