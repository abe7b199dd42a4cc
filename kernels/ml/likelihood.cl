/* NP-MRF maximum-likelihood synthesis: the per-voxel work of one relaxation step.
 *
 * Layout: volumes are (Z, Y, X), row-major; a voxel's flat index is (z * Y + y) * X + x.
 * Global id 0 enumerates work items (voxels or voxel-views of the current batch); the
 * host passes the batch's flat voxel indices, so sizes are kernel arguments and one
 * build serves every shape. Neighbours wrap around (toroidal, tileable output).
 * The buffers may hold one tile of a larger block (clsolid.ml.tiled), its halo included: the
 * kernels that draw random numbers or keep scores also take where the tile's first voxel
 * sits in the whole block (oz, oy, ox) and the block's shape (GZ, GY, GX), and use the
 * voxel's coordinates in the whole block (whole_coords), so a tiled run draws exactly what a
 * one-piece run does. One piece: origin 0, whole shape = (Z, Y, X).
 *
 * Compile-time constants (-D):
 *   NR     neighbours per view (k*k - 1)
 *   VW     exemplar sites per vector (4, 8 or 16)
 *   VB     voxel-views per work item in parzen_groups, 1, 2, 4 or 8 (they share each load)
 *   NGMAX  largest number of centre-value groups (log_sums rows hold NGV*VW, -inf padded)
 *   NLMAX  largest number of labels
 *   NVIEW  number of constrained views (2 or 3)
 *   NS     windows per source in the pruned sum's candidate sets (clsolid.ml.pruned)
 *   MISMATCH  1: values differ by [a != b] instead of (a - b)^2, 2: by [a != b] (COST[a] + COST[b])
 *          (clsolid.ml.model.difference); COSTS then lists COST[label] (labels 0..L-1)
 */
#define CAT_(a, b) a##b
#define CAT(a, b) CAT_(a, b)
typedef CAT(float, VW) floatv;
typedef CAT(int, VW) intv;
#define NLV ((NLMAX + VW - 1) / VW)   /* label vectors */
#define NGV ((NGMAX + VW - 1) / VW)   /* group vectors */

#include <pyopencl-random123/philox.cl>

/* Far below any term that can matter: exp of it is 0 in float32. */
#define NEGLIGIBLE (-87.0f)

/* Scores within TIE_TOL * max(1, |best|) of the best are ties, and the lowest label wins.
 * Exact ties are common (two one-site views centred on levels a and b tie at (a+b)/2);
 * without a tolerance float32 and float64 would break them differently. Must equal
 * clsolid.ml.reference.TIE_TOL. */
#define TIE_TOL 1e-4f

/* First index whose score is within the tie tolerance of the maximum. */
inline int first_best(const float *score, int n)
{
    float best = score[0];
    for (int l = 1; l < n; ++l) best = fmax(best, score[l]);
    float cut = best - TIE_TOL * fmax(1.0f, fabs(best));
    int l = 0;
    while (score[l] < cut) ++l;
    return l;
}

inline float hmin(floatv v)
{
#if VW == 16
    float8 a = fmin(v.lo, v.hi);
    float4 b = fmin(a.lo, a.hi);
#elif VW == 8
    float4 b = fmin(v.lo, v.hi);
#else
    float4 b = v;
#endif
    float2 c = fmin(b.lo, b.hi);
    return fmin(c.x, c.y);
}

inline float hsum(floatv v)
{
#if VW == 16
    float8 a = v.lo + v.hi;
    float4 b = a.lo + a.hi;
#elif VW == 8
    float4 b = v.lo + v.hi;
#else
    float4 b = v;
#endif
    float2 c = b.lo + b.hi;
    return c.x + c.y;
}

/* Rows NCHILD.. of a neighbourhood (parent_weight > 0: the coarser scale's 3 x 3) are read from
 * the parent block, which follows the Z x Y x X block in the volume buffer (its temperatures,
 * zeros, in the temperature buffer); without them NCHILD is NR. */
#ifndef NCHILD
#define NCHILD NR
#endif
#define PARENT(r, Z, Y, X) ((r) >= NCHILD ? (Z) * (Y) * (X) : 0)

inline int wrap(int i, int n)
{
    int r = i % n;
    return r < 0 ? r + n : r;
}

/* Flat index of (z, y, x) + off on the torus; off is usually within one period, so the
 * remainders are taken only when needed. */
inline int shifted(int z, int y, int x, int Z, int Y, int X, __global const int *off)
{
    int a = z + off[0], b = y + off[1], c = x + off[2];
    if (a < 0 || a >= Z) a = wrap(a, Z);
    if (b < 0 || b >= Y) b = wrap(b, Y);
    if (c < 0 || c >= X) c = wrap(c, X);
    return (a * Y + b) * X + c;
}

inline int neighbour(int voxel, int Y, int X, int Z, __global const int *off)
{
    int z = voxel / (Y * X), rem = voxel - z * Y * X;
    int y = rem / X, x = rem - y * X;
    return shifted(z, y, x, Z, Y, X, off);
}

/* The coordinates (x, y, z, 0) in the whole GZ x GY x GX block of voxel (z, y, x) of a tile
 * whose first voxel sits at (oz, oy, ox) of it (on the torus): the Philox counter's words. */
