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
 *   NMIS the first NMIS kept terms are phase codes, compared by weighted mismatch: 0 where
 *        the codes are equal, else their sum (clsolid.search.codes); the rest by squared
 *        difference. 0: every term squared (grey levels)
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
#define ADD(m, wd, acc) ((acc) + (m))
#else
#define TERM(e, wd, acc) fma((wd) * (e), (e), (acc))
#define ADD(m, wd, acc) fma((wd), (m), (acc))
#endif
/* The weighted mismatch of two vectors of phase codes: 0 where equal, else the codes' sum. */
#define MISMATCH(a, b) select((floatv)(0.0f), (a) + (b), isnotequal((a), (b)))

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
            if (d < NMIS) {
                for (int b = 0; b < QB; ++b)
                    acc[b] = ADD(MISMATCH((floatv)(x[b][d]), t), (floatv)(w[d]), acc[b]);
                continue;
            }
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

/* The query's kept terms (xs: QDIM terms) and the weights as NV vectors each, zero padded. */
static void query_vectors(const float *xs, __global const int *keep, __global const float *weights,
                          floatv *x, floatv *w)
{
    float xv[NV * VW], wv[NV * VW];
    for (int d = 0; d < NV * VW; ++d) {
        xv[d] = d < DIM ? xs[keep[d]] : 0.0f;
        wv[d] = weights[d];
    }
    for (int v = 0; v < NV; ++v) {
        x[v] = VLOAD(v, xv);
        w[v] = VLOAD(v, wv);
    }
}

/* The weighted distance between a query (x, w: query_vectors) and one row of the table, VW
 * contiguous terms at a time, the VW partial sums added at the end; with NMIS, the vectors
 * holding codes compare them lane by lane (a lane below NMIS: mismatch, else squared). */
static float row_distance(const floatv *x, const floatv *w, __global const float *row)
{
    floatv acc = (floatv)(0.0f);
    for (int v = 0; v < NV; ++v) {
        const floatv t = VLOAD(v, row);
        const floatv e = x[v] - t;
#if NMIS
        if (v * VW < NMIS) {
            float lanes[VW];
            for (int l = 0; l < VW; ++l)
                lanes[l] = v * VW + l < NMIS ? 1.0f : 0.0f;
            const floatv code = VLOAD(0, lanes);
            acc = ADD(code * MISMATCH(x[v], t) + ((floatv)(1.0f) - code) * e * e, w[v], acc);
            continue;
        }
#endif
        acc = TERM(e, w[v], acc);
    }
    float lane[VW];
    VSTORE(acc, 0, lane);
    float sum = 0.0f;
    for (int l = 0; l < VW; ++l)
        sum += lane[l];
    return sum;
}

/* dists[q*n_cand + j]: the weighted SSD between query q and site cand[q*n_cand + j]
 * (+inf for a negative site: no candidate). One work-item per query, its terms read once
 * into private vectors; each candidate's row (table: (n_sites, NV * VW), row-major, zero
 * padded, as the weights are) by row_distance: in another order than k_nearest's sums
 * (equal for integer grey levels, within rounding otherwise; a candidate's distance is only
 * compared with other candidates'). */
__kernel void candidate_distances(__global const float *queries, __global const int *keep,
                                  __global const float *table,
                                  __global const float *weights, __global const int *cand,
                                  int n_queries, int n_cand, __global float *dists)
{
    const int q = get_global_id(0);
    if (q >= n_queries)
        return;
    float xs[QDIM];
    for (int d = 0; d < QDIM; ++d)
        xs[d] = queries[(size_t)q * QDIM + d];
    floatv x[NV], w[NV];
    query_vectors(xs, keep, weights, x, w);
    for (int j = 0; j < n_cand; ++j) {
        const size_t i = (size_t)q * n_cand + j;
        const int site = cand[i];
        dists[i] = site < 0 ? INFINITY : row_distance(x, w, table + (size_t)site * (NV * VW));
    }
}

#ifdef SIMILAR
/* The k-coherence search of one view for a set of voxels, gathering on the device what
 * clsolid.search.coherence does on the host (SIMILAR: sites per proposal; SPREAD: 1 to
 * rank the candidates by (sqrt(distance) + spread_eps) * excess[site], the index histogram's
 * factors: clsolid.search.usage.spread_rank; 0 by distance alone).
 *
 * The query of voxel v = voxels[i] is voxel_query's. Each of the
 * 3 x 3 neighbours n of v in the plane (v included, row by row) proposes
 * similar[shift[matched[n], j], :] (j: n's place; a row of -1 for an unknown match or an
 * invalid shift: shift and similar end with it, at row n_sites). v's match is the candidate
 * of least rank (above), the lowest site on a tie, dists[i] its row_distance; sites[i] = -1
 * (dists[i] = +inf) where no neighbour proposes one. next[v] takes the match (next holds a
 * copy of matched): every work-item reads the matches as the call began, whether or not the
 * voxels are neighbours (Kopf's overlap rule searches the whole block at once). */
__kernel void coherence_best(__global const float *vol, int vz, int vy, int vx,
                             __global const float *coarse, int cz, int cy, int cx,
                             int row_axis, int col_axis, __global const int *voxels, int n,
                             __global const int *matched, __global int *next,
                             __global const int *shift, __global const int *similar,
                             int n_sites, __global const int *keep, __global const float *table,
                             __global const float *weights, __global const float *excess, float spread_eps,
                             __global int *sites, __global float *dists)
{
    const int i = get_global_id(0);
    if (i >= n)
        return;
    const int v = voxels[i];
    const int dims[3] = {vz, vy, vx}, stride[3] = {vy * vx, vx, 1};
    const int pos[3] = {v / (vy * vx), (v / vx) % vy, v % vx};
    const int depth = 3 - row_axis - col_axis, base = pos[depth] * stride[depth];
    float xs[QDIM];
    voxel_query(vol, vz, vy, vx, coarse, cz, cy, cx, row_axis, col_axis, v, xs);
    floatv x[NV], w[NV];
    query_vectors(xs, keep, weights, x, w);
    float least = INFINITY, top = INFINITY;  /* top: the chosen candidate's score */
    int best = -1, proposed[9], n_proposed = 0;
    for (int a = 0; a < 3; ++a) {
        const int row = wrap(pos[row_axis] + a - 1, dims[row_axis]) * stride[row_axis];
        for (int b = 0; b < 3; ++b) {
            const int s = matched[base + row + wrap(pos[col_axis] + b - 1, dims[col_axis]) * stride[col_axis]];
            const int sh = shift[(s < 0 ? n_sites : s) * 9 + a * 3 + b];
            /* neighbours that continue one match propose one set: it is measured once (the
             * 9 neighbours usually propose only a few distinct sets) */
            bool again = sh < 0;
            for (int j = 0; j < n_proposed; ++j)
                again |= proposed[j] == sh;
            if (again)
                continue;
            proposed[n_proposed++] = sh;
            for (int t = 0; t < SIMILAR; ++t) {
                const int c = similar[(sh < 0 ? n_sites : sh) * SIMILAR + t];
                if (c < 0)
                    continue;
                const float d = row_distance(x, w, table + (size_t)c * (NV * VW));
#if SPREAD
                const float score = (sqrt(fmax(d, 0.0f)) + spread_eps) * excess[c];
#else
                const float score = d;
#endif
                if (score < top || (score == top && c < best)) {
                    top = score;
                    least = d;
                    best = c;
                }
            }
        }
    }
    sites[i] = best;
    dists[i] = least;
    if (best >= 0)
        next[v] = best;
}
#endif /* SIMILAR */
