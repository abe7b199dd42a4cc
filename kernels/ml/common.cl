/* NP-MRF maximum-likelihood synthesis (Urs, Da Costa & Germain, IEEE TIP 2014, eqs. 3-11; R.-D.
 * Urs's PhD thesis, Bordeaux 2013, §4.2-4.3): the per-voxel work of one relaxation step, in four
 * files built as one program in this order (clsolid.ml.opencl):
 *   common.cl  what the others share: layout, the scalar arguments, distance terms
 *   exact.cl   the Parzen sum over every exemplar site (parzen_groups)
 *   pruned.cl  the pruned Parzen sum over candidate windows (parzen_candidates and its helpers)
 *   relax.cl   the per-label LCPDF and the relaxation step (decide), state read-back
 *
 * Layout: volumes are (Z, Y, X), row-major; voxel (z, y, x) of the block has the flat index
 * (z * Y + y) * X + x. Neighbours wrap around (toroidal, tileable output). The buffers may hold
 * one tile of a larger block (clsolid.ml.tiled), its halo included: the kernels that draw random
 * numbers or keep scores use the voxel's coordinates in the whole block (whole_coords), so a
 * tiled run draws exactly what a one-piece run does. One piece: origin 0, whole shape = (Z, Y, X).
 *
 * Global ids: only dimension 0 is used, and it is never a coordinate. The host passes a batch
 * of flat voxel indices (voxels) and work item i takes entry i of the batch: voxel voxels[i]
 * (prune_flags, decide, pack_state), or item i, the voxel-view pair voxels[i / n_views] seen in
 * view i % n_views (parzen_groups takes VB items from i * VB; parzen_candidates and
 * projected_nearest item item0 + i). A voxel's (z, y, x) come from its flat index. Global sizes
 * are rounded up to the local size: a work item past the batch returns at once. So sizes are
 * arguments, and one build serves every shape.
 *
 * Compile-time constants (-D), only those that change the code (array sizes, loop bounds,
 * which terms are computed); everything else is an argument:
 *   NR     terms per view (k*k - 1, plus 9 parent terms where the scale has them)
 *   NCHILD the first NCHILD terms are the window's; the rest the parent's (default NR)
 *   VW     exemplar sites per vector (4, 8 or 16)
 *   VB     voxel-views per work item in parzen_groups, 1, 2, 4 or 8 (they share each load)
 *   NLV    vectors of labels: labels and centre-value groups are held in NLV * VW lanes
 *   NVIEW  number of constrained views (2 or 3)
 *   NS     windows per source in the pruned sum's candidate sets (clsolid.ml.pruned)
 *   MISMATCH  0: values differ by (a - b)^2, 1: by [a != b], 2: by [a != b] (cost[a] + cost[b])
 *          (clsolid.ml.model.difference), the costs per label in the label_cost buffer
 *   NCH    values compared per neighbour: 1, or a colour's channels (MISMATCH 0 only), each
 *          label's colour then in label_cost [label][NCH]; a window has NT = NR * NCH terms
 *   TERM_WEIGHTS  1: term r of a window weighs term_root[r]^2 (fall-off, shared and parent
 *          weights; clsolid.ml.model.term_weights), 0: every term weighs 1
 *   PROJ_K, PROJ_D, PROJ_P  the projected candidates (pruned.cl), where there are any
 */
#define CAT_(a, b) a##b
#define CAT(a, b) CAT_(a, b)
typedef CAT(float, VW) floatv;
typedef CAT(int, VW) intv;
#define NGV NLV   /* vectors of centre-value groups: a group is a label */

#include <pyopencl-random123/philox.cl>

/* The scalar arguments of every kernel, one block per CLBackend, rewritten by the host when
 * the scale, the block or the sweep changes; what changes from launch to launch (the range of
 * the batch) is a plain argument. Fields are 4-byte int, uint or float only, so the layout has
 * no padding and is the same on every device; clsolid.ml.opencl reads its NumPy twin from this
 * definition: add a field here and the host has it. */