inline uint4 whole_coords(int z, int y, int x, int oz, int oy, int ox, int GZ, int GY, int GX)
{
    return (uint4)((x + ox) % GX, (y + oy) % GY, (z + oz) % GZ, 0u);
}

/* Fold a vector of distances into one group's running (minimum, rescaled sum). */
inline void add_chunk(floatv a, float cmin, float k, float *gmin, float *gsum)
{
    float m = *gmin;
    if (cmin < m) {
        *gsum *= exp((cmin - m) * k);   /* first chunk: exp(-inf) * 0 = 0 */
        *gmin = m = cmin;
    }
    *gsum += hsum(exp(((floatv)(m) - a) * k));   /* padding lanes: exp(-inf) = 0 */
}

/* A neighbour's pair (xw, w) from its value x and weight wr = 1 - t: (wr x, wr) for squared
 * differences, (x, wr^2) for mismatches; ADD_TERM then adds wr^2 (x - p)^2 or wr^2 [x != p]
 * to acc, for the exemplar values p (of type T). */
/* The fall-off (FALLOFF defined): neighbour r's weight 1 - t times FALLOFF_ROOT[r], the square
 * root of its Gaussian weight, so that its term weighs (1 - t)^2 times that weight. Undefined,
 * the weight is left as it is (not multiplied by 1, which could change how terms are fused). */
#ifdef FALLOFF
__constant float FALLOFF_ROOT[] = {FALLOFF};
#define TERM_WEIGHT(wr, r) ((wr) * FALLOFF_ROOT[r])
#else
#define TERM_WEIGHT(wr, r) (wr)
#endif

#if MISMATCH == 2
/* weighted: exemplar values arrive as their labels' costs (COSTS, distinct); a voxel's value,
 * a label 0..L-1, is looked up, and a mismatch costs the sum of the two */
__constant float COST[] = {COSTS};
#define PAIR(x, wr, xw, w) { xw = COST[(int)(x)]; w = (wr) * (wr); }
#define ADD_TERM(T, acc, xw, w, p) { acc += select((T)(0.0f), (w) * ((T)(xw) + (p)), (p) != (T)(xw)); }
#elif MISMATCH
#define PAIR(x, wr, xw, w) { xw = (x); w = (wr) * (wr); }
#define ADD_TERM(T, acc, xw, w, p) { acc += select((T)(0.0f), (T)(w), (p) != (T)(xw)); }
#else
#define PAIR(x, wr, xw, w) { xw = (wr) * (x); w = (wr); }
#define ADD_TERM(T, acc, xw, w, p) { T d_ = (xw) - (w) * (p); acc += d_ * d_; }
#endif

/* For VB voxel-views per work item: the log of the Parzen sum of each centre-value group,
 *   log_sums[item][g] = log sum_{p : c_p = g} exp(-k * A_p),
 *   A_p = sum_r ((1 - t_r)(x_r - y_{p,r}))^2,       k = 1 / (2 h^2).
 * Exemplar sites are sorted by centre value and padded per group to whole vectors
 * (chunk_valid lanes are real); patches is laid out [chunk][r][VW]. Each group keeps a
 * running minimum of A and a sum rescaled to it (online log-sum-exp), so nothing
 * underflows whatever the window size or the number of grey levels.
 * Item i is voxel voxels[i / n_views] seen in view i % n_views.
 * src[view * n_vox + voxel] receives the voxel's source for the pruned likelihood: the site of
 * least A, as chunk_site[c * VW + lane] names each lane's (the lowest site with its neighbourhood).
 */
