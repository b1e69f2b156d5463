/* SPDX-License-Identifier: Apache-2.0 */
/* Area emitters: emissive triangles of one glTF primitive instance, the
 * emitter type of the paper (§3).  Their shapes for shaft tests (an
 * oriented box, a plane frame), points on them by area, and their part of
 * the emitter interface (lib/scene/scene.h, lib/scene/internal.h). */
#include "scene/internal.h"

#include <string.h>

/* A bounding box of an area emitter (or cluster) with many triangles, oriented to its
 * plane: the axis is its area-weighted normal when the triangles mostly
 * agree on it (a tessellated panel, whose box is then flat), the in-plane
 * axes its vertices' principal directions; else the world axes (a closed
 * bulb).  Widened a little, so rounding never leaves a vertex outside. */
void lie_scene_hull_of(const lie_scene *s, const uint32_t *tris, uint32_t first, uint32_t n_tris, lie_vec3 hull[8],
                       int *n_hull)
{
    *n_hull = 0;
    if (n_tris <= LIE_EMITTER_HULL_TRIS)
        return;
#define TRI_OF(k) (tris ? tris[k] : first + (uint32_t)(k))
#define VERT(i) s->tri_p[3 * (size_t)TRI_OF((i) / 3) + (i) % 3]
    size_t nv = 3 * (size_t)n_tris;
    double nx = 0, ny = 0, nz = 0, total = 0, cx = 0, cy = 0, cz = 0;
    for (uint32_t t = 0; t < n_tris; t++) {
        lie_vec3 g = s->tri_ng[TRI_OF(t)];
        double a = s->tri_area[TRI_OF(t)];
        nx += a * g.x;
        ny += a * g.y;
        nz += a * g.z;
        total += a;
    }
    for (size_t i = 0; i < nv; i++) {
        lie_vec3 P = VERT(i);
        cx += P.x;
        cy += P.y;
        cz += P.z;
    }
    cx /= (double)nv;
    cy /= (double)nv;
    cz /= (double)nv;
    double len = sqrt(nx * nx + ny * ny + nz * nz);
    double ax[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    if (len > 0.5 * total && len > 0.0) {
        double w[3] = {nx / len, ny / len, nz / len};
        /* any unit u orthogonal to w, then v = w x u */
        double u[3] = {fabs(w[0]) < 0.9 ? 1.0 : 0.0, fabs(w[0]) < 0.9 ? 0.0 : 1.0, 0.0};
        double d = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
        for (int k = 0; k < 3; k++)
            u[k] -= d * w[k];
        double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        for (int k = 0; k < 3; k++)
            u[k] /= ul;
        double v[3] = {w[1] * u[2] - w[2] * u[1], w[2] * u[0] - w[0] * u[2], w[0] * u[1] - w[1] * u[0]};
        /* principal directions in the plane: the angle that diagonalises
         * the 2x2 covariance of the projected vertices */
        double suu = 0, svv = 0, suv = 0;
        for (size_t i = 0; i < nv; i++) {
            lie_vec3 P = VERT(i);
            double q[3] = {P.x - cx, P.y - cy, P.z - cz};
            double pu = q[0] * u[0] + q[1] * u[1] + q[2] * u[2], pv = q[0] * v[0] + q[1] * v[1] + q[2] * v[2];
            suu += pu * pu;
            svv += pv * pv;
            suv += pu * pv;
        }
        double th = 0.5 * atan2(2.0 * suv, suu - svv), c = cos(th), sn = sin(th);
        for (int k = 0; k < 3; k++) {
            ax[0][k] = c * u[k] + sn * v[k];
            ax[1][k] = -sn * u[k] + c * v[k];
            ax[2][k] = w[k];
        }
    }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double mag = 0.0;
    for (size_t i = 0; i < nv; i++) {
        lie_vec3 P = VERT(i);
        double q[3] = {P.x, P.y, P.z};
        for (int a = 0; a < 3; a++) {
            double pr = q[0] * ax[a][0] + q[1] * ax[a][1] + q[2] * ax[a][2];
            lo[a] = pr < lo[a] ? pr : lo[a];
            hi[a] = pr > hi[a] ? pr : hi[a];
            mag = fmax(mag, fabs(q[a]));
        }
    }
    if (!isfinite(mag))
        return; /* keep the vertices */
    double pad = 1e-5 * (mag + 1.0);
    for (int k = 0; k < 8; k++) {
        double p[3] = {0, 0, 0};
        for (int a = 0; a < 3; a++) {
            double t = (k >> a) & 1 ? hi[a] + pad : lo[a] - pad;
            for (int q = 0; q < 3; q++)
                p[q] += t * ax[a][q];
        }
        hull[k] = lie_v3((float)p[0], (float)p[1], (float)p[2]);
    }
    *n_hull = 8;
#undef VERT
#undef TRI_OF
}

/* Is the emitter planar (see lie_emitter)?  Its largest triangle gives the
 * normal and the first in-plane axis; a vertex may stand off the plane by
 * 1e-5 of the emitter's size (tessellation rounding), a triangle's normal
 * may differ by 0.26 degrees. */
static void emitter_plane(const lie_scene *s, lie_emitter *e)
{
    e->planar = 0;
    if (e->n_tris == 0)
        return;
    uint32_t big = e->first_tri;
    for (uint32_t t = e->first_tri; t < e->first_tri + e->n_tris; t++)
        if (s->tri_area[t] > s->tri_area[big])
            big = t;
    const lie_vec3 *B = &s->tri_p[3 * (size_t)big];
    double n[3] = {s->tri_ng[big].x, s->tri_ng[big].y, s->tri_ng[big].z};
    double u[3] = {(double)B[1].x - B[0].x, (double)B[1].y - B[0].y, (double)B[1].z - B[0].z};
    double d = u[0] * n[0] + u[1] * n[1] + u[2] * n[2];
    for (int k = 0; k < 3; k++)
        u[k] -= d * n[k];
    double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (!(ul > 0.0) || !isfinite(ul))
        return;
    for (int k = 0; k < 3; k++)
        u[k] /= ul;
    double v[3] = {n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0]};
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t t = e->first_tri; t < e->first_tri + e->n_tris; t++) {
        lie_vec3 g = s->tri_ng[t];
        double c = g.x * n[0] + g.y * n[1] + g.z * n[2];
        if (!(c > 0.99999) && !(e->double_sided && c < -0.99999))
            return;
        for (int k = 0; k < 3; k++) {
            const lie_vec3 *q = &s->tri_p[3 * (size_t)t + (size_t)k];
            double x[3] = {q->x, q->y, q->z};
            double pr[3] = {x[0] * u[0] + x[1] * u[1] + x[2] * u[2], x[0] * v[0] + x[1] * v[1] + x[2] * v[2],
                            x[0] * n[0] + x[1] * n[1] + x[2] * n[2]};
            for (int a = 0; a < 3; a++) {
                lo[a] = pr[a] < lo[a] ? pr[a] : lo[a];
                hi[a] = pr[a] > hi[a] ? pr[a] : hi[a];
            }
        }
    }
    double size = fmax(hi[0] - lo[0], hi[1] - lo[1]);
    if (!isfinite(size) || !(size > 0.0) || hi[2] - lo[2] > 1e-5 * size)
        return;
    double cu = 0.5 * (lo[0] + hi[0]), cv = 0.5 * (lo[1] + hi[1]), cn = 0.5 * (lo[2] + hi[2]);
    e->plane_o = lie_v3((float)(cu * u[0] + cv * v[0] + cn * n[0]), (float)(cu * u[1] + cv * v[1] + cn * n[1]),
                        (float)(cu * u[2] + cv * v[2] + cn * n[2]));
    e->plane_u = lie_v3((float)u[0], (float)u[1], (float)u[2]);
    e->plane_v = lie_v3((float)v[0], (float)v[1], (float)v[2]);
    e->plane_n = lie_v3((float)n[0], (float)n[1], (float)n[2]);
    e->plane_ext[0] = (float)(lo[0] - cu);
    e->plane_ext[1] = (float)(hi[0] - cu);
    e->plane_ext[2] = (float)(lo[1] - cv);
    e->plane_ext[3] = (float)(hi[1] - cv);
    e->planar = 1;
}