/* A buffer, not a struct by value: struct kernel arguments follow each device's ABI (alignment, padding). */
typedef struct {
    /* the block the state buffers hold: the whole volume, or a tile with its halo */
    int Z, Y, X;          /* its shape */
    int n_vox;            /* Z * Y * X: the stride of a view in src */
    int oz, oy, ox;       /* where its first voxel sits in the whole block (0 in one piece) */
    int GZ, GY, GX;       /* the whole block's shape (Z, Y, X in one piece) */
    /* the scale */
    int n_views;          /* constrained views (NVIEW) */
    int n_labels;         /* labels (at most NLV * VW) */
    int n_groups;         /* centre-value groups of the exemplar sites (at most n_labels) */
    int n_chunks;         /* vectors of VW sites in the exact sum's table */
    int n_union;          /* offsets of the temperature update's neighbourhood */
    float k;              /* 1 / (2 h^2), h the Parzen bandwidth */
    float xi;             /* the temperature update's xi (< 0) */
    int heuristic;        /* how the views combine (see decide) */
    int relaxation;       /* 0 ICM, 1 Gibbs, 2 annealing */
    int score_stride;     /* decide keeps the scores of every score_stride-th voxel of the whole block */
    /* the pruned sum */
    int grid_rows, grid_cols;   /* the exemplar's grid of window sites */
    int n_sample;         /* sites sampled for the rest of the sum (0: none) */
    int n_lists;          /* projected_nearest's lists of sites */
    float min_weight;     /* prune_flags: least mean (1 - t)^2 over a view's neighbours */
    int need_source;      /* prune_flags: 1 if a voxel without a source needs the exact sum */
    /* the sweep */
    uint key0, key1;      /* the Philox key */
    uint tag;             /* decide's counter word 3 */
    uint sample_tag;      /* the pruned sum's sample: its counter word 3 */
    float t_in;           /* annealing's global temperature */
    int n_projected;      /* projected candidates parzen_candidates reads: PROJ_K, or 0 in a sweep without */
} ml_scalars;

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

/* The distance between a voxel's window and an exemplar site's, term by term (TIP 2014 eq. 9:
 * each neighbour's difference times 1 - t, t its temperature).
 * TERM_WEIGHT(root, wr, r): neighbour r's weight wr = 1 - t, times root[r], the square root of
 * its term weight (TERM_WEIGHTS), so that its term weighs (1 - t)^2 times that weight. Without
 * term weights wr is left as it is, not multiplied by 1, so terms fuse as they always have.
 * PAIR(cost, x, wr, xw, w): the neighbour's pair (xw, w) from its value x: (wr x, wr) for squared
 * differences, (x, wr^2) for mismatches; weighted mismatches (exemplar values arrive as their
 * labels' costs, distinct) look the voxel's label x up in cost.
 * ADD_TERM(T, acc, xw, w, p) then adds wr^2 (x - p)^2, wr^2 [x != p] or wr^2 [x != p] (cost
 * of x + p) to acc, for the exemplar values p (of type T). */
#if TERM_WEIGHTS
#define TERM_WEIGHT(root, wr, r) ((wr) * (root)[r])
#else
#define TERM_WEIGHT(root, wr, r) (wr)
#endif

#ifndef NCH
#define NCH 1
#endif
#define NT (NR * NCH)   /* terms per window: each neighbour's NCH values */

/* PAIRS(cost, x, wr, xw, w, r): neighbour r's NCH pairs into xw[r NCH + c], w[r NCH + c]: a
 * colour's channels c (the label x's colour, cost[x NCH + c]), each squared difference then
 * one term, so that a window's sum is the squared distance between colours (TIP 2014 §V). */
#if NCH > 1
#define PAIRS(cost, x, wr, xw, w, r) { \
    __global const float *col_ = (cost) + (int)(x) * NCH; \
    for (int c_ = 0; c_ < NCH; ++c_) { xw[(r) * NCH + c_] = (wr) * col_[c_]; w[(r) * NCH + c_] = (wr); } }
#else
#define PAIRS(cost, x, wr, xw, w, r) PAIR(cost, x, wr, xw[r], w[r])
#endif

#if MISMATCH == 2
#define PAIR(cost, x, wr, xw, w) { xw = (cost)[(int)(x)]; w = (wr) * (wr); }
#define ADD_TERM(T, acc, xw, w, p) { acc += select((T)(0.0f), (w) * ((T)(xw) + (p)), (p) != (T)(xw)); }
#elif MISMATCH
#define PAIR(cost, x, wr, xw, w) { xw = (x); w = (wr) * (wr); }
#define ADD_TERM(T, acc, xw, w, p) { acc += select((T)(0.0f), (T)(w), (p) != (T)(xw)); }
#else
#define PAIR(cost, x, wr, xw, w) { xw = (wr) * (x); w = (wr); }
#define ADD_TERM(T, acc, xw, w, p) { T d_ = (xw) - (w) * (p); acc += d_ * d_; }
#endif