__kernel void parzen_groups(__global const float *vol, __global const float *temp,
                            int Z, int Y, int X,
                            __global const int *voxels, int n_items, int n_views,
                            __global const int *offsets,      /* [view][NR][3] */
                            __global const float *patches,    /* [chunk][NR][VW] */
                            __global const int *chunk_group,
                            __global const int *chunk_valid,
                            int n_chunks, int n_groups, float k,
                            __global float *log_sums,         /* [item][NGV * VW] */
                            __global const int *chunk_site, __global int *src, int n_vox)
{
    int first = get_global_id(0) * VB;
    if (first >= n_items) return;

    float xw[VB][NR], w[VB][NR];
    for (int b = 0; b < VB; ++b) {
        int item = min(first + b, n_items - 1);   /* spare slots repeat the last item */
        int voxel = voxels[item / n_views];
        __global const int *off = offsets + (item % n_views) * NR * 3;
        for (int r = 0; r < NR; ++r) {
            int j = neighbour(voxel, Y, X, Z, off + 3 * r) + PARENT(r, Z, Y, X);
            PAIR(vol[j], TERM_WEIGHT(1.0f - temp[j], r), xw[b][r], w[b][r])
        }
    }

    float gmin[VB][NGMAX], gsum[VB][NGMAX], best[VB];
    int best_chunk[VB];
    for (int b = 0; b < VB; ++b) {
        best[b] = INFINITY;
        best_chunk[b] = 0;
    }
    for (int b = 0; b < VB; ++b)
        for (int g = 0; g < n_groups; ++g) {
            gmin[b][g] = INFINITY;
            gsum[b][g] = 0.0f;
        }

    const intv lane = (intv)(0, 1, 2, 3
#if VW >= 8
                             , 4, 5, 6, 7
#endif
#if VW == 16
                             , 8, 9, 10, 11, 12, 13, 14, 15
#endif
                             );
    for (int c = 0; c < n_chunks; ++c) {
        /* Plain operators, not fma()/vload(): PoCL leaves those builtins as calls. The
         * chunk is 4*VW-byte aligned (buffers are, and chunks are whole vectors). */
        __global const floatv *pc = (__global const floatv *)(patches + (size_t)c * NR * VW);
        /* Named accumulators: an array here would live on the stack, not in registers. */
        floatv a0 = 0.0f, a1 = 0.0f, a2 = 0.0f, a3 = 0.0f, a4 = 0.0f, a5 = 0.0f, a6 = 0.0f, a7 = 0.0f;
        for (int r = 0; r < NR; ++r) {
            floatv p = pc[r];
#define TERM(b, acc) ADD_TERM(floatv, acc, xw[b][r], w[b][r], p)
            TERM(0, a0)
#if VB > 1
            TERM(1, a1)
#endif
#if VB > 2
            TERM(2, a2) TERM(3, a3)
#endif
#if VB > 4
            TERM(4, a4) TERM(5, a5) TERM(6, a6) TERM(7, a7)
#endif
#undef TERM
        }
        int g = chunk_group[c];
        intv pad = lane >= (intv)(chunk_valid[c]);
        floatv acc[8] = {a0, a1, a2, a3, a4, a5, a6, a7};
        for (int b = 0; b < VB; ++b) {
            floatv a = select(acc[b], (floatv)(INFINITY), pad);
            float cmin = hmin(a);
            if (cmin < best[b]) {
                best[b] = cmin;
                best_chunk[b] = c;
            }
            add_chunk(a, cmin, k, &gmin[b][g], &gsum[b][g]);
        }
    }

    /* The source: the least lane of the best chunk, recomputed (one chunk per item). */
    for (int b = 0; b < VB && first + b < n_items; ++b) {
        int c = best_chunk[b];
        __global const floatv *pc = (__global const floatv *)(patches + (size_t)c * NR * VW);
        floatv a = 0.0f;
        for (int r = 0; r < NR; ++r) ADD_TERM(floatv, a, xw[b][r], w[b][r], pc[r])
        const float *as = (const float *)&a;
        int lane = 0;
        for (int l = 1; l < chunk_valid[c]; ++l)
            if (as[l] < as[lane]) lane = l;
        int item = first + b;
        src[(item % n_views) * n_vox + voxels[item / n_views]] = chunk_site[c * VW + lane];
    }

    for (int b = 0; b < VB && first + b < n_items; ++b)
        for (int g = 0; g < NGV * VW; ++g)   /* rows padded to whole vectors with -inf */
            log_sums[(size_t)(first + b) * NGV * VW + g] = g < n_groups ? log(gsum[b][g]) - k * gmin[b][g] : -INFINITY;
}


#define NRV ((NR + 7) / 8)   /* neighbours per pruned-sum row, in float8 vectors */
/* A term below exp(UNSEEN) = 2.8e-8 of its group's largest is under half a float32 ulp of
 * the group's sum (at least 1), so adding it would leave the sum as it is: it is skipped. */
#define UNSEEN (-17.4f)
#ifndef PROJ_K
#define PROJ_K 0   /* the projected candidates an item takes (prune_projected_k; 0: none) */
#endif
#define NCAND (9 * NS + PROJ_K)
#define HB (NCAND > 128 ? 9 : NCAND > 64 ? 8 : 7)   /* the candidate set's table: 2^HB slots, at least twice the candidates */
#define HS (1 << HB)

/* The slot of window wnd in the candidate set's open-addressing table: where it is, or the
 * empty slot (-1) where it would go. */
inline int slot_of(const int *seen, int wnd)
{
    uint h = ((uint)wnd * 2654435761u) >> (32 - HB);
    while (seen[h] >= 0 && seen[h] != wnd) h = (h + 1) & (HS - 1);
    return h;
}

/* The pruned sum: for items item0 <= i < n_items, the same log_sums as parzen_groups but over
 * each item's candidate windows only (clsolid.ml.pruned): the windows similar[w][0..NS-1] of
 * the sources of the voxel and its 8 in-slice neighbours (coh_off [view][9][3]), each shifted
 * back by the neighbour's exemplar offset (coh_shift [view][9][2]) on the grid of
 * grid_rows x grid_cols sites. A window stands for win_count identical sites (its term is
 * weighted by their number, win_logc = log count); win_patches rows hold NRV float8 vectors,
 * zero-padded. The nearest candidate's win_source becomes the voxel's source in that view
 * (the lowest site with its neighbourhood). The rest of the sum is estimated from n_sample
 * sites, every (n_sites / n_sample)-th from a start drawn by Philox (counter (x, y, z, tag)
 * with the voxel's whole-block coordinates, word view), each weighted n_sites / n_sample; a
 * sampled site of a candidate window is already counted and is skipped
 * (clsolid.ml.pruned.term_weights).
 */
