/* NP-MRF maximum-likelihood synthesis: the per-voxel work of one relaxation step, in four
 * files built as one program in this order (clsolid.ml.opencl):
 *   common.cl  what the others share: layout, helpers, distance terms
 *   exact.cl   the Parzen sum over every exemplar site (parzen_groups)
 *   pruned.cl  the pruned Parzen sum over candidate windows (parzen_candidates and its helpers)
 *   relax.cl   the per-label LCPDF and the relaxation step (decide), state read-back
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
