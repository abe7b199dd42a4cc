/* The relaxation step (TIP 2014 eqs. 3, 8, 10-11 and Fig. 1; thesis §4.2.3-4.3.4): each voxel's
 * per-label LCPDF from its views' group sums, the views combined, a label chosen, the
 * temperature updated; and the state read back. Needs common.cl before it. */

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
    int near[NGV * VW], n_near = 0;
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
    /* normalise over the labels (TIP 2014 eq. 3, thesis eq. 4.4) */
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

/* Annealing (TIP 2014 Fig. 1): accept a proposal of log score s_new against the current
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
__kernel void decide(__constant const ml_scalars *P, int n_voxels,
                     __global float *vol, __global float *temp,   /* the state */
                     __global const int *voxels,
                     __global const float *log_sums,   /* [i * n_views + view][NGV * VW], parzen_* */
                     __global const float *kern,       /* [2][n_groups][NLV * VW], see view_logf */
                     __global const float *labels,     /* [n_labels] */
                     __global const int *union_offsets,   /* [n_union][3] */
                     __global const float *bias,       /* [NLV * VW] */
                     __global float *scores)           /* [voxel / score_stride][n_labels] */
{
    int i = get_global_id(0);
    if (i >= n_voxels) return;
    const int Z = P->Z, Y = P->Y, X = P->X, GY = P->GY, GX = P->GX, n_views = P->n_views;
    const int n_groups = P->n_groups, n_labels = P->n_labels, n_union = P->n_union;
    const int heuristic = P->heuristic, relaxation = P->relaxation, score_stride = P->score_stride;
    const float xi = P->xi, t_in = P->t_in;
    int voxel = voxels[i];

    floatv fv[NVIEW][NLV];
    for (int v = 0; v < n_views; ++v)
        view_logf(log_sums + (size_t)(i * n_views + v) * NGV * VW, n_groups, kern, n_labels, fv[v]);

    int z = voxel / (Y * X), rem = voxel - z * Y * X;
    int y = rem / X, x = rem - y * X;
    uint4 g = whole_coords(z, y, x, P->oz, P->oy, P->ox, P->GZ, GY, GX);
    uint u[4] = {0u, 0u, 0u, 0u};
    float x_s = vol[voxel];
    int cur = 0, prop = 0;
    if (relaxation) {
        philox4x32_ctr_t c = {{g.x, g.y, g.z, P->tag}};
        philox4x32_key_t key = {{P->key0, P->key1}};
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
__kernel void pack_state(__constant const ml_scalars *P, int n,
                         __global const float *vol, __global const float *temp, __global const int *src,
                         __global const int *voxels, __global float *values, __global int *sources)
{
    int i = get_global_id(0);
    if (i >= n) return;
    const int n_vox = P->n_vox, n_views = P->n_views;
    int voxel = voxels[i];
    values[i] = vol[voxel];
    values[n + i] = temp[voxel];
    for (int v = 0; v < n_views; ++v) sources[v * n + i] = src[v * n_vox + voxel];
}

/* The normalised per-label log LCPDF of each voxel-view (for tests and diagnostics):
 * out[item][label], with the same code path as decide. */
__kernel void lcpdf(__constant const ml_scalars *P, int n_items, __global const float *log_sums,
                    __global const float *kern, __global float *out)
{
    int i = get_global_id(0);
    if (i >= n_items) return;
    floatv f[NLV];
    const int n_labels = P->n_labels;
    view_logf(log_sums + (size_t)i * NGV * VW, P->n_groups, kern, n_labels, f);
    const float *fs = (const float *)f;
    for (int l = 0; l < n_labels; ++l) out[(size_t)i * n_labels + l] = fs[l];
}