__kernel void parzen_candidates(__global const float *vol, __global const float *temp,
                                int Z, int Y, int X, int oz, int oy, int ox, int GZ, int GY, int GX,
                                __global const int *voxels, int item0, int n_items, int n_views,
                                __global const int *offsets, __global const int *coh_off,
                                __global const int *coh_shift, __global int *src, int n_vox,
                                __global const int *window_of, __global const int *similar,
                                __global const float *win_patches,   /* [window][NRV * 8] */
                                __global const int *win_group, __global const float *win_logc,
                                __global const int *win_source, int grid_rows, int grid_cols,
                                __global const int *projected,   /* [item - item0][PROJ_K] windows, -1: none */
                                int n_projected,   /* of them to read: PROJ_K, or 0 in a sweep without */
                                int n_sample, uint key0, uint key1, uint tag,
                                int n_groups, float k, __global float *log_sums)
{
    int item = item0 + get_global_id(0);
    if (item >= n_items) return;
    int voxel = voxels[item / n_views], view = item % n_views;
    int z = voxel / (Y * X), rem = voxel - z * Y * X;
    int y = rem / X, x = rem - y * X;

    /* the distinct shifted sources */
    int base[9], nb = 0;
    for (int j = 0; j < 9; ++j) {
        int s = src[view * n_vox + shifted(z, y, x, Z, Y, X, coh_off + (view * 9 + j) * 3)];
        if (s < 0) continue;
        int r = s / grid_cols - coh_shift[(view * 9 + j) * 2];
        int c = s % grid_cols - coh_shift[(view * 9 + j) * 2 + 1];
        if (r < 0 || r >= grid_rows || c < 0 || c >= grid_cols) continue;
        int wnd = window_of[r * grid_cols + c], seen = 0;
        for (int i = 0; i < nb; ++i) seen |= base[i] == wnd;
        if (!seen) base[nb++] = wnd;
    }
    /* their similar windows, each once: a small open-addressing set keeps the distinct ones */
    int cand[NCAND], nc = 0, seen[HS];
    for (int i = 0; i < HS; ++i) seen[i] = -1;
    for (int j = 0; j < nb; ++j) {
        __global const int *sim = similar + base[j] * NS;
        for (int q = 0; q < NS; ++q) {
            int wnd = sim[q], h = slot_of(seen, wnd);
            if (seen[h] == wnd) continue;
            seen[h] = wnd;
            cand[nc++] = wnd;
        }
    }
    for (int j = 0; j < n_projected; ++j) {   /* the projected candidates (projected_nearest), each once */
        int wnd = projected[(size_t)(item - item0) * PROJ_K + j];
        if (wnd < 0) continue;
        int h = slot_of(seen, wnd);
        if (seen[h] == wnd) continue;
        seen[h] = wnd;
        cand[nc++] = wnd;
    }

    float8 xw[NRV], w[NRV];
    for (int q = 0; q < NRV; ++q) xw[q] = w[q] = (float8)(0.0f);
    float *xws = (float *)xw, *ws = (float *)w;
    __global const int *off = offsets + view * NR * 3;
    for (int r = 0; r < NR; ++r) {
        int j = shifted(z, y, x, Z, Y, X, off + 3 * r) + PARENT(r, Z, Y, X);
        PAIR(vol[j], TERM_WEIGHT(1.0f - temp[j], r), xws[r], ws[r])
    }
    floatv gmaxv[NGV], gsumv[NGV];   /* a group at a time below, a vector at a time at the end */
    for (int j = 0; j < NGV; ++j) {
        gmaxv[j] = (floatv)(-INFINITY);
        gsumv[j] = (floatv)(0.0f);
    }
    float *gmax = (float *)gmaxv, *gsum = (float *)gsumv;
    float best = INFINITY;
    int best_w = 0;
    int n_sites = grid_rows * grid_cols, start = 0;
    if (n_sample) {
        uint4 g = whole_coords(z, y, x, oz, oy, ox, GZ, GY, GX);
        philox4x32_ctr_t ctr = {{g.x, g.y, g.z, tag}};
        philox4x32_key_t key = {{key0, key1}};
        start = mul_hi(philox4x32(ctr, key).v[view], (uint)n_sites);
    }
    float log_rest = log((float)n_sites / (float)n_sample);
    /* The j-th sample site is (start + floor(j n_sites / n_sample)) mod n_sites, stepped
     * without dividing: the step's whole part, and its remainder carried. */
    int step = n_sample ? n_sites / n_sample : 0, carry = n_sample ? n_sites % n_sample : 0;
    int site = start, owed = 0;
    for (int i = 0; i < nc + n_sample; ++i) {
        int wnd;
        float e0 = 0.0f;
        if (i < nc) {
            wnd = cand[i];
        } else {   /* the sample: the site's window unless it is a candidate */
            int s = site;
            site += step;
            owed += carry;
            if (owed >= n_sample) {
                owed -= n_sample;
                ++site;
            }
            if (site >= n_sites) site -= n_sites;
            wnd = window_of[s];
            /* the next one's row, on its way while this one is summed (a sampled row is seldom cached) */
            prefetch(win_patches + (size_t)window_of[site] * NRV * 8, NRV * 8);
            if (seen[slot_of(seen, wnd)] == wnd) continue;
            e0 = log_rest;
        }
        __global const float8 *p = (__global const float8 *)(win_patches + (size_t)wnd * NRV * 8);
        float8 acc = (float8)(0.0f);
        for (int q = 0; q < NRV; ++q) ADD_TERM(float8, acc, xw[q], w[q], p[q])
        float4 h = acc.lo + acc.hi;
        float a = (h.x + h.y) + (h.z + h.w);
        if (a < best || (a == best && wnd < best_w)) {   /* the lowest window on a tie */
            best = a;
            best_w = wnd;
        }
        int g = win_group[wnd];
        float e = (i < nc ? win_logc[wnd] : e0) - k * a;   /* online log-sum-exp of the group's terms */
        if (e > gmax[g]) {
            gsum[g] = gsum[g] * exp(gmax[g] - e) + 1.0f;
            gmax[g] = e;
        } else if (e - gmax[g] > UNSEEN) {
            gsum[g] += exp(e - gmax[g]);
        }
    }
    if (best < INFINITY) src[view * n_vox + voxel] = win_source[best_w];
    /* groups without terms (the padding's too) hold a sum of 0: -inf */
    __global floatv *out = (__global floatv *)(log_sums + (size_t)item * NGV * VW);
    for (int j = 0; j < NGV; ++j)
        out[j] = select((floatv)(-INFINITY), gmaxv[j] + log(gsumv[j]), isgreater(gsumv[j], (floatv)(0.0f)));
}

