/* Pair geometry: what lie-build, the ray segment trees (lib/rst) and the
 * renderer agree a patch-emitter pair is (lib/lie/pair.h). */
#include "lie/pair.h"
#include "lie/shaft.h"

#include <string.h>

float lie_pair_ray_far(const lie_scene *s)
{
    lie_vec3 ext = lie_box3_is_empty(&s->bounds) ? lie_v3(1, 1, 1) : lie_v3_sub(s->bounds.hi, s->bounds.lo);
    float scale = fmaxf(1.0f, fmaxf(ext.x, fmaxf(ext.y, ext.z)));
    return 4.0f * scale + 4.0f * lie_v3_len(ext);
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
    const lie_emitter *em = &s->emitters[e];
    int n_emitter = em->type == LIE_EMITTER_AREA ? (em->n_hull ? em->n_hull : 3 * (int)em->n_tris) : 3;
    return lie_pair_hull_patch_points(1) + n_emitter;
}

int lie_pair_hull_points(const lie_scene *s, uint32_t tri, const lie_vec3 V[3], int e, lie_vec3 *out)
{
    const lie_emitter *em = &s->emitters[e];
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
    if (em->type == LIE_EMITTER_AREA && em->n_hull) {
        memcpy(&out[n], em->hull, sizeof(lie_vec3) * (size_t)em->n_hull); /* a box around many triangles */
        n += em->n_hull;
    } else if (em->type == LIE_EMITTER_AREA) {
        memcpy(&out[n], &s->tri_p[3 * (size_t)em->first_tri], sizeof(lie_vec3) * 3 * em->n_tris);
        n += 3 * (int)em->n_tris;
    } else if (em->type == LIE_EMITTER_POINT) {
        out[n++] = em->position;
    } else {
        float far = lie_pair_ray_far(s);
        for (int k = 0; k < 3; k++)
            out[n++] = lie_v3_add(V[k], lie_v3_scale(em->direction, -far));
    }
    return n;
}

/* ---- which pairs cannot interact -------------------------------------- */

/* A pair is unlit when no point of the patch can receive light from any
 * point of the emitter with a non-zero geometric term — exactly the pairs
 * whose every shadow sample the renderer would weight 0. */
int lie_pair_unlit(const lie_scene *s, uint32_t tri, const lie_vec3 V[3], int two_sided, int e)
{
    const lie_emitter *em = &s->emitters[e];
    lie_vec3 ng = s->tri_ng[tri];
    if (s->tri_area[tri] <= 0.0f)
        return 1;
    if (em->type == LIE_EMITTER_AREA) {
        if (tri >= em->first_tri && tri < em->first_tri + em->n_tris)
            return 1; /* an emitter does not light itself */
        /* emitter wholly behind (or in) the patch's plane */
        int front = 0, back = 0;
        for (uint32_t k = 0; k < em->n_tris && !(front && back); k++) {
            const lie_vec3 *E = &s->tri_p[3 * (size_t)(em->first_tri + k)];
            for (int j = 0; j < 3; j++) {
                float d = lie_v3_dot(ng, lie_v3_sub(E[j], V[0]));
                front |= d > 0.0f;
                back |= d < 0.0f;
            }
        }
        if (!front && (!two_sided || !back))
            return 1;
        /* patch wholly behind every triangle of a one-sided emitter */
        if (!em->double_sided) {
            for (uint32_t k = 0; k < em->n_tris; k++) {
                uint32_t g = em->first_tri + k;
                const lie_vec3 *E = &s->tri_p[3 * (size_t)g];
                lie_vec3 ne = s->tri_ng[g];
                float margin = 4e-4f * lie_maxf(lie_v3_maxabs(V[0]), 1.0f);
                for (int j = 0; j < 3; j++)
                    if (lie_v3_dot(ne, lie_v3_sub(V[j], E[0])) > -margin)
                        return 0;
            }
            return 1;
        }
        return 0;
    }
    if (em->type == LIE_EMITTER_POINT) {
        float d = lie_v3_dot(ng, lie_v3_sub(em->position, V[0]));
        return two_sided ? d == 0.0f : d <= 0.0f;
    }
    float d = -lie_v3_dot(ng, em->direction);
    return two_sided ? d == 0.0f : d <= 0.0f;
}

int lie_pair_hull_meets_box(const lie_vec3 *hull, int n, lie_box3 box, float tol)
{
    lie_vec3 corners[8];
    for (int k = 0; k < 8; k++)
        corners[k] = lie_v3(k & 1 ? box.hi.x : box.lo.x, k & 2 ? box.hi.y : box.lo.y, k & 4 ? box.hi.z : box.lo.z);
    return lie_hull_meets_hull(hull, n, corners, 8, tol);
}
