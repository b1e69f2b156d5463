/* Shadow rays answered by local illumination environments (§4.2). */
#include "lie/lie.h"
#include "shade/shade.h"

#include <stdlib.h>
#include <string.h>

/* A blocker's vertices, compact for the test loop. */
typedef struct mt_tri {
    float ax, ay, az, bx, by, bz, cx, cy, cz;
} mt_tri;

/* Bounding spheres, for culling blockers per shading point. */
typedef struct sphere {
    float x, y, z, r;
} sphere;

struct lie_lie_vis {
    const lie_scene *s;
    const lie_env *env;
    mt_tri *tris;
    sphere *tri_sphere;     /* per triangle */
    sphere *emitter_sphere; /* per emitter; r < 0: no culling (directional) */
    lie_vis_oracle oracle;
};

static lie_vis_class classify(void *ctx, const lie_surface *sf, int e, const void **pair)
{
    const lie_lie_vis *v = ctx;
    const lie_pnode *n = lie_env_find_leaf(v->env, sf->tri, e, sf->b1, sf->b2);
    switch (n->cls) {
    case LIE_CLASS_VISIBLE:
        return LIE_VISCLASS_VISIBLE;
    case LIE_CLASS_UNLIT:
    case LIE_CLASS_OCCLUDED:
        return LIE_VISCLASS_OCCLUDED;
    case LIE_CLASS_PARTIAL:
        *pair = n;
        return LIE_VISCLASS_BLOCKERS;
    default:
        return LIE_VISCLASS_TEST_ALL; /* complex, or not built */
    }
}

/* The blockers whose bounding spheres meet the cone from o around the
 * emitter's bounding sphere, cut at the emitter: every segment of this
 * point lies in it (the patch's list serves the whole patch; one point
 * needs fewer, often none). */
static int select_blockers(void *ctx, const void *pair, int e, lie_vec3 o, uint32_t *out)
{
    const lie_lie_vis *v = ctx;
    const lie_pnode *nd = pair;
    const uint32_t *list = v->env->pool + nd->list;
    const sphere E = v->emitter_sphere[e];
    float wx = E.x - o.x, wy = E.y - o.y, wz = E.z - o.z;
    float D2 = wx * wx + wy * wy + wz * wz;
    if (!(E.r >= 0.0f) || D2 <= E.r * E.r) {
        memcpy(out, list, sizeof *out * nd->count); /* no cone: keep them all */
        return (int)nd->count;
    }
    float D = sqrtf(D2), sa = E.r / D, ca = sqrtf(1.0f - sa * sa);
    int m = 0;
    for (uint32_t j = 0; j < nd->count; j++) {
        const sphere B = v->tri_sphere[list[j]];
        float vx = B.x - o.x, vy = B.y - o.y, vz = B.z - o.z;
        float v2 = vx * vx + vy * vy + vz * vz;
        if (v2 <= B.r * B.r) {
            out[m++] = list[j]; /* o inside the blocker's sphere */
            continue;
        }
        float dv = sqrtf(v2);
        float t = (vx * wx + vy * wy + vz * wz) / D; /* along the axis */
        if (t + B.r < 0.0f || t - B.r > D + E.r)
            continue; /* behind o, or beyond the emitter */
        float sb = B.r / dv, cb = sqrtf(1.0f - sb * sb);
        float cos_theta = t / dv;
        /* inside the cone widened by the sphere's angular radius:
         * theta <= alpha + beta, i.e. cos theta >= cos(alpha + beta) */
        float cos_sum = ca * cb - sa * sb;
        int wide = ca * cb - sa * sb < -0.999f; /* alpha + beta near pi */
        if (wide || cos_theta >= cos_sum - 1e-6f)
            out[m++] = list[j];
    }
    return m;
}

/* Segments o -> o + d_i against the selected blockers.  The origin is
 * shared, so per blocker we set up once the three planes through o and the
 * triangle's edges and the triangle's plane; a segment is blocked when its
 * direction is inside all three edge planes (same sign) and its end is on
 * the other side of the triangle's plane from o.  Four dot products per
 * segment and blocker, no division, vectorised over segments. */
static void occluded(void *ctx, const uint32_t *blockers, int n_blockers, lie_vec3 o, const float *dxs,
                     const float *dys, const float *dzs, int n, uint32_t *occ_out)
{
    const lie_lie_vis *v = ctx;
    const float *restrict dx = dxs, *restrict dy = dys, *restrict dz = dzs;
    uint32_t *restrict occ = occ_out;
    memset(occ, 0, sizeof *occ * (size_t)n);
    for (int j = 0; j < n_blockers; j++) {
        const mt_tri T = v->tris[blockers[j]];        /* vertices relative to the origin (shared vertices stay bit-equal,
         * so neighbouring triangles' edge planes are exact negations:
         * watertight) */
        float ax = T.ax - o.x, ay = T.ay - o.y, az = T.az - o.z;
        float bx = T.bx - o.x, by = T.by - o.y, bz = T.bz - o.z;
        float cx = T.cx - o.x, cy = T.cy - o.y, cz = T.cz - o.z;
        /* edge planes through the origin */
        float m0x = ay * bz - az * by, m0y = az * bx - ax * bz, m0z = ax * by - ay * bx;
        float m1x = by * cz - bz * cy, m1y = bz * cx - bx * cz, m1z = bx * cy - by * cx;
        float m2x = cy * az - cz * ay, m2y = cz * ax - cx * az, m2z = cx * ay - cy * ax;
        /* triangle plane: n . (p - o) = h, h = n . a */
        float e1x = bx - ax, e1y = by - ay, e1z = bz - az, e2x = cx - ax, e2y = cy - ay, e2z = cz - az;
        float nx = e1y * e2z - e1z * e2y, ny = e1z * e2x - e1x * e2z, nz = e1x * e2y - e1y * e2x;
        float h = nx * ax + ny * ay + nz * az;
#pragma omp simd
        for (int i = 0; i < n; i++) {
            float e0 = m0x * dx[i] + m0y * dy[i] + m0z * dz[i];
            float e1 = m1x * dx[i] + m1y * dy[i] + m1z * dz[i];
            float e2 = m2x * dx[i] + m2y * dy[i] + m2z * dz[i];
            float pd = nx * dx[i] + ny * dy[i] + nz * dz[i];
            int inside = ((e0 >= 0.0f) & (e1 >= 0.0f) & (e2 >= 0.0f)) | ((e0 <= 0.0f) & (e1 <= 0.0f) & (e2 <= 0.0f));
            /* the plane is crossed between t = 0 and t = 1: h and pd share a
             * sign and |h| <= |pd| (h = 0: the origin lies in the plane) */
            int crosses = ((h >= 0.0f) & (pd >= h)) | ((h <= 0.0f) & (pd <= h));
            int degenerate = (e0 == 0.0f) & (e1 == 0.0f) & (e2 == 0.0f);
            occ[i] |= (uint32_t)-(inside & crosses & !degenerate);
        }
    }
}

