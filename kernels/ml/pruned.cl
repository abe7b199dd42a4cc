/* The pruned Parzen sum (clsolid.ml.pruned): each voxel-view's sum over candidate windows (its
 * neighbours' sources, shifted, and their similar windows; optionally the windows nearest by
 * a projection) plus a sample of the other sites; and which voxels still need the exact sum.
 * Needs common.cl before it. */

#define NRV ((NT + 7) / 8)   /* terms per pruned-sum row (a colour's channels each one), in float8 vectors */
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
 * sites, every (n_sites / n_sample)-th from a start drawn by Philox (counter (x, y, z, sample_tag)
 * with the voxel's whole-block coordinates, word view), each weighted n_sites / n_sample; a
 * sampled site of a candidate window is already counted and is skipped
 * (clsolid.ml.pruned.term_weights).
 */
__kernel void parzen_candidates(__constant const ml_scalars *P, int item0, int n_items,
                                /* the state */
                                __global const float *vol, __global const float *temp, __global int *src,
                                /* the batch */
                                __global const int *voxels, __global float *log_sums,
                                /* the window terms (common.cl) */
                                __global const int *offsets,
                                __constant const float *term_root, __global const float *label_cost,
                                /* the coherence: in-slice neighbours [view][9][3], exemplar shifts [view][9][2] */
                                __global const int *coh_off, __global const int *coh_shift,
                                /* the exemplar's distinct windows */
                                __global const int *window_of, __global const int *similar,
                                __global const float *win_patches,   /* [window][NRV * 8] */
                                __global const int *win_group, __global const float *win_logc,
                                __global const int *win_source,
                                /* [item - item0][PROJ_K] windows, -1: none (projected_nearest) */
                                __global const int *projected)
{
    int item = item0 + get_global_id(0);
    if (item >= n_items) return;
    const int Z = P->Z, Y = P->Y, X = P->X, n_vox = P->n_vox, n_views = P->n_views;
    const int grid_rows = P->grid_rows, grid_cols = P->grid_cols, n_groups = P->n_groups;
    const int n_sample = P->n_sample, n_projected = P->n_projected;
    const float k = P->k;
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
        PAIRS(label_cost, vol[j], TERM_WEIGHT(term_root, 1.0f - temp[j], r), xws, ws, r)
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
        uint4 g = whole_coords(z, y, x, P->oz, P->oy, P->ox, P->GZ, P->GY, P->GX);
        philox4x32_ctr_t ctr = {{g.x, g.y, g.z, P->sample_tag}};
        philox4x32_key_t key = {{P->key0, P->key1}};
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

/* The projected candidates (clsolid.ml.pruned.ProjectedWindows), compiled where there are any:
 * PROJ_K windows an item takes, PROJ_D principal axes, PROJ_P lists of sites searched. */
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
 * (of n_lists, all of them where there are fewer; centres proj_centres [list][PROJ_D]) whose
 * centres are nearest, the lower list on a tie; list l holds the sites
 * list_site [list_start[l] .. list_start[l + 1]), their projections in the same order in
 * proj_sites [i][PROJ_D] (float8 rows of PDV, zero-padded).
 * The PROJ_K least kept, nearest first, the lower site first on a tie. Writes their windows
 * (window_of), -1 past the sites searched, to projected [item - item0][PROJ_K]. */
__kernel void projected_nearest(__constant const ml_scalars *P, int item0, int n_items,
                                __global const float *vol, __global const int *voxels, __global const int *offsets,
                                /* the projection: per term [NR], axes [NR][PDV] */
                                __global const float *proj_scale, __global const float *proj_mean,
                                __global const float8 *proj_axes,
                                /* the lists of sites: centres [list][PDV], sites by list, their projections [i][PDV] */
                                __global const float8 *proj_centres, __global const int *list_start,
                                __global const int *list_site, __global const float8 *proj_sites,
                                __global const int *window_of,
                                __global int *projected)   /* [item - item0][PROJ_K] */
{
    int item = item0 + get_global_id(0);
    if (item >= n_items) return;
    const int Z = P->Z, Y = P->Y, X = P->X, n_views = P->n_views, n_lists = P->n_lists;
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
__kernel void prune_flags(__constant const ml_scalars *P, int n_voxels,
                          __global const float *temp, __global const int *src, __global const int *voxels,
                          __global const int *offsets, __global int *flags)
{
    int i = get_global_id(0);
    if (i >= n_voxels) return;
    const int Z = P->Z, Y = P->Y, X = P->X, n_vox = P->n_vox, n_views = P->n_views;
    const int need_source = P->need_source;
    const float min_weight = P->min_weight;
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