void lie_scene_emitter_shape(const lie_scene *s, lie_emitter *e)
{
    lie_scene_hull_of(s, NULL, e->first_tri, e->n_tris, e->hull, &e->n_hull);
    emitter_plane(s, e);
}

/* Index of the triangle whose CDF interval holds a (binary search). */
static uint32_t cdf_find(const float *cdf, uint32_t n, float a)
{
    uint32_t lo = 0, hi = n - 1;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        if (a < cdf[mid])
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

uint32_t lie_scene_point_on(const lie_scene *s, const uint32_t *tris, uint32_t first, uint32_t n, const float *cdf,
                            float area, float u1, float u2, lie_vec3 *p, lie_vec3 *nrm, float *b1, float *b2)
{
    float a = u1 * area;
    uint32_t t = cdf_find(cdf, n, a);
    float lo = t > 0 ? cdf[t - 1] : 0.0f;
    float ta = cdf[t] - lo;
    float ru = ta > 0.0f ? (a - lo) / ta : 0.5f;
    ru = lie_fminf(lie_fmaxf(ru, 0.0f), LIE_BELOW_ONE);
    lie_sample_triangle(ru, u2, b1, b2);
    uint32_t g = tris ? tris[t] : first + t;
    const lie_vec3 *P = &s->tri_p[3 * (size_t)g];
    float b0 = 1.0f - *b1 - *b2;
    *p = lie_v3_add(lie_v3_add(lie_v3_scale(P[0], b0), lie_v3_scale(P[1], *b1)), lie_v3_scale(P[2], *b2));
    *nrm = s->tri_ng[g];
    return g;
}

uint32_t lie_emitter_point(const lie_scene *s, int e, float u1, float u2, lie_vec3 *p, lie_vec3 *n,
                           float *b1, float *b2)
{
    const lie_emitter *em = &s->emitters[e];
    return lie_scene_point_on(s, NULL, em->first_tri, em->n_tris, em->tri_cdf, em->area, u1, u2, p, n, b1, b2);
}

/* ---- the interface ------------------------------------------------------ */

static int area_hull_cap(const lie_emitter *em) { return em->n_hull ? em->n_hull : 3 * (int)em->n_tris; }

/* A box around many triangles, else the triangles' vertices. */
static int area_extent(const lie_scene *s, const lie_emitter *em, const lie_vec3 **pts)
{
    if (em->n_hull) {
        *pts = em->hull;
        return em->n_hull;
    }
    *pts = &s->tri_p[3 * (size_t)em->first_tri];
    return 3 * (int)em->n_tris;
}

static int area_hull_points(const lie_scene *s, const lie_emitter *em, const lie_vec3 V[3], float far, lie_vec3 *out)
{
    (void)V, (void)far;
    const lie_vec3 *pts;
    int n = area_extent(s, em, &pts);
    memcpy(out, pts, sizeof(lie_vec3) * (size_t)n);
    return n;
}

static const lie_vec3 *area_facing(const lie_scene *s, const lie_emitter *em) { return &s->tri_ng[em->first_tri]; }

static uint32_t area_target(const lie_scene *s, int e, float u1, float u2, lie_vec3 p, float far, lie_vec3 *q,
                            lie_vec3 *n, int *one_sided)
{
    (void)p, (void)far;
    *one_sided = !s->emitters[e].double_sided;
    float b1, b2;
    return lie_emitter_point(s, e, u1, u2, q, n, &b1, &b2);
}

int lie_scene_area_may_reach(const lie_scene *s, const lie_emitter *em, const uint32_t *tris, uint32_t first,
                             uint32_t n, const lie_vec3 V[3], lie_vec3 ng, int two_sided)
{
    /* emitter wholly behind (or in) the patch's plane */
    int front = 0, back = 0;
    for (uint32_t k = 0; k < n && !(front && back); k++) {
        const lie_vec3 *E = &s->tri_p[3 * (size_t)(tris ? tris[k] : first + k)];
        for (int j = 0; j < 3; j++) {
            float d = lie_v3_dot(ng, lie_v3_sub(E[j], V[0]));
            front |= d > 0.0f;
            back |= d < 0.0f;
        }
    }
    if (!front && (!two_sided || !back))
        return 0;
    /* patch wholly behind every triangle of a one-sided emitter */
    if (!em->double_sided) {
        for (uint32_t k = 0; k < n; k++) {
            uint32_t g = tris ? tris[k] : first + k;
            const lie_vec3 *E = &s->tri_p[3 * (size_t)g];
            lie_vec3 ne = s->tri_ng[g];
            float margin = 4e-4f * lie_maxf(lie_v3_maxabs(V[0]), 1.0f);
            for (int j = 0; j < 3; j++)
                if (lie_v3_dot(ne, lie_v3_sub(V[j], E[0])) > -margin)
                    return 1;
        }
        return 0;
    }
    return 1;
}

static int area_can_reach(const lie_scene *s, const lie_emitter *em, uint32_t tri, const lie_vec3 V[3], lie_vec3 ng,
                          int two_sided)
{
    return !lie_emitter_owns(em, tri) /* an emitter does not light itself */
           && lie_scene_area_may_reach(s, em, NULL, em->first_tri, em->n_tris, V, ng, two_sided);
}

static void area_bounding_sphere(const lie_scene *s, const lie_emitter *em, float sphere[4])
{
    lie_bound_sphere(&s->tri_p[3 * (size_t)em->first_tri], 3 * em->n_tris, sphere);
}

/* The emissive texture of the emitter's material, or NULL. */
static const lie_texture *emissive_texture(const lie_scene *s, const lie_emitter *em, const lie_material **mat)
{
    *mat = lie_scene_material(s, s->tri_material[em->first_tri]);
    int k = (*mat)->emissive_tex;
    return k >= 0 && k < s->n_textures ? &s->textures[k] : NULL;
}

static void area_sample_point(const lie_scene *s, int e, float u1, float u2, lie_emitter_sample *out)
{
    const lie_emitter *em = &s->emitters[e];
    float b1, b2;
    uint32_t g = lie_emitter_point(s, e, u1, u2, &out->p, &out->n, &b1, &b2);
    for (int k = 0; k < 3; k++)
        out->le[k] = em->radiance[k];
    const lie_material *mat;
    const lie_texture *tex = emissive_texture(s, em, &mat);
    if (tex) {
        float rgba[4], xu, xv;
        lie_scene_slot_uv(s, mat, LIE_TEX_EMISSIVE, g, b1, b2, &xu, &xv);
        lie_texture_sample(tex, xu, xv, rgba);
        for (int k = 0; k < 3; k++)
            out->le[k] *= rgba[k];
    }
    out->inv_pdf = em->area;
    out->tri = g;
}

static float area_pdf(const lie_emitter *em) { return 1.0f / em->area; }

static int area_uniform(const lie_scene *s, const lie_emitter *em)
{
    const lie_material *mat;
    return emissive_texture(s, em, &mat) == NULL;
}

static int area_polygon(const lie_scene *s, const lie_emitter *em, lie_emitter_polygon *out)
{
    if (em->n_tris == 0 || !area_uniform(s, em))
        return 0; /* radiance varies over the emitter: sampled */
    out->first_tri = em->first_tri;
    out->n_tris = em->n_tris;
    out->two_sided = em->double_sided;
    memcpy(out->radiance, em->radiance, sizeof out->radiance);
    out->planar = em->planar;
    out->o = em->plane_o;
    out->u = em->plane_u;
    out->v = em->plane_v;
    out->n = em->plane_n;
    return 1;
}

/* A Lambertian emitter of radiance Le and area A emits pi Le A per side. */
static void area_power(const lie_scene *s, const lie_emitter *em, float phi[3])
{
    (void)s;
    float k = (float)M_PI * em->area * (em->double_sided ? 2.0f : 1.0f);
    for (int c = 0; c < 3; c++)
        phi[c] = k * em->radiance[c];
}

const lie_emitter_class lie_emitter_area_class = {
    .name = "area",
    .delta = 0,
    .hull_cap = area_hull_cap,
    .hull_points = area_hull_points,
    .facing = area_facing,
    .target = area_target,
    .can_reach = area_can_reach,
    .extent = area_extent,
    .bounding_sphere = area_bounding_sphere,
    .sample_point = area_sample_point,
    .pdf = area_pdf,
    .uniform = area_uniform,
    .incident = NULL, /* sampled: lie_emitter_sample_point */
    .polygon = area_polygon,
    .power = area_power,
};