static void describe(void *ctx, const lie_surface *sf, int e, int *cls, uint32_t *count, uint64_t *patch_id)
{
    const lie_lie_vis *v = ctx;
    lie_patch_path path;
    const lie_pnode *n = lie_env_find_leaf_path(v->env, sf->tri, e, sf->b1, sf->b2, &path);
    *cls = (int)n->cls;
    *count = n->count;
    *patch_id = lie_hash_u64x4(sf->tri, path.digits, (uint64_t)path.depth, (uint64_t)e);
}

/* A sphere around points: the box's centre, the farthest point's distance
 * (slightly enlarged so rounding never culls a real blocker). */
static sphere bounding_sphere(const lie_vec3 *p, uint32_t n)
{
    lie_box3 b = lie_box3_empty();
    for (uint32_t i = 0; i < n; i++)
        lie_box3_grow(&b, p[i]);
    lie_vec3 c = lie_v3_scale(lie_v3_add(b.lo, b.hi), 0.5f);
    float r = 0.0f;
    for (uint32_t i = 0; i < n; i++)
        r = fmaxf(r, lie_v3_len(lie_v3_sub(p[i], c)));
    float mag = fmaxf(fabsf(c.x), fmaxf(fabsf(c.y), fabsf(c.z)));
    sphere s = {c.x, c.y, c.z, r * 1.001f + 1e-5f * fmaxf(1.0f, mag)};
    return s;
}

lie_status lie_lie_vis_create(const lie_scene *s, const lie_env *env, lie_lie_vis **out, lie_error *err)
{
    *out = NULL;
    if (env->n_tris != s->n_tris || env->n_emitters != s->n_emitters)
        return lie_error_set(err, LIE_ERR_ARG, s->path,
                             "the cache has %u triangles and %d emitters, the scene %u and %d", env->n_tris,
                             env->n_emitters, s->n_tris, s->n_emitters);
    lie_lie_vis *v = calloc(1, sizeof *v);
    if (!v)
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    v->tris = malloc(sizeof *v->tris * ((size_t)s->n_tris + 1));
    if (!v->tris) {
        free(v);
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    }
    for (uint32_t t = 0; t < s->n_tris; t++) {
        const lie_vec3 *P = &s->tri_p[3 * (size_t)t];
        mt_tri m = {P[0].x, P[0].y, P[0].z, P[1].x, P[1].y, P[1].z, P[2].x, P[2].y, P[2].z};
        v->tris[t] = m;
    }
    v->tri_sphere = malloc(sizeof *v->tri_sphere * ((size_t)s->n_tris + 1));
    v->emitter_sphere = malloc(sizeof *v->emitter_sphere * ((size_t)s->n_emitters + 1));
    if (!v->tri_sphere || !v->emitter_sphere) {
        lie_lie_vis_destroy(v);
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    }
    for (uint32_t t = 0; t < s->n_tris; t++)
        v->tri_sphere[t] = bounding_sphere(&s->tri_p[3 * (size_t)t], 3);
    for (int e = 0; e < s->n_emitters; e++) {
        const lie_emitter *em = &s->emitters[e];
        if (em->type == LIE_EMITTER_AREA) {
            v->emitter_sphere[e] = bounding_sphere(&s->tri_p[3 * (size_t)em->first_tri], 3 * em->n_tris);
        } else if (em->type == LIE_EMITTER_POINT) {
            sphere p = {em->position.x, em->position.y, em->position.z, 0.0f};
            v->emitter_sphere[e] = p;
        } else {
            sphere none = {0.0f, 0.0f, 0.0f, -1.0f};
            v->emitter_sphere[e] = none;
        }
    }
    v->s = s;
    v->env = env;
    v->oracle.ctx = v;
    v->oracle.classify = classify;
    v->oracle.occluded = occluded;
    v->oracle.select = select_blockers;
    uint32_t longest = 0;
    for (uint32_t i = 0; i < env->n_nodes; i++)
        if (env->nodes[i].cls == LIE_CLASS_PARTIAL && env->nodes[i].count > longest)
            longest = env->nodes[i].count;
    v->oracle.max_blockers = (int)longest;
    v->oracle.describe = describe;
    *out = v;
    return LIE_OK;
}

const lie_vis_oracle *lie_lie_vis_oracle(const lie_lie_vis *v) { return &v->oracle; }

void lie_lie_vis_destroy(lie_lie_vis *v)
{
    if (!v)
        return;
    free(v->tris);
    free(v->tri_sphere);
    free(v->emitter_sphere);
    free(v);
}