#if PROJ_K > 0
#define PDV ((PROJ_D + 7) / 8)
/* Whether (a, s) comes before (b, t): the nearer, the lower index on a tie. */
#define BEFORE(a, s, b, t) ((a) < (b) || ((a) == (b) && (s) < (t)))

/* Offers (a, id) to dist/ids [0..n), the n nearest offered so far, nearest first: kept if
 * it comes BEFORE the last (ids INT_MAX: none yet). */
inline void keep_nearest(float *dist, int *ids, int n, float a, int id)
{
    if (!BEFORE(a, id, dist[n - 1], ids[n - 1])) return;
    int j = n - 1;
    for (; j > 0 && BEFORE(a, id, dist[j - 1], ids[j - 1]); --j) {
        dist[j] = dist[j - 1];
        ids[j] = ids[j - 1];
    }
    dist[j] = a;
    ids[j] = id;
}

/* Squared distance between two projections in float8 rows of PDV. */
inline float proj_distance(const float8 *q, __global const float8 *p)
{
    float8 acc = (float8)(0.0f);
    for (int d = 0; d < PDV; ++d) {
        float8 e = q[d] - p[d];
        acc += e * e;
    }
    float4 h = acc.lo + acc.hi;
    return (h.x + h.y) + (h.z + h.w);
}

/* The PROJ_K sites nearest to each item's window (items item0 <= i < n_items) by the distance
 * between projections on the exemplar windows' first PROJ_D principal axes
 * (clsolid.ml.pruned.ProjectedWindows): the window, each term times proj_scale (the fall-off's
 * square root; the temperatures left out), less proj_mean, times proj_axes [NR][PROJ_D]; its
 * squared distance to the projections of the sites it searches: those of the PROJ_P lists
 * (of n_lists, centres proj_centres [list][PROJ_D]) whose centres are nearest, the lower list
 * on a tie; list l holds the sites list_site [list_start[l] .. list_start[l + 1]), their
 * projections in the same order in proj_sites [i][PROJ_D] (float8 rows of PDV, zero-padded).
 * The PROJ_K least kept, nearest first, the lower site first on a tie. Writes their windows
 * (window_of), -1 past the sites searched, to projected [item - item0][PROJ_K]. */
__kernel void projected_nearest(__global const float *vol, int Z, int Y, int X,
                                __global const int *voxels, int item0, int n_items, int n_views,
                                __global const int *offsets, __global const float *proj_scale,
                                __global const float *proj_mean, __global const float8 *proj_axes,
                                __global const float8 *proj_centres, int n_lists,
                                __global const int *list_start, __global const int *list_site,
                                __global const float8 *proj_sites, __global const int *window_of,
                                __global int *projected)
{
    int item = item0 + get_global_id(0);
    if (item >= n_items) return;
    int voxel = voxels[item / n_views], view = item % n_views;
    int z = voxel / (Y * X), rem = voxel - z * Y * X;
    int y = rem / X, x = rem - y * X;
    float8 q[PDV];   /* the axes come in float8 rows, zero-padded past PROJ_D */
    for (int d = 0; d < PDV; ++d) q[d] = (float8)(0.0f);
    __global const int *off = offsets + view * NR * 3;
    for (int r = 0; r < NR; ++r) {
        float v = vol[shifted(z, y, x, Z, Y, X, off + 3 * r) + PARENT(r, Z, Y, X)] * proj_scale[r] - proj_mean[r];
        for (int d = 0; d < PDV; ++d) q[d] += v * proj_axes[r * PDV + d];
    }
    float lbest[PROJ_P];   /* the lists to search */
    int lists[PROJ_P];
    for (int j = 0; j < PROJ_P; ++j) {
        lbest[j] = INFINITY;
        lists[j] = INT_MAX;
    }
    for (int l = 0; l < n_lists; ++l)
        keep_nearest(lbest, lists, PROJ_P, proj_distance(q, proj_centres + (size_t)l * PDV), l);
    float best[PROJ_K];
    int site[PROJ_K];
    for (int j = 0; j < PROJ_K; ++j) {
        best[j] = INFINITY;
        site[j] = INT_MAX;
    }
    for (int p = 0; p < PROJ_P && lists[p] != INT_MAX; ++p)
        for (int i = list_start[lists[p]]; i < list_start[lists[p] + 1]; ++i)
            keep_nearest(best, site, PROJ_K, proj_distance(q, proj_sites + (size_t)i * PDV), list_site[i]);
    for (int j = 0; j < PROJ_K; ++j)
        projected[(size_t)(item - item0) * PROJ_K + j] = site[j] == INT_MAX ? -1 : window_of[site[j]];
}
#endif

