/* SPDX-License-Identifier: Apache-2.0 */
/* Linearly transformed cosines over polygons (Heitz, Dupuy, Hill, Neubelt
 * 2016): map the polygon by the fitted M^-1, clip it to the upper
 * hemisphere, and take the clamped cosine's closed form over a spherical
 * polygon, Lambert's edge sum (§3.2 of the paper; Arvo 1995).  See ltc.h
 * for what is integrated and how the BRDF is split. */
#include "shade/ltc.h"

#include <assert.h>

#include "shade/shade.h"

/* Sutherland-Hodgman against z > 0.  A simple polygon of n vertices gives
 * at most 2n; a convex one at most n + 1.  Crossing points get z = 0
 * exactly, so the next clip or edge sum sees them on the horizon. */
static int clip_upper(const lie_vec3 *in, int n, lie_vec3 *out)
{
    int k = 0;
    for (int i = 0; i < n; i++) {
        lie_vec3 a = in[i], b = in[i + 1 < n ? i + 1 : 0];
        int ia = a.z > 0.0f, ib = b.z > 0.0f;
        if (ia)
            out[k++] = a;
        if (ia != ib) {
            float t = a.z / (a.z - b.z);
            out[k++] = lie_v3(a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), 0.0f);
        }
    }
    return k;
}

/* Lambert's edge sum for the clamped cosine over the spherical polygon
 * spanned by directions v (not necessarily unit), all with z >= 0:
 *   (1 / 2 pi) | sum acos(a.b) (a x b).z / |a x b| |.
 * The robust form: theta / sin(theta) comes from atan2(|a x b|, a.b),
 * accurate for short edges (a.b -> 1, where acos loses half its digits)
 * and for long ones; an edge whose ends are opposite (a x b = 0, a.b < 0)
 * has no defined great circle and is taken as 0 (it only arises for a
 * polygon through the shading point, seen edge-on). */
static float edge_sum(const lie_vec3 *v, int n)
{
    lie_vec3 u[4 * LIE_LTC_MAX_VERTS];
    for (int i = 0; i < n; i++) {
        float l2 = lie_v3_dot(v[i], v[i]);
        u[i] = lie_v3_scale(v[i], l2 > 0.0f ? 1.0f / sqrtf(l2) : 0.0f);
    }
    float sum = 0.0f;
    for (int i = 0; i < n; i++) {
        lie_vec3 a = u[i], b = u[i + 1 < n ? i + 1 : 0];
        lie_vec3 c = lie_v3_cross(a, b);
        float s = sqrtf(lie_v3_dot(c, c));
        if (s > 0.0f)
            sum += c.z * (atan2f(s, lie_v3_dot(a, b)) / s);
    }
    return fminf(fabsf(sum) * (float)(0.5 * M_1_PI), 1.0f);
}

/* Map n <= 2 LIE_LTC_MAX_VERTS directions by m (row-major; NULL: identity),
 * clip, integrate. */
static float integrate(const float *m, const lie_vec3 *v, int n)
{
    lie_vec3 t[2 * LIE_LTC_MAX_VERTS], c[4 * LIE_LTC_MAX_VERTS];
    const lie_vec3 *src = v;
    if (m) {
        for (int i = 0; i < n; i++)
            t[i] = lie_v3(m[0] * v[i].x + m[1] * v[i].y + m[2] * v[i].z,
                          m[3] * v[i].x + m[4] * v[i].y + m[5] * v[i].z,
                          m[6] * v[i].x + m[7] * v[i].y + m[8] * v[i].z);
        src = t;
    }
    int k = clip_upper(src, n, c);
    return k >= 3 ? edge_sum(c, k) : 0.0f;
}

float lie_ltc_integrate(const float *m, const lie_vec3 *verts, int n)
{
    assert(n <= LIE_LTC_MAX_VERTS);
    if (n < 3 || n > LIE_LTC_MAX_VERTS)
        return 0.0f;
    return integrate(m, verts, n);
}

/* Bilinear lookup at roughness r (row) and u (column); rows == 1 for the
 * diffuse table. */
static lie_ltc_bin lookup(const lie_ltc_bin *bins, int rows, int cols, float r, float u)
{
    float fr = lie_minf(lie_maxf(r, 0.0f), 1.0f) * (float)(rows - 1);
    float fu = lie_minf(lie_maxf(u, 0.0f), 1.0f) * (float)(cols - 1);
    int i0 = (int)fr, j0 = (int)fu;
    int i1 = i0 + 1 < rows ? i0 + 1 : i0, j1 = j0 + 1 < cols ? j0 + 1 : j0;
    float wr = fr - (float)i0, wu = fu - (float)j0;
    const float *b00 = &bins[i0 * cols + j0].m00, *b01 = &bins[i0 * cols + j1].m00;
    const float *b10 = &bins[i1 * cols + j0].m00, *b11 = &bins[i1 * cols + j1].m00;
    float o[6];
    for (int k = 0; k < 6; k++)
        o[k] = (1.0f - wr) * ((1.0f - wu) * b00[k] + wu * b01[k]) + wr * ((1.0f - wu) * b10[k] + wu * b11[k]);
    lie_ltc_bin out = {o[0], o[1], o[2], o[3], o[4], o[5]};
    return out;
}

static void set_minv(const lie_ltc_bin *b, float m[9])
{
    m[0] = b->m00, m[1] = 0.0f, m[2] = b->m02;
    m[3] = 0.0f, m[4] = 1.0f, m[5] = 0.0f;
    m[6] = b->m20, m[7] = 0.0f, m[8] = b->m22;
}

