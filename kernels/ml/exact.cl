/* The exact Parzen sum (TIP 2014 eqs. 4-7, thesis §4.2.2): every exemplar site's term, summed
 * per centre-value group. Needs common.cl before it. */

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

/* For VB voxel-views per work item: the log of the Parzen sum of each centre-value group,
 *   log_sums[item][g] = log sum_{p : c_p = g} exp(-k * A_p),
 *   A_p = sum_r ((1 - t_r)(x_r - y_{p,r}))^2,       k = 1 / (2 h^2).
 * Exemplar sites are sorted by centre value and padded per group to whole vectors
 * (chunk_valid lanes are real); patches is laid out [chunk][NT][VW] (term r of a colour's
 * neighbour n, channel c at r = n NCH + c). Each group keeps a
 * running minimum of A and a sum rescaled to it (online log-sum-exp), so nothing
 * underflows whatever the window size or the number of grey levels.
 * src[view * n_vox + voxel] receives the voxel's source for the pruned likelihood: the site of
 * least A, as chunk_site[c * VW + lane] names each lane's (the lowest site with its neighbourhood).
 * A view sums over chunks view_chunks[2 view] to view_chunks[2 view + 1]: every chunk with one
 * exemplar, its own exemplar's with one per view (the host then builds VB = 1, so that the
 * items of a work item never need different chunks).
 */
__kernel void parzen_groups(__constant const ml_scalars *P, int n_items,
                            /* the state */
                            __global const float *vol, __global const float *temp, __global int *src,
                            /* the batch */
                            __global const int *voxels,
                            __global float *log_sums,         /* [item][NGV * VW] */
                            /* the window terms (common.cl) */
                            __global const int *offsets,      /* [view][NR][3] */
                            __constant const float *term_root, __global const float *label_cost,
                            /* the exemplar's sites */
                            __global const float *patches,    /* [chunk][NT][VW] */
                            __global const int *chunk_group, __global const int *chunk_valid,
                            __global const int *chunk_site,   /* [chunk * VW + lane] */
                            __global const int *view_chunks)  /* [view][2]: first and end chunk */
{
    int first = get_global_id(0) * VB;
    if (first >= n_items) return;
    const int Z = P->Z, Y = P->Y, X = P->X, n_vox = P->n_vox, n_views = P->n_views;
    const int n_groups = P->n_groups;
    const int view0 = first % n_views;   /* every item's view sums over the same chunks (see above) */
    const int c_begin = view_chunks[2 * view0], c_end = view_chunks[2 * view0 + 1];
    const float k = P->k;

    float xw[VB][NT], w[VB][NT];
    for (int b = 0; b < VB; ++b) {
        int item = min(first + b, n_items - 1);   /* spare slots repeat the last item */
        int voxel = voxels[item / n_views];
        __global const int *off = offsets + (item % n_views) * NR * 3;
        for (int r = 0; r < NR; ++r) {
            int j = neighbour(voxel, Y, X, Z, off + 3 * r) + PARENT(r, Z, Y, X);
            PAIRS(label_cost, vol[j], TERM_WEIGHT(term_root, 1.0f - temp[j], r), xw[b], w[b], r)
        }
    }

    float gmin[VB][NGV * VW], gsum[VB][NGV * VW], best[VB];
    int best_chunk[VB];
    for (int b = 0; b < VB; ++b) {
        best[b] = INFINITY;
        best_chunk[b] = c_begin;
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
    for (int c = c_begin; c < c_end; ++c) {
        /* Plain operators, not fma()/vload(): PoCL leaves those builtins as calls. The
         * chunk is 4*VW-byte aligned (buffers are, and chunks are whole vectors). */
        __global const floatv *pc = (__global const floatv *)(patches + (size_t)c * NT * VW);
        /* Named accumulators: an array here would live on the stack, not in registers. */
        floatv a0 = 0.0f, a1 = 0.0f, a2 = 0.0f, a3 = 0.0f, a4 = 0.0f, a5 = 0.0f, a6 = 0.0f, a7 = 0.0f;
        for (int r = 0; r < NT; ++r) {
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
        __global const floatv *pc = (__global const floatv *)(patches + (size_t)c * NT * VW);
        floatv a = 0.0f;
        for (int r = 0; r < NT; ++r) ADD_TERM(floatv, a, xw[b][r], w[b][r], pc[r])
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