/* flags[i] = 1 where voxel voxels[i] needs the exact sum (clsolid.ml.pruned.needs_exact): some
 * view's mean (1 - t)^2 over its neighbours below min_weight, or (need_source) no source yet. */
__kernel void prune_flags(__global const float *temp, int Z, int Y, int X,
                          __global const int *voxels, int n_voxels, int n_views,
                          __global const int *offsets, __global const int *src, int n_vox,
                          float min_weight, int need_source, __global int *flags)
{
    int i = get_global_id(0);
    if (i >= n_voxels) return;
    int voxel = voxels[i], flag = 0;
    int z = voxel / (Y * X), rem = voxel - z * Y * X;
    int y = rem / X, x = rem - y * X;
    for (int v = 0; v < n_views; ++v) {
        float total = 0.0f;
        for (int r = 0; r < NR; ++r) {
            float wr = 1.0f - temp[shifted(z, y, x, Z, Y, X, offsets + (v * NR + r) * 3) + PARENT(r, Z, Y, X)];
            total += wr * wr;
        }
        if ((need_source && src[v * n_vox + voxel] < 0) || total < min_weight * NR) flag = 1;
    }
    flags[i] = flag;
}


inline float vmax_all(const floatv *v, int n)
{
    floatv m = v[0];
    for (int j = 1; j < n; ++j) m = m > v[j] ? m : v[j];
    return -hmin(-m);
}

/* Normalised log f_view(label) for every label, as NLV vectors; lanes past n_labels = -inf.
 *   log f(label) = log sum_g exp(ls_g + L[g][label]),   L = -k (label - value_g)^2 ([label != value_g]: MISMATCH)
 * kern holds two tables [group][label] made on the host, label rows padded to whole vectors:
 * exp(L) (padding 1), then L (padding 0), so a padding lane is never taken for an underflow.
 * Fast path: with M = max_g ls_g, f = M + log sum_g exp(ls_g - M) exp(L[g][label]).
 * Where that sum is too small to trust in float32 (a label far from every likely group)
 * the label is summed again exactly, subtracting its own maximum over the groups, so no
 * term underflows; a vector of labels at a time, a group's terms only where one of those
 * labels would add more than exp(NEGLIGIBLE) of its maximum.
 * ls has NGV*VW entries; padding groups hold -inf. */
inline void view_logf(__global const float *ls, int n_groups, __global const float *kern, int n_labels,
                      floatv *f)
{
    floatv e[NGV];
    for (int j = 0; j < NGV; ++j) e[j] = ((__global const floatv *)ls)[j];
    float M = vmax_all(e, NGV);
    for (int j = 0; j < NGV; ++j) e[j] = exp(e[j] - (floatv)(M));
    const float *es = (const float *)e;
    /* the groups with terms: an empty one (-inf; most, in a pruned sum) adds exactly nothing */
    int near[NGMAX], n_near = 0;
    for (int g = 0; g < n_groups; ++g)
        if (ls[g] > -INFINITY) near[n_near++] = g;
    for (int j = 0; j < NLV; ++j) f[j] = (floatv)(0.0f);
    for (int i = 0; i < n_near; ++i) {
        int g = near[i];
        __global const floatv *row = (__global const floatv *)(kern + g * NLV * VW);
        for (int j = 0; j < NLV; ++j) f[j] += es[g] * row[j];
    }
    __global const floatv *lkern = (__global const floatv *)(kern + n_groups * NLV * VW);
    for (int j = 0; j < NLV; ++j) {
        intv slow = islessequal(f[j], (floatv)(1e-30f));
        f[j] = (floatv)(M) + log(f[j]);
        if (!any(slow)) continue;
        floatv mx = (floatv)(-INFINITY), s = (floatv)(0.0f);
        for (int i = 0; i < n_near; ++i)
            mx = fmax(mx, (floatv)(ls[near[i]]) + lkern[near[i] * NLV + j]);
        for (int i = 0; i < n_near; ++i) {
            floatv x = (floatv)(ls[near[i]]) + lkern[near[i] * NLV + j] - mx;
            if (any(slow & isgreater(x, (floatv)(NEGLIGIBLE)))) s += exp(x);
        }
        f[j] = select(f[j], mx + log(s), slow);
    }
    float *fs = (float *)f;
    for (int l = n_labels; l < NLV * VW; ++l) fs[l] = -INFINITY;
    /* normalise over the labels (eq. 4.4) */
    float mx = vmax_all(f, NLV);
    floatv acc = (floatv)(0.0f);
    for (int j = 0; j < NLV; ++j) acc += exp(f[j] - (floatv)(mx));
    float lse = mx + log(hsum(acc));
    for (int j = 0; j < NLV; ++j) f[j] -= (floatv)(lse);
}

