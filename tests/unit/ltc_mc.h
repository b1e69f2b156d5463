/* SPDX-License-Identifier: Apache-2.0 */
/* The Monte Carlo reference for lib/shade/ltc (tests/unit/test_ltc.c and
 * tests/helpers/ltc-bench.c): int_P f(wi, wo) cos dwi over a planar convex
 * polygon with lib/shade's own BRDF (lie_brdf_eval_cos), by multiple
 * importance sampling (balance heuristic) of three strategies, n points
 * each: uniform over the polygon's area, GGX normals reflected about wo,
 * and the cosine.  Points are Hammersley sets with a fixed shift per
 * strategy, so the reference is deterministic. */
#ifndef LIE_TEST_LTC_MC_H
#define LIE_TEST_LTC_MC_H

#include <math.h>
#include <string.h>

#include "lie.h"
#include "shade/ltc.h"

/* A surface as lie_surface_from_hit fills it, for the BRDF alone. */
static inline lie_surface ltc_mc_surface(lie_vec3 n, lie_vec3 wo, float roughness, float metallic,
                                         const float base[3])
{
    lie_surface sf;
    memset(&sf, 0, sizeof sf);
    sf.n = sf.ng = n;
    sf.wo = wo;
    for (int k = 0; k < 3; k++) {
        sf.base_color[k] = base[k];
        sf.diffuse[k] = base[k] * (1.0f - metallic);
        sf.f0[k] = 0.04f * (1.0f - metallic) + base[k] * metallic;
    }
    sf.alpha = fmaxf(roughness * roughness, 1e-3f);
    sf.lambert = metallic <= 0.0f && roughness >= 1.0f;
    return sf;
}

/* Where direction w from the origin meets the polygon (fan triangulated),
 * or 0; *t the distance. */
static inline int ltc_mc_hit(const lie_vec3 *v, int nv, lie_vec3 pn, lie_vec3 w, double *t)
{
    double dn = (double)lie_v3_dot(pn, w);
    if (fabs(dn) < 1e-12)
        return 0;
    *t = (double)lie_v3_dot(pn, v[0]) / dn;
    if (*t <= 0.0)
        return 0;
    lie_vec3 x = lie_v3_scale(w, (float)*t);
    for (int i = 1; i + 1 < nv; i++) {
        lie_vec3 a = lie_v3_sub(v[0], x), b = lie_v3_sub(v[i], x), c = lie_v3_sub(v[i + 1], x);
        float s0 = lie_v3_dot(lie_v3_cross(a, b), pn), s1 = lie_v3_dot(lie_v3_cross(b, c), pn),
              s2 = lie_v3_dot(lie_v3_cross(c, a), pn);
        if ((s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0))
            return 1;
    }
    return 0;
}

static inline double ltc_mc_ggx_pdf(const lie_surface *sf, lie_vec3 w)
{
    lie_vec3 h = lie_v3_norm(lie_v3_add(w, sf->wo));
    float nh = lie_v3_dot(h, sf->n);
    if (nh < 0.0f) {
        h = lie_v3_scale(h, -1.0f);
        nh = -nh;
    }
    double a2 = (double)sf->alpha * sf->alpha;
    double dd = nh * nh * (a2 - 1.0) + 1.0;
    double vh = fabs((double)lie_v3_dot(sf->wo, h));
    return vh > 0.0 ? a2 / (M_PI * dd * dd) * nh / (4.0 * vh) : 0.0;
}

/* n = +z; wo at `degrees` from it in the xz plane. */
static inline lie_vec3 ltc_view(float degrees)
{
    float th = degrees * (float)(M_PI / 180.0);
    return lie_v3(sinf(th), 0.0f, cosf(th));
}

/* A square of half-size h centred at distance d along unit c, facing the
 * origin. */
static inline void ltc_square_toward(lie_vec3 c, float d, float h, lie_vec3 q[4])
{
    lie_vec3 t, b;
    lie_onb(c, &t, &b);
    lie_vec3 m = lie_v3_scale(c, d);
    q[0] = lie_v3_add(m, lie_v3_add(lie_v3_scale(t, -h), lie_v3_scale(b, -h)));
    q[1] = lie_v3_add(m, lie_v3_add(lie_v3_scale(t, h), lie_v3_scale(b, -h)));
    q[2] = lie_v3_add(m, lie_v3_add(lie_v3_scale(t, h), lie_v3_scale(b, h)));
    q[3] = lie_v3_add(m, lie_v3_add(lie_v3_scale(t, -h), lie_v3_scale(b, h)));
}

/* The polygons the comparisons use at view angle `degrees` (n = +z): a
 * small and a large square toward the mirror direction, a square off the
 * plane of incidence, a triangle, and a square crossing the horizon. */
static inline void ltc_polygons(float degrees, lie_vec3 p[5][4], int nv[5])
{
    lie_vec3 wo = ltc_view(degrees);
    lie_vec3 r = lie_v3(-wo.x, 0.0f, wo.z);
    ltc_square_toward(r, 2.0f, 0.25f, p[0]);
    ltc_square_toward(r, 2.0f, 1.0f, p[1]);
    ltc_square_toward(lie_v3_norm(lie_v3(0.5f, 0.5f, 0.7f)), 2.0f, 0.5f, p[2]);
    p[3][0] = lie_v3(-1.0f, -0.5f, 1.5f);
    p[3][1] = lie_v3(1.0f, -1.0f, 2.0f);
    p[3][2] = lie_v3(0.2f, 1.0f, 1.0f);
    p[4][0] = lie_v3(-1.0f, -1.0f, -0.5f);
    p[4][1] = lie_v3(-1.0f, 1.0f, -0.5f);
    p[4][2] = lie_v3(-1.0f, 1.0f, 1.0f);
    p[4][3] = lie_v3(-1.0f, -1.0f, 1.0f);
    nv[0] = nv[1] = nv[2] = nv[4] = 4;
    nv[3] = 3;
}