/* The lobe frame: z = n, x toward wo in the plane of n and wo. */
static void lobe_frame(lie_vec3 n, lie_vec3 wo, float f[9], float *nv)
{
    float c = lie_v3_dot(n, wo);
    lie_vec3 x = lie_v3_sub(wo, lie_v3_scale(n, c));
    float l2 = lie_v3_dot(x, x);
    lie_vec3 y;
    if (l2 > 1e-12f) {
        x = lie_v3_scale(x, 1.0f / sqrtf(l2));
        y = lie_v3_cross(n, x);
    } else {
        lie_onb(n, &x, &y); /* normal view: the lobe is isotropic about n */
    }
    f[0] = x.x, f[1] = x.y, f[2] = x.z;
    f[3] = y.x, f[4] = y.y, f[5] = y.z;
    f[6] = n.x, f[7] = n.y, f[8] = n.z;
    *nv = lie_maxf(c, 1e-4f);
}

void lie_ltc_shading_init(const lie_ltc_table *t, lie_vec3 n, lie_vec3 wo, float roughness,
                          const float f0[3], const float c_diff[3], lie_ltc_shading *sh)
{
    float nv;
    lobe_frame(n, wo, sh->frame, &nv);
    float u = sqrtf(lie_maxf(1.0f - nv, 0.0f));
    lie_ltc_bin s = lookup(t->ggx, t->n_rough, t->n_cos, roughness, u);
    lie_ltc_bin d = lookup(t->diffuse, 1, t->n_cos, 0.0f, u);
    set_minv(&s, sh->spec_m);
    set_minv(&d, sh->diff_m);
    if (t->ggx_fresnel) {
        lie_ltc_bin fz = lookup(t->ggx_fresnel, t->n_rough, t->n_cos, roughness, u);
        set_minv(&fz, sh->fres_m);
        for (int k = 0; k < 3; k++) {
            sh->spec_w[k] = s.norm * f0[k];
            sh->fres_w[k] = fz.norm * (1.0f - f0[k]);
        }
    } else {
        set_minv(&s, sh->fres_m);
        for (int k = 0; k < 3; k++) {
            sh->spec_w[k] = s.norm * (f0[k] * (1.0f - s.fresnel) + s.fresnel);
            sh->fres_w[k] = 0.0f;
        }
    }
    for (int k = 0; k < 3; k++)
        sh->diff_w[k] = c_diff[k] * (1.0f - f0[k]) * (float)M_1_PI * d.norm;
    sh->has_spec = 1;
}

void lie_ltc_shading_lambert(lie_vec3 n, const float c_diff[3], lie_ltc_shading *sh)
{
    float nv;
    lobe_frame(n, n, sh->frame, &nv);
    static const float identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int k = 0; k < 9; k++)
        sh->spec_m[k] = sh->fres_m[k] = sh->diff_m[k] = identity[k];
    for (int k = 0; k < 3; k++) {
        sh->spec_w[k] = sh->fres_w[k] = 0.0f;
        sh->diff_w[k] = c_diff[k]; /* c_diff / pi * (pi * LTC with M = I) */
    }
    sh->has_spec = 0;
}

void lie_ltc_shading_from_surface(const lie_ltc_table *t, const lie_surface *sf, lie_ltc_shading *sh)
{
    if (sf->lambert)
        lie_ltc_shading_lambert(sf->n, sf->diffuse, sh);
    else
        lie_ltc_shading_init(t, sf->n, sf->wo, sqrtf(sf->alpha), sf->f0, sf->diffuse, sh);
}

void lie_ltc_polygon(const lie_ltc_shading *sh, const lie_vec3 *verts, int n, float out[3])
{
    out[0] = out[1] = out[2] = 0.0f;
    assert(n <= LIE_LTC_MAX_VERTS);
    if (n < 3 || n > LIE_LTC_MAX_VERTS)
        return;
    const float *f = sh->frame;
    lie_vec3 l[LIE_LTC_MAX_VERTS], c[2 * LIE_LTC_MAX_VERTS];
    for (int i = 0; i < n; i++)
        l[i] = lie_v3(f[0] * verts[i].x + f[1] * verts[i].y + f[2] * verts[i].z,
                      f[3] * verts[i].x + f[4] * verts[i].y + f[5] * verts[i].z,
                      f[6] * verts[i].x + f[7] * verts[i].y + f[8] * verts[i].z);
    /* The BRDF is 0 below the shading horizon: clip there first (the
     * fitted distributions' mass below it is folded into the norms). */
    int k = clip_upper(l, n, c);
    if (k < 3)
        return;
    if (!sh->has_spec) {
        float e = edge_sum(c, k);
        for (int j = 0; j < 3; j++)
            out[j] = sh->diff_w[j] * e;
        return;
    }
    float es = integrate(sh->spec_m, c, k), ed = integrate(sh->diff_m, c, k);
    float ef = sh->fres_w[0] > 0.0f || sh->fres_w[1] > 0.0f || sh->fres_w[2] > 0.0f ? integrate(sh->fres_m, c, k) : 0.0f;
    for (int j = 0; j < 3; j++)
        out[j] = sh->spec_w[j] * es + sh->fres_w[j] * ef + sh->diff_w[j] * ed;
}

void lie_ltc_polygon_once(const lie_ltc_table *t, lie_vec3 n, lie_vec3 wo, float roughness,
                          const float f0[3], const float c_diff[3], const lie_vec3 *verts, int nv,
                          float out[3])
{
    lie_ltc_shading sh;
    lie_ltc_shading_init(t, n, wo, roughness, f0, c_diff, &sh);
    lie_ltc_polygon(&sh, verts, nv, out);
}