/* Uniform word to a float in [0, 1): (u >> 8) * 2^-24, exact in float32 (philox.unit_float). */
inline float unit_float(uint u)
{
    return (float)(u >> 8) * (1.0f / 16777216.0f);
}

/* Gibbs: the index drawn from the distribution proportional to exp(score[l]), l < n, by
 * inverting its cumulative sum at r * total, r in [0, 1). score: NLV vectors, -inf past n
 * (its exponentials a vector at a time; the sums in label order). */
inline int draw_label(const floatv *score, int n, float r)
{
    floatv wv[NLV];
    float mx = vmax_all(score, NLV);
    for (int j = 0; j < NLV; ++j) wv[j] = exp(score[j] - (floatv)(mx));
    const float *w = (const float *)wv;
    float total = 0.0f;
    for (int l = 0; l < n; ++l) total += w[l];
    float target = r * total, cum = 0.0f;
    int last = 0;
    for (int l = 0; l < n; ++l) {
        if (w[l] > 0.0f) {
            last = l;
            cum += w[l];
            if (cum > target) return l;
        }
    }
    return last;   /* r * total rounded up to total */
}

/* Annealing (TIP14 Fig. 1): accept a proposal of log score s_new against the current
 * label's s_cur if p = exp(s_new - s_cur) > 1 or p * t_in > q. Scores within the tie
 * tolerance are equal (p = 1): exact ties are common, as in first_best. */
inline bool accept(float s_new, float s_cur, float t_in, float q)
{
    float d = s_new - s_cur;
    if (fabs(d) <= TIE_TOL * fmax(1.0f, fabs(s_cur))) d = 0.0f;
    return d > 0.0f || exp(d) * t_in > q;
}

/* Index of the label nearest to x (the first on a tie): x is a label except after h1-mean. */
inline int nearest_label(__global const float *labels, int n, float x)
{
    int best = 0;
    for (int l = 1; l < n; ++l)
        if (fabs(labels[l] - x) < fabs(labels[best] - x)) best = l;
    return best;
}

/* One relaxation step per voxel from its views' group sums, then the temperature update
 *   t = max(0, (xi + sum_r t_r) / |N|) over the union of the views' neighbourhoods.
 * A voxel whose temperature is 0 when visited is an inherited voxel being re-synthesised:
 * its value may change but its temperature stays 0. Ties (see TIE_TOL) go to the lowest label.
 * heuristic: 0 h2-product, 1 h2-min, 2 h2-max, 3 h1-lowest, 4 h1-highest, 5 h1-mean.
 * relaxation: 0 ICM (argmax), 1 Gibbs (a draw from the combined, normalised LCPDF),
 * 2 annealing (a uniform proposal, accepted as in accept()). bias[label] (NLV*VW, 0 past the
 * labels) is added to the combined log score (h2) or to each view's (h1): the balance term.
 * The random words come from Philox4x32-10 keyed (key0, key1), counter (x, y, z, tag) with
 * the voxel's whole-block coordinates:
 *   Gibbs      word v draws view v (h1), word 0 the combined LCPDF (h2);
 *   annealing  word 0 the proposal (multiply-high onto the labels), word 1 + v the q of
 *              view v (h1), word 1 the q of the combined score (h2).
 * h1 heuristics combine the per-view solutions: the argmax, a draw, or the proposal where
 * that view alone accepts it (else the current value).
 * scores[g / score_stride][label] receives, for voxels whose flat index g in the whole block is
 * a multiple of score_stride, the combined log score before the bias (h1: the sum of the
 * views' log LCPDFs).
 */