/* A square 2000 wide at height 1 above the shading point (n = +z): all of
 * the upper hemisphere but elevations below 0.001 rad. */
static inline void ltc_sky(lie_vec3 q[4])
{
    const float F = 1000.0f;
    q[0] = lie_v3(-F, -F, 1.0f);
    q[1] = lie_v3(F, -F, 1.0f);
    q[2] = lie_v3(F, F, 1.0f);
    q[3] = lie_v3(-F, F, 1.0f);
}

static inline double ltc_mc_frac(double x) { return x - floor(x); }

static inline void ltc_mc_polygon(const lie_surface *sf, const lie_vec3 *v, int nv, int n, double out[3])
{
    out[0] = out[1] = out[2] = 0.0;
    lie_vec3 pn = lie_v3_cross(lie_v3_sub(v[1], v[0]), lie_v3_sub(v[2], v[0]));
    for (int i = 3; i < nv; i++)
        if (lie_v3_dot(pn, pn) < 1e-20f)
            pn = lie_v3_cross(lie_v3_sub(v[i - 1], v[0]), lie_v3_sub(v[i], v[0]));
    pn = lie_v3_norm(pn);
    double area[LIE_LTC_MAX_VERTS], total = 0.0;
    for (int i = 1; i + 1 < nv; i++) {
        total += 0.5 * lie_v3_len(lie_v3_cross(lie_v3_sub(v[i], v[0]), lie_v3_sub(v[i + 1], v[0])));
        area[i] = total;
    }
    if (total <= 0.0)
        return;
    lie_vec3 t, b;
    lie_onb(sf->n, &t, &b);
    double a2 = (double)sf->alpha * sf->alpha;
    static const double shift[3][2] = {{0.137, 0.511}, {0.733, 0.281}, {0.389, 0.907}};
    for (int s = 0; s < 3; s++)
        for (int i = 0; i < n; i++) {
            double u1 = ltc_mc_frac((i + 0.5) / n + shift[s][0]);
            double u2 = ltc_mc_frac(lie_radical_inverse2((uint32_t)i) + shift[s][1]);
            lie_vec3 w;
            if (s == 0) { /* a point on the polygon */
                double pick = u1 * total;
                int k = 1;
                while (k + 2 < nv && area[k] < pick)
                    k++;
                double lo = k > 1 ? area[k - 1] : 0.0;
                double r = (pick - lo) / (area[k] - lo);
                r = r < 0.0 ? 0.0 : r > 1.0 ? 1.0 : r;
                double su = sqrt(r);
                double ba = 1.0 - su, bb = su * (1.0 - u2), bc = su * u2;
                lie_vec3 x = lie_v3(
                    (float)(ba * v[0].x + bb * v[k].x + bc * v[k + 1].x),
                    (float)(ba * v[0].y + bb * v[k].y + bc * v[k + 1].y),
                    (float)(ba * v[0].z + bb * v[k].z + bc * v[k + 1].z));
                w = lie_v3_norm(x);
            } else if (s == 1) { /* GGX normals, reflected */
                double ch = 1.0 / sqrt(1.0 + a2 * u1 / (1.0 - u1)), sh = sqrt(1.0 - ch * ch);
                double ph = 2.0 * M_PI * u2;
                lie_vec3 h = lie_v3_add(lie_v3_add(lie_v3_scale(t, (float)(sh * cos(ph))),
                                                   lie_v3_scale(b, (float)(sh * sin(ph)))),
                                        lie_v3_scale(sf->n, (float)ch));
                w = lie_v3_sub(lie_v3_scale(h, 2.0f * lie_v3_dot(sf->wo, h)), sf->wo);
                w = lie_v3_norm(w);
            } else { /* cosine */
                double r = sqrt(u1), ph = 2.0 * M_PI * u2;
                w = lie_v3_add(lie_v3_add(lie_v3_scale(t, (float)(r * cos(ph))), lie_v3_scale(b, (float)(r * sin(ph)))),
                               lie_v3_scale(sf->n, (float)sqrt(1.0 - u1)));
            }
            double d;
            if (!ltc_mc_hit(v, nv, pn, w, &d))
                continue;
            float f[3];
            lie_brdf_eval_cos(sf, w, f);
            double ce = fabs((double)lie_v3_dot(pn, w));
            double p_area = ce > 0.0 ? d * d / (total * ce) : 0.0;
            double nl = lie_v3_dot(sf->n, w);
            double p_cos = nl > 0.0 ? nl / M_PI : 0.0;
            double den = (double)n * (p_area + ltc_mc_ggx_pdf(sf, w) + p_cos);
            if (den <= 0.0)
                continue;
            for (int k = 0; k < 3; k++)
                out[k] += f[k] / den;
        }
}

#endif
