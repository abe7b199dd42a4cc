/* The voxels' queries, gathered from the block on the device (clsolid.search.block): the
 * exhaustive search's (voxel_queries, then k_nearest of match.cl; or project_queries first,
 * for the search on principal components) and the coherence search's (match.cl's
 * coherence_best, built with this file before it).
 *
 * Compile-time constants:
 *   QDIM  terms of a query (KSIDE*KSIDE, or KSIDE*KSIDE + 9 with a parent level)
 *   KSIDE the square's side
 *   PARENT 1 if a coarser level's 3 x 3 square follows it, else 0
 *   COMPONENTS (optional) principal components project_queries projects onto
 *
 * vol: the level's block (Z, Y, X) float, toroidal; coarse: the coarser block (cz, cy, cx). */

static int wrap(int a, int n)
{
    const int m = a % n;
    return m < 0 ? m + n : m;
}

/* The query of voxel v in the plane (row_axis, col_axis), into xs (QDIM terms): its
 * KSIDE x KSIDE square, row by row, then (PARENT) the coarser block's 3 x 3 around
 * (z/2, y/2, x/2); both toroidal. clsolid.search.features.voxel_features on the host. */
static void voxel_query(__global const float *vol, int vz, int vy, int vx, __global const float *coarse, int cz,
                        int cy, int cx, int row_axis, int col_axis, int v, float *xs)
{
    const int dims[3] = {vz, vy, vx}, stride[3] = {vy * vx, vx, 1};
    const int pos[3] = {v / (vy * vx), (v / vx) % vy, v % vx};
    const int depth = 3 - row_axis - col_axis, base = pos[depth] * stride[depth];
    int cols[KSIDE];
    for (int b = 0; b < KSIDE; ++b)
        cols[b] = wrap(pos[col_axis] + b - KSIDE / 2, dims[col_axis]) * stride[col_axis];
    for (int a = 0; a < KSIDE; ++a) {
        const int row = base + wrap(pos[row_axis] + a - KSIDE / 2, dims[row_axis]) * stride[row_axis];
        for (int b = 0; b < KSIDE; ++b)
            xs[a * KSIDE + b] = vol[row + cols[b]];
    }
#if PARENT
    const int cdims[3] = {cz, cy, cx}, cstride[3] = {cy * cx, cx, 1};
    const int ppos[3] = {(pos[0] / 2) % cz, (pos[1] / 2) % cy, (pos[2] / 2) % cx};
    const int cbase = ppos[depth] * cstride[depth];
    for (int a = 0; a < 3; ++a) {
        const int row = cbase + wrap(ppos[row_axis] + a - 1, cdims[row_axis]) * cstride[row_axis];
        for (int b = 0; b < 3; ++b) {
            const int col = wrap(ppos[col_axis] + b - 1, cdims[col_axis]) * cstride[col_axis];
            xs[KSIDE * KSIDE + a * 3 + b] = coarse[row + col];
        }
    }
#endif
}

/* queries[i * QDIM + d]: the query of voxel voxels[first + i] (voxel_query), for the exhaustive
 * search (k_nearest) of a set of voxels without gathering them on the host. */
__kernel void voxel_queries(__global const float *vol, int vz, int vy, int vx,
                            __global const float *coarse, int cz, int cy, int cx,
                            int row_axis, int col_axis, __global const int *voxels, int first, int n,
                            __global float *queries)
{
    const int i = get_global_id(0);
    if (i >= n)
        return;
    float xs[QDIM];
    voxel_query(vol, vz, vy, vx, coarse, cz, cy, cx, row_axis, col_axis, voxels[first + i], xs);
    for (int d = 0; d < QDIM; ++d)
        queries[(size_t)i * QDIM + d] = xs[d];
}

#ifdef COMPONENTS
/* out[i * COMPONENTS + p] = sum_d basis[p * QDIM + d] * queries[i * QDIM + d] - offset[p]:
 * the queries on the leading principal components of the sites (clsolid.search.projection:
 * the weights' square roots folded into the basis, the mean into the offset). */
__kernel void project_queries(__global const float *queries, int n, __global const float *basis,
                              __global const float *offset, __global float *out)
{
    const int i = get_global_id(0);
    if (i >= n)
        return;
    float q[QDIM];
    for (int d = 0; d < QDIM; ++d)
        q[d] = queries[(size_t)i * QDIM + d];
    for (int p = 0; p < COMPONENTS; ++p) {
        float s = 0.0f;
        for (int d = 0; d < QDIM; ++d)
            s = fma(q[d], basis[p * QDIM + d], s);
        out[(size_t)i * COMPONENTS + p] = s - offset[p];
    }
}
#endif