__kernel void decide(__global float *vol, __global float *temp, int Z, int Y, int X,
                     int oz, int oy, int ox, int GZ, int GY, int GX,
                     __global const int *voxels, int n_voxels, int n_views,
                     __global const float *log_sums, int n_groups, __global const float *kern,
                     __global const float *labels, int n_labels,
                     __global const int *union_offsets, int n_union, float xi,
                     int heuristic, int relaxation, __global const float *bias,
                     uint key0, uint key1, uint tag, float t_in,
                     __global float *scores, int score_stride)
{
    int i = get_global_id(0);
    if (i >= n_voxels) return;
    int voxel = voxels[i];

    floatv fv[NVIEW][NLV];
    for (int v = 0; v < n_views; ++v)
        view_logf(log_sums + (size_t)(i * n_views + v) * NGV * VW, n_groups, kern, n_labels, fv[v]);

    int z = voxel / (Y * X), rem = voxel - z * Y * X;
    int y = rem / X, x = rem - y * X;
    uint4 g = whole_coords(z, y, x, oz, oy, ox, GZ, GY, GX);
    uint u[4] = {0u, 0u, 0u, 0u};
    float x_s = vol[voxel];
    int cur = 0, prop = 0;
    if (relaxation) {
        philox4x32_ctr_t c = {{g.x, g.y, g.z, tag}};
        philox4x32_key_t key = {{key0, key1}};
        philox4x32_ctr_t r = philox4x32(c, key);
        for (int j = 0; j < 4; ++j) u[j] = r.v[j];
        if (relaxation == 2) {
            cur = nearest_label(labels, n_labels, x_s);
            prop = mul_hi(u[0], (uint)n_labels);
        }
    }
    __global const floatv *bv = (__global const floatv *)bias;
    /* The balance needs each kept voxel's combined score without the bias (clsolid.ml.balance). */
    long whole = ((long)g.z * GY + g.y) * GX + g.x;
    __global float *keep = whole % score_stride ? 0 : scores + (size_t)(whole / score_stride) * n_labels;

    float value;
    if (heuristic <= 2) {
        /* combine the views label by label, vector-wise, then decide on the combined score */
        floatv comb[NLV];
        for (int j = 0; j < NLV; ++j) {
            floatv c = fv[0][j];
            for (int v = 1; v < n_views; ++v) {
                floatv o = fv[v][j];
                c = heuristic == 0 ? c + o : heuristic == 1 ? (c < o ? c : o) : (c > o ? c : o);
            }
            comb[j] = c;
        }
        const float *cs = (const float *)comb;
        if (keep)
            for (int l = 0; l < n_labels; ++l) keep[l] = cs[l];
        for (int j = 0; j < NLV; ++j) comb[j] += bv[j];
        if (relaxation == 0)
            value = labels[first_best(cs, n_labels)];
        else if (relaxation == 1)
            value = labels[draw_label(comb, n_labels, unit_float(u[0]))];
        else
            value = accept(cs[prop], cs[cur], t_in, unit_float(u[1])) ? labels[prop] : x_s;
    } else {
        float chosen = 0.0f, chosen_p = 0.0f, mean = 0.0f;
        if (keep)   /* h1 decides per view: the product stands for the combined law */
            for (int l = 0; l < n_labels; ++l) {
                float c = 0.0f;
                for (int v = 0; v < n_views; ++v) c += ((const float *)fv[v])[l];
                keep[l] = c;
            }
        for (int v = 0; v < n_views; ++v) {
            for (int j = 0; j < NLV; ++j) fv[v][j] += bv[j];
            const float *fs = (const float *)fv[v];
            int best = cur;
            float val = x_s;
            if (relaxation == 0) {
                best = first_best(fs, n_labels);
                val = labels[best];
            } else if (relaxation == 1) {
                best = draw_label(fv[v], n_labels, unit_float(u[v]));
                val = labels[best];
            } else if (accept(fs[prop], fs[cur], t_in, unit_float(u[1 + v]))) {
                best = prop;
                val = labels[prop];
            }
            float p = fs[best], tol = TIE_TOL * fmax(1.0f, fabs(chosen_p));
            mean += val;
            /* between views, too, a near-tie keeps the earlier view */
            if (v == 0 || (heuristic == 3 && p < chosen_p - tol) || (heuristic == 4 && p > chosen_p + tol)) {
                chosen = val;
                chosen_p = p;
            }
        }
        value = heuristic == 5 ? floor(mean / n_views + 0.5f) : chosen;
    }

    float t = temp[voxel];
    if (t > 0.0f) {
        float total = 0.0f;
        for (int r = 0; r < n_union; ++r)
            total += temp[neighbour(voxel, Y, X, Z, union_offsets + 3 * r)];
        t = (xi + total) / (float)n_union;
        t = t > 0.0f ? t : 0.0f;
    }
    vol[voxel] = value;
    temp[voxel] = t;
}

/* The state of voxels[0..n) of the buffers, packed to be read back (a tile gives back only the
 * voxels it updated): values[i] = vol, values[n + i] = temp, sources[view * n + i] = src. */
__kernel void pack_state(__global const float *vol, __global const float *temp, __global const int *src,
                         int n_vox, int n_views, __global const int *voxels, int n,
                         __global float *values, __global int *sources)
{
    int i = get_global_id(0);
    if (i >= n) return;
    int voxel = voxels[i];
    values[i] = vol[voxel];
    values[n + i] = temp[voxel];
    for (int v = 0; v < n_views; ++v) sources[v * n + i] = src[v * n_vox + voxel];
}

/* The normalised per-label log LCPDF of each voxel-view (for tests and diagnostics):
 * out[item][label], with the same code path as decide. */
__kernel void lcpdf(__global const float *log_sums, int n_items, int n_groups, __global const float *kern,
                    int n_labels, __global float *out)
{
    int i = get_global_id(0);
    if (i >= n_items) return;
    floatv f[NLV];
    view_logf(log_sums + (size_t)i * NGV * VW, n_groups, kern, n_labels, f);
    const float *fs = (const float *)f;
    for (int l = 0; l < n_labels; ++l) out[(size_t)i * n_labels + l] = fs[l];
}
