/* The structure tensor field of an image and the dissimilarities between tensors
 * (clsolid.tensor; Akl et al., ICIP 2014, eqs. 1-12). The float64 references are
 * clsolid/tensor/field.py and clsolid/tensor/dissimilarity.py.
 *
 * A tensor is three floats (xx, xy, yy), interleaved; images are row-major (y rows, x columns).
 *
 * Compile-time constants:
 *   METRIC  0 ED, 1 SO, 2 FN, 3 LE (clsolid.tensor.dissimilarity.METRICS' order)
 *   NT      tensors in a neighbourhood (tensor_std, tensor_best) */

/* Index a of a side of n extended by mirroring (numpy's "reflect": -1 reads 1) or by
 * wrapping; the radius is below n, so one reflection suffices. */
static int extend(int a, int n, int wrap)
{
    if (wrap) {
        const int m = a % n;
        return m < 0 ? m + n : m;
    }
    if (a < 0)
        return -a;
    if (a >= n)
        return 2 * (n - 1) - a;
    return a;
}

/* The channel ch of pixel (row, col) moved by t along axis, the image extended. */
static float along(__global const float *src, int h, int w, int c, int ch, int row, int col, int t, int axis,
                   int wrap)
{
    const int r = axis == 0 ? extend(row - t, h, wrap) : row;
    const int q = axis == 1 ? extend(col - t, w, wrap) : col;
    return src[(r * w + q) * c + ch];
}

/* dst[p, c] = sum_j taps[j] src[p - (j - radius) along axis, c]: a 1D convolution of each of
 * the c interleaved channels of an (h, w) image along axis 0 (rows) or 1 (columns). With
 * odd taps (a derivative), sum_{t > 0} taps[radius + t] (src[p - t] - src[p + t]): a flat
 * region's gradient is exactly 0 (clsolid.tensor.field.convolve_axis). */
__kernel void convolve(__global const float *src, __global float *dst, int h, int w, int c,
                       __global const float *taps, int radius, int axis, int wrap, int odd)
{
    const int gid = get_global_id(0);
    if (gid >= h * w * c)
        return;
    const int ch = gid % c, p = gid / c, row = p / w, col = p % w;
    float s = 0.0f;
    if (odd) {
        for (int t = 1; t <= radius; ++t)
            s = fma(taps[radius + t], along(src, h, w, c, ch, row, col, t, axis, wrap)
                                          - along(src, h, w, c, ch, row, col, -t, axis, wrap), s);
    } else {
        for (int t = -radius; t <= radius; ++t)
            s = fma(taps[radius + t], along(src, h, w, c, ch, row, col, t, axis, wrap), s);
    }
    dst[gid] = s;
}

/* out[p] = (ix ix, ix iy, iy iy) at each of n pixels: the gradient products W smooths (eq. 3). */
__kernel void products(__global const float *ix, __global const float *iy, int n, __global float *out)
{
    const int p = get_global_id(0);
    if (p >= n)
        return;
    const float x = ix[p], y = iy[p];
    out[3 * p] = x * x;
    out[3 * p + 1] = x * y;
    out[3 * p + 2] = y * y;
}

#ifdef METRIC
#define C_FLOOR 1e-3f

/* What the metric compares of a tensor (clsolid.tensor.dissimilarity.features): the tensor
 * (ED, FN), its logarithm with the eigenvalues floored at eps (LE), or (C, O, 0) (SO). */
static float3 feature(float3 s, float eps)
{
#if METRIC == 0 || METRIC == 2
    return s;
#else
    const float mid = 0.5f * (s.x + s.z), radius = 0.5f * hypot(s.x - s.z, 2.0f * s.y);
    const float theta = 0.5f * atan2(2.0f * s.y, s.x - s.z);
#if METRIC == 1
    const float trace = 2.0f * mid;
    return (float3)(trace > 0.0f ? 2.0f * radius / trace : 0.0f, theta, 0.0f);
#else
    const float a = log(fmax(mid + radius, eps)), b = log(fmax(mid - radius, eps));
    const float c = cos(theta), sn = sin(theta);
    return (float3)(a * c * c + b * sn * sn, (a - b) * sn * c, a * sn * sn + b * c * c);
#endif
#endif
}

/* out[i] = feature(tensors[i]) for n tensors. */
__kernel void tensor_features(__global const float *tensors, int n, float eps, __global float *out)
{
    const int i = get_global_id(0);
    if (i >= n)
        return;
    const float3 f = feature(vload3(i, tensors), eps);
    vstore3(f, i, out);
}

/* The dissimilarity of two tensors' features (clsolid.tensor.dissimilarity.feature_dissimilarity). */
static float pair(float3 a, float3 b, float alpha)
{
#if METRIC == 1
    const float c1 = fmax(a.x, C_FLOOR), c2 = fmax(b.x, C_FLOOR);
    const float m_or = fabs(sin(a.y - b.y)) * fmin(a.x, b.x);
    const float m_coh = fmax(c1 / c2, c2 / c1);
    return pow(m_or, alpha) * pow(m_coh, 1.0f - alpha);
#else
    const float3 d = a - b;
    const float ed = d.x * d.x + 2.0f * d.y * d.y + d.z * d.z;
#if METRIC == 0
    return ed;
#else
    return sqrt(ed);
#endif
#endif
}

/* STD (eq. 12) of query q's and site s's neighbourhoods of NT features, each weighted. */
static float neighbourhood(__global const float *q, __global const float *t, __global const float *weights,
                           float alpha)
{
    float sum = 0.0f;
    for (int n = 0; n < NT; ++n)
        if (weights[n] != 0.0f)
            sum = fma(weights[n], pair(vload3(n, q), vload3(n, t), alpha), sum);
    return sum;
}

/* out[i * n_sites + s]: STD between query i and site s (features, NT a neighbourhood). */
__kernel void tensor_std(__global const float *queries, int m, __global const float *table, int n_sites,
                         __global const float *weights, float alpha, __global float *out)
{
    const int gid = get_global_id(0);
    if (gid >= m * n_sites)
        return;
    const int i = gid / n_sites, s = gid % n_sites;
    out[gid] = neighbourhood(queries + (size_t)i * 3 * NT, table + (size_t)s * 3 * NT, weights, alpha);
}

/* site[i], dist[i]: the site of least STD to query i (the lowest index on a tie). */
__kernel void tensor_best(__global const float *queries, int m, __global const float *table, int n_sites,
                          __global const float *weights, float alpha, __global int *site, __global float *dist)
{
    const int i = get_global_id(0);
    if (i >= m)
        return;
    __global const float *q = queries + (size_t)i * 3 * NT;
    float least = INFINITY;
    int best = 0;
    for (int s = 0; s < n_sites; ++s) {
        const float d = neighbourhood(q, table + (size_t)s * 3 * NT, weights, alpha);
        if (d < least) {
            least = d;
            best = s;
        }
    }
    site[i] = best;
    dist[i] = least;
}
#endif
