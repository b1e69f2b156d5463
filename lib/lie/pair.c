/* SPDX-License-Identifier: Apache-2.0 */
/* Pair geometry: what lie-build, the ray segment trees (lib/rst) and the
 * renderer agree a patch-emitter pair is (lib/lie/pair.h). */
#include "lie/pair.h"
#include "lie/shaft.h"

#include <float.h>
#include <string.h>

float lie_pair_ray_far(const lie_scene *s)
{
    lie_vec3 ext = lie_box3_is_empty(&s->bounds) ? lie_v3(1, 1, 1) : lie_v3_sub(s->bounds.hi, s->bounds.lo);
    float scale = fmaxf(1.0f, fmaxf(ext.x, fmaxf(ext.y, ext.z)));
    float need = 4.0f * scale + 4.0f * lie_v3_len(ext);
    if (!(need < FLT_MAX / 2.0f))
        return need;
    int ex;
    frexpf(need, &ex); /* need = m 2^ex, m in [0.5, 1): 2^ex > need */
    return ldexpf(1.0f, ex);
}

float lie_pair_hull_scale(const lie_vec3 *hull, int n)
{
    float m = 1.0f;
    for (int i = 0; i < n; i++)
        m = fmaxf(m, lie_v3_maxabs(hull[i]));
    return m;
}

float lie_pair_eps(const lie_scene *s, uint32_t tri)
{
    const lie_vec3 *P = &s->tri_p[3 * (size_t)tri];
    float mag = 0.0f;
    for (int k = 0; k < 3; k++)
        mag = fmaxf(mag, fmaxf(fabsf(P[k].x), fmaxf(fabsf(P[k].y), fabsf(P[k].z))));
    return lie_ray_eps_bound(mag);
}

int lie_pair_hull_cap(const lie_scene *s, int e)
{
    return lie_pair_hull_patch_points(1) + lie_cluster_hull_cap(s, e);
}

int lie_pair_hull_points(const lie_scene *s, uint32_t tri, const lie_vec3 V[3], int e, lie_vec3 *out)
{
    int two_sided = lie_pair_two_sided(s, tri);
    float eps = lie_pair_eps(s, tri);
    lie_vec3 ng = s->tri_ng[tri];
    int n = 0;
    for (int k = 0; k < 3; k++) {
        out[n++] = V[k];
        out[n++] = lie_v3_add(V[k], lie_v3_scale(ng, eps));
        if (two_sided)
            out[n++] = lie_v3_sub(V[k], lie_v3_scale(ng, eps));
    }
    return n + lie_cluster_hull_points(s, e, V, lie_pair_ray_far(s), out + n);
}

/* ---- which pairs cannot interact -------------------------------------- */

/* A pair is unlit when no point of the patch can receive light from any
 * point of the emitter with a non-zero geometric term — exactly the pairs
 * whose every shadow sample the renderer would weight 0. */
int lie_pair_unlit(const lie_scene *s, uint32_t tri, const lie_vec3 V[3], int two_sided, int e)
{
    if (s->tri_area[tri] <= 0.0f)
        return 1;
    return !lie_cluster_can_reach(s, e, tri, V, s->tri_ng[tri], two_sided);
}

int lie_pair_hull_meets_box(const lie_vec3 *hull, int n, lie_box3 box, float tol)
{
    lie_vec3 corners[8];
    for (int k = 0; k < 8; k++)
        corners[k] = lie_v3(k & 1 ? box.hi.x : box.lo.x, k & 2 ? box.hi.y : box.lo.y, k & 4 ? box.hi.z : box.lo.z);
    return lie_hull_meets_hull(hull, n, corners, 8, tol);
}
