/* SPDX-License-Identifier: Apache-2.0 */
/* Shadow rays answered by local illumination environments (§4.2).
 * Size: one job, the LIE oracle: the leaf lookup, the blocker selection and
 * the per-blocker tests share the compact blocker layout built here. */
#include "lie/lie.h"
#include "shade/bitmask.h"
#include "shade/internal.h"

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

struct lie_env_shadows {
    const lie_scene *s;
    const lie_env *env;
    mt_tri *tris;
    sphere *tri_sphere;     /* per triangle */
    sphere *emitter_sphere; /* per cluster (lie_cluster); r < 0: no culling (directional) */
    /* per triangle, side by side, for the selection loops (which gather
     * them by a list's triangle indices): its sphere's x, y, z, r and its
     * vertices a x, y, z, b x, y, z, c x, y, z */
    float *soa_sphere[4];
    float *soa_vert[9];
    int32_t *solid;         /* per triangle: its convex solid (lie_solids_find) or -1 */
    uint8_t *unbuilt;       /* lie_env_shadows_record_unbuilt's mask, or NULL */
    lie_vis_oracle oracle;
};

static lie_class classify(void *ctx, const lie_surface *sf, int e, const void **pair)
{
    const lie_env_shadows *v = ctx;
    const lie_pnode *n = lie_env_find_leaf(v->env, sf->tri, e, sf->b1, sf->b2);
    switch (n->cls) {
    case LIE_CLASS_VISIBLE:
        return LIE_CLASS_VISIBLE;
    case LIE_CLASS_UNLIT:
    case LIE_CLASS_OCCLUDED:
        return LIE_CLASS_OCCLUDED;
    case LIE_CLASS_PARTIAL:
        *pair = n;
        return LIE_CLASS_PARTIAL;
    case LIE_CLASS_NONE:
        /* a byte set to 1 by any number of threads: relaxed atomic stores */
        if (v->unbuilt)
            __atomic_store_n(&v->unbuilt[sf->tri], (uint8_t)1, __ATOMIC_RELAXED);
        return LIE_CLASS_NONE; /* not built: the whole scene answers */
    default:
        return LIE_CLASS_COMPLEX; /* complex */
    }
}

/* The blockers whose bounding spheres meet the cone from o around the
 * emitter's bounding sphere, cut at the emitter: every segment of this
 * point lies in it (the patch's list serves the whole patch; one point
 * needs fewer, often none).  The spheres of each list lie side by side
 * (soa_sphere), so the test runs over eight blockers at a time; the
 * flags go to out[] and are compacted in place. */
static int select_planar(const lie_env_shadows *v, const lie_pnode *nd, const lie_emitter *em, lie_vec3 o, float eps,
                         uint32_t *out);

static int select_blockers(void *ctx, const void *pair, int e, lie_vec3 o, float eps, uint32_t *out)
{
    const lie_env_shadows *v = ctx;
    const lie_pnode *nd = pair;
    const lie_emitter *em = &v->s->emitters[v->s->clusters[e].emitter];
    if (em->planar) /* a cluster lies in its emitter's plane, within its extent */
        return select_planar(v, nd, em, o, eps, out);
    const uint32_t *list = v->env->pool + nd->list;
    const int count = (int)nd->count;
    const sphere E = v->emitter_sphere[e];
    float wx = E.x - o.x, wy = E.y - o.y, wz = E.z - o.z;
    float D2 = wx * wx + wy * wy + wz * wz;
    if (!(E.r >= 0.0f) || D2 <= E.r * E.r) {
        memcpy(out, list, sizeof *out * (size_t)count); /* no cone: keep them all */
        return count;
    }
    float D = sqrtf(D2), sa = E.r / D, ca = sqrtf(1.0f - sa * sa);
    float ux = wx / D, uy = wy / D, uz = wz / D, far = D + E.r;
    const float *restrict bx = v->soa_sphere[0], *restrict by = v->soa_sphere[1], *restrict bz = v->soa_sphere[2],
                          *restrict br = v->soa_sphere[3];
    uint32_t *restrict keep = out;
#pragma omp simd
    for (int j = 0; j < count; j++) {
        const uint32_t b = list[j];
        float vx = bx[b] - o.x, vy = by[b] - o.y, vz = bz[b] - o.z, r = br[b];
        float v2 = vx * vx + vy * vy + vz * vz;
        int inside = v2 <= r * r; /* o inside the blocker's sphere */
        float dv = sqrtf(v2);
        float t = vx * ux + vy * uy + vz * uz; /* along the axis */
        int in_range = (t + r >= 0.0f) & (t - r <= far); /* not behind o, not beyond the emitter */
        float sb = r / dv, cb = sqrtf(1.0f - sb * sb);
        /* inside the cone widened by the sphere's angular radius:
         * theta <= alpha + beta, i.e. cos theta >= cos(alpha + beta) */
        float cos_sum = ca * cb - sa * sb;
        int wide = cos_sum < -0.999f; /* alpha + beta near pi */
        int in_cone = wide | (t / dv >= cos_sum - 1e-6f);
        keep[j] = (uint32_t)(inside | (in_range & in_cone));
    }
    int m = 0;
    for (int j = 0; j < count; j++)
        if (keep[j])
            out[m++] = list[j];
    return m;
}

/* The depth (along a planar emitter's normal, from o at distance D from
 * its plane) that no segment from o reaches: a segment to a sample at
 * distance |d| ends eps short of it, at depth D - eps D / |d|, and |d| is
 * at most |w| (w = plane origin - o) plus the reach of the box
 * ext = s min, max, t min, max around the plane origin that holds the
 * samples.  Half that margin is kept against rounding. */
static float unreached_depth(float D, float eps, float wx, float wy, float wz, const float ext[4])
{
    float rs = lie_maxf(-ext[0], ext[1]), rt = lie_maxf(-ext[2], ext[3]);
    float dmax = sqrtf(wx * wx + wy * wy + wz * wz) + sqrtf(rs * rs + rt * rt);
    return D - 0.5f * eps * (D / dmax);
}

/* Toward a planar emitter: the blockers that are not wholly behind o
 * (depth along the emitter's normal < 0), not wholly where no segment
 * reaches (at or beyond the emitter's plane), and, when wholly in front of o, whose shadow on the plane meets
 * the emitter's extent.  A vertex at depth l > 0 and plane coordinate
 * a_u = a.u falls at s = a_u D / l - w.u on the plane, so "every vertex
 * left of s0" is a_u D < (w.u + s0) l for each: no division.  Over the
 * list's vertices side by side, eight blockers at a time. */
LIE_HOT static int select_planar(const lie_env_shadows *v, const lie_pnode *nd, const lie_emitter *em, lie_vec3 o, float eps,
                         uint32_t *out)
{
    const uint32_t *list = v->env->pool + nd->list;
    const int count = (int)nd->count;
    const lie_vec3 U = em->plane_u, V = em->plane_v;
    const float wx = em->plane_o.x - o.x, wy = em->plane_o.y - o.y, wz = em->plane_o.z - o.z;
    const float d = wx * em->plane_n.x + wy * em->plane_n.y + wz * em->plane_n.z;
    const float sg = d > 0.0f ? 1.0f : -1.0f, D = sg * d;
    const float kx = sg * em->plane_n.x, ky = sg * em->plane_n.y, kz = sg * em->plane_n.z;
    const float wu = wx * U.x + wy * U.y + wz * U.z, wv = wx * V.x + wy * V.y + wz * V.z;
    const float pad = 1e-4f * lie_maxf(em->plane_ext[1] - em->plane_ext[0], em->plane_ext[3] - em->plane_ext[2]);
    const float L = wu + em->plane_ext[0] - pad, R = wu + em->plane_ext[1] + pad;
    const float B = wv + em->plane_ext[2] - pad, T = wv + em->plane_ext[3] + pad;
    /* shadows are boxed only for vertices at least eps in front of o */
    const float front = eps;
    const float end = unreached_depth(D, eps, wx, wy, wz, em->plane_ext);
    const float *const *P = (const float *const *)v->soa_vert;
    const float *restrict pax = P[0], *restrict pay = P[1], *restrict paz = P[2];
    const float *restrict pbx = P[3], *restrict pby = P[4], *restrict pbz = P[5];
    const float *restrict pcx = P[6], *restrict pcy = P[7], *restrict pcz = P[8];
    uint32_t *restrict keep = out;
#pragma omp simd
    for (int j = 0; j < count; j++) {
        const uint32_t i = list[j];
        float ax = pax[i] - o.x, ay = pay[i] - o.y, az = paz[i] - o.z;
        float bx = pbx[i] - o.x, by = pby[i] - o.y, bz = pbz[i] - o.z;
        float cx = pcx[i] - o.x, cy = pcy[i] - o.y, cz = pcz[i] - o.z;
        float la = ax * kx + ay * ky + az * kz, lb = bx * kx + by * ky + bz * kz, lc = cx * kx + cy * ky + cz * kz;
        float au = ax * U.x + ay * U.y + az * U.z, bu = bx * U.x + by * U.y + bz * U.z,
              cu = cx * U.x + cy * U.y + cz * U.z;
        float av = ax * V.x + ay * V.y + az * V.z, bv = bx * V.x + by * V.y + bz * V.z,
              cv = cx * V.x + cy * V.y + cz * V.z;
        int behind = (la < 0.0f) & (lb < 0.0f) & (lc < 0.0f);
        int beyond = (la > end) & (lb > end) & (lc > end);
        int in_front = (la > front) & (lb > front) & (lc > front);
        int left = (au * D < L * la) & (bu * D < L * lb) & (cu * D < L * lc);
        int right = (au * D > R * la) & (bu * D > R * lb) & (cu * D > R * lc);
        int below = (av * D < B * la) & (bv * D < B * lb) & (cv * D < B * lc);
        int above = (av * D > T * la) & (bv * D > T * lb) & (cv * D > T * lc);
        keep[j] = (uint32_t)!(behind | beyond | (in_front & (left | right | below | above)));
    }
    int m = 0;
    for (int j = 0; j < count; j++)
        if (keep[j])
            out[m++] = list[j];
    return m;
}

/* Segments against one blocker, in 3D: the origin is shared, so per
 * blocker we set up once the three planes through o and the triangle's
 * edges and the triangle's plane; a segment is blocked when its direction
 * is inside all three edge planes (same sign) and its end is on the other
 * side of the triangle's plane from o.  Four dot products per segment, no
 * division, vectorised over segments. */
LIE_HOT static void blocker_3d(const mt_tri *T, lie_vec3 o, const float *dxs, const float *dys, const float *dzs, int n,
                       uint32_t *occ_out)
{
    const float *restrict dx = dxs, *restrict dy = dys, *restrict dz = dzs;
    uint32_t *restrict occ = occ_out;
    /* vertices relative to the origin (shared vertices stay bit-equal, so
     * neighbouring triangles' edge planes are exact negations: watertight) */
    float ax = T->ax - o.x, ay = T->ay - o.y, az = T->az - o.z;
    float bx = T->bx - o.x, by = T->by - o.y, bz = T->bz - o.z;
    float cx = T->cx - o.x, cy = T->cy - o.y, cz = T->cz - o.z;
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

/* Toward a planar emitter, o sees the emitter's plane at distance D along
 * its normal, and every sample's direction d has depth D.  The rays from o
 * that meet a blocker are the cone of its vertex vectors a, b, c: d is in
 * it iff d's three coordinates in that basis (by Cramer's rule, the edge
 * planes' dot products divided by det(a, b, c)) are >= 0, and the ray then
 * meets the triangle at the fraction tau = h / (n.d) of d (n the
 * triangle's normal, h = n.a), at depth tau D.  The segment to a sample
 * ends at 1 - eps/|d| > 1 - eps/D, so a hit at depth <= D - 2 eps blocks
 * it and a hit at tau >= 1 does not.  For a blocker whose vertices all lie
 * short of D - 2 eps (nearly all; behind o is fine) the cone alone decides;
 * for one reaching the emitter's plane (a wall) the depth condition is one
 * more linear form, and if some sample's ray meets it between the two
 * bounds the caller answers that blocker in 3D.  These forms are linear in
 * a sample's (s, t): two fused multiply-adds each per sample, and a
 * compare.  (select_planar has culled blockers whose shadow misses the
 * emitter.)  If the cone holds the corners of the samples' box, every
 * sample is blocked.  Returns 0 if the blocker is to be tested in 3D, 1 if
 * done, 2 if every sample is blocked. */
typedef struct plane_view {
    float wx, wy, wz;  /* po - o */
    float kx, ky, kz;  /* the plane's unit normal, pointing away from o */
    float D;           /* distance from o to the plane */
    float hi;          /* D - 2 eps: a hit short of this depth blocks */
    float end;         /* no segment reaches this depth */
} plane_view;

/* What the setup pass found for a blocker, and whether it faces o. */
enum { B_NONE = 0, B_CONE = 1, B_REACHES = 2, B_ALL = 3, B_KIND = 15, B_FRONT = 16 };
/* Its linear forms in (s, t), each as constant, s and t coefficients:
 * three edges, and for a blocker reaching the plane g and g2. */
enum { W_E0 = 0, W_E1 = 3, W_E2 = 6, W_G = 9, W_G2 = 12 };

/* The setup pass, over the selected blockers side by side: their vertices
 * are gathered relative to o, then eight at a time each gets its kind and
 * forms. */
LIE_HOT static void setup_2d(const lie_env_shadows *v, const uint32_t *blockers, int nb, lie_vec3 o, const plane_view *pv,
                     const lie_light_samples *ls, float *work, size_t stride, uint32_t *kind_out)
{
    float *restrict W[LIE_BLOCKER_WORK];
    for (int k = 0; k < LIE_BLOCKER_WORK; k++)
        W[k] = work + (size_t)k * stride;
    for (int j = 0; j < nb; j++) {
        const mt_tri *T = &v->tris[blockers[j]];
        W[0][j] = T->ax - o.x;
        W[1][j] = T->ay - o.y;
        W[2][j] = T->az - o.z;
        W[3][j] = T->bx - o.x;
        W[4][j] = T->by - o.y;
        W[5][j] = T->bz - o.z;
        W[6][j] = T->cx - o.x;
        W[7][j] = T->cy - o.y;
        W[8][j] = T->cz - o.z;
    }
    const float ux = ls->pu[0], uy = ls->pu[1], uz = ls->pu[2];
    const float vx = ls->pv[0], vy = ls->pv[1], vz = ls->pv[2];
    const float wx = pv->wx, wy = pv->wy, wz = pv->wz, kx = pv->kx, ky = pv->ky, kz = pv->kz;
    const float D = pv->D, hi = pv->hi, end = pv->end;
    const float s_lo = ls->smin, s_hi = ls->smax, t_lo = ls->tmin, t_hi = ls->tmax;
    const float s_abs = lie_maxf(fabsf(s_lo), fabsf(s_hi)), t_abs = lie_maxf(fabsf(t_lo), fabsf(t_hi));
    uint32_t *restrict kind = kind_out;
#pragma omp simd
    for (int j = 0; j < nb; j++) {
        float ax = W[0][j], ay = W[1][j], az = W[2][j], bx = W[3][j], by = W[4][j], bz = W[5][j];
        float cx = W[6][j], cy = W[7][j], cz = W[8][j];
        float la = ax * kx + ay * ky + az * kz, lb = bx * kx + by * ky + bz * kz, lc = cx * kx + cy * ky + cz * kz;
        float lmin = lie_minf(la, lie_minf(lb, lc)), lmax = lie_maxf(la, lie_maxf(lb, lc));
        /* edge planes through o, oriented so that inside is all >= 0 */
        float m0x = ay * bz - az * by, m0y = az * bx - ax * bz, m0z = ax * by - ay * bx;
        float m1x = by * cz - bz * cy, m1y = bz * cx - bx * cz, m1z = bx * cy - by * cx;
        float m2x = cy * az - cz * ay, m2y = cz * ax - cx * az, m2z = cx * ay - cy * ax;
        float det = ax * m1x + ay * m1y + az * m1z;
        float sg = det > 0.0f ? 1.0f : -1.0f;
        m0x *= sg, m0y *= sg, m0z *= sg, m1x *= sg, m1y *= sg, m1z *= sg, m2x *= sg, m2y *= sg, m2z *= sg;
        float e00 = m0x * wx + m0y * wy + m0z * wz, e0s = m0x * ux + m0y * uy + m0z * uz,
              e0t = m0x * vx + m0y * vy + m0z * vz;
        float e10 = m1x * wx + m1y * wy + m1z * wz, e1s = m1x * ux + m1y * uy + m1z * uz,
              e1t = m1x * vx + m1y * vy + m1z * vz;
        float e20 = m2x * wx + m2y * wy + m2z * wz, e2s = m2x * ux + m2y * uy + m2z * uz,
              e2t = m2x * vx + m2y * vy + m2z * vz;
        /* the triangle's plane: g >= 0 iff the hit is short of hi, g2 > 0
         * iff it is short of tau = 1 */
        float e1x = bx - ax, e1y = by - ay, e1z = bz - az, e2x = cx - ax, e2y = cy - ay, e2z = cz - az;
        float nx = e1y * e2z - e1z * e2y, ny = e1z * e2x - e1x * e2z, nz = e1x * e2y - e1y * e2x;
        float h = nx * ax + ny * ay + nz * az;
        float sh = h > 0.0f ? 1.0f : -1.0f;
        float n0 = nx * wx + ny * wy + nz * wz, nu = nx * ux + ny * uy + nz * uz, nv = nx * vx + ny * vy + nz * vz;
        /* every corner of the samples' box inside: every sample blocked */
        int all = 1;
        all &= fmaf(t_lo, e0t, fmaf(s_lo, e0s, e00)) > 0.0f;
        all &= fmaf(t_lo, e0t, fmaf(s_hi, e0s, e00)) > 0.0f;
        all &= fmaf(t_hi, e0t, fmaf(s_lo, e0s, e00)) > 0.0f;
        all &= fmaf(t_hi, e0t, fmaf(s_hi, e0s, e00)) > 0.0f;
        all &= fmaf(t_lo, e1t, fmaf(s_lo, e1s, e10)) > 0.0f;
        all &= fmaf(t_lo, e1t, fmaf(s_hi, e1s, e10)) > 0.0f;
        all &= fmaf(t_hi, e1t, fmaf(s_lo, e1s, e10)) > 0.0f;
        all &= fmaf(t_hi, e1t, fmaf(s_hi, e1s, e10)) > 0.0f;
        all &= fmaf(t_lo, e2t, fmaf(s_lo, e2s, e20)) > 0.0f;
        all &= fmaf(t_lo, e2t, fmaf(s_hi, e2s, e20)) > 0.0f;
        all &= fmaf(t_hi, e2t, fmaf(s_lo, e2s, e20)) > 0.0f;
        all &= fmaf(t_hi, e2t, fmaf(s_hi, e2s, e20)) > 0.0f;
        W[W_E0 + 0][j] = e00, W[W_E0 + 1][j] = e0s, W[W_E0 + 2][j] = e0t;
        W[W_E1 + 0][j] = e10, W[W_E1 + 1][j] = e1s, W[W_E1 + 2][j] = e1t;
        W[W_E2 + 0][j] = e20, W[W_E2 + 1][j] = e2s, W[W_E2 + 2][j] = e2t;
        int none = (lmax < 0.0f) | (lmin > end) | (det == 0.0f); /* behind o, unreached, edge-on */
        int reaches = lmax >= hi;
        /* A blocker reaching the plane whose depth forms keep one sign over
         * the samples' box (a column beside, not under, the light): g >= 0
         * throughout makes it a plain cone; g < 0 and g2 <= 0 throughout,
         * nothing.  The margin covers rounding, as in the corner test. */
        float g0 = sh * (hi * n0 - D * h), gu = sh * hi * nu, gv = sh * hi * nv;
        float k0 = sh * (n0 - h), ku = sh * nu, kv = sh * nv;
        float gs0 = lie_minf(gu * s_lo, gu * s_hi), gs1 = lie_maxf(gu * s_lo, gu * s_hi);
        float gt0 = lie_minf(gv * t_lo, gv * t_hi), gt1 = lie_maxf(gv * t_lo, gv * t_hi);
        float ks1 = lie_maxf(ku * s_lo, ku * s_hi), kt1 = lie_maxf(kv * t_lo, kv * t_hi);
        float gtol = 1e-5f * (fabsf(g0) + fabsf(gu) * s_abs + fabsf(gv) * t_abs);
        float ktol = 1e-5f * (fabsf(k0) + fabsf(ku) * s_abs + fabsf(kv) * t_abs);
        int short_all = g0 + gs0 + gt0 > gtol;
        int reach_none = (g0 + gs1 + gt1 < -gtol) & (k0 + ks1 + kt1 < -ktol);
        int cone_only = (reaches == 0) | short_all;
        W[W_G + 0][j] = g0, W[W_G + 1][j] = gu, W[W_G + 2][j] = gv;
        W[W_G2 + 0][j] = k0, W[W_G2 + 1][j] = ku, W[W_G2 + 2][j] = kv;
        kind[j] = ((none | (reaches & reach_none)) ? B_NONE : !cone_only ? B_REACHES : all ? B_ALL : B_CONE) |
                  (h < 0.0f ? B_FRONT : 0);
    }
}

/* A blocker short of hi: the cone alone decides. */
typedef struct cone {
    float a0, s0, t0, a1, s1, t1, a2, s2, t2;
} cone;

static inline cone cone_of(const float *f)
{
    cone c = {f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7], f[8]};
    return c;
}

static inline int in_cone(cone c, float s, float t)
{
    float e0 = fmaf(t, c.t0, fmaf(s, c.s0, c.a0));
    float e1 = fmaf(t, c.t1, fmaf(s, c.s1, c.a1));
    float e2 = fmaf(t, c.t2, fmaf(s, c.s2, c.a2));
    return (e0 >= 0.0f) & (e1 >= 0.0f) & (e2 >= 0.0f);
}

LIE_HOT static void cone_3(const float *f, const lie_light_samples *ls, uint32_t *occ_out)
{
    const cone c = cone_of(f);
    const float *restrict ss = ls->s, *restrict ts = ls->t;
    uint32_t *restrict occ = occ_out;
    const int n = lie_light_samples_padded(ls);
#pragma omp simd
    for (int i = 0; i < n; i++)
        occ[i] |= (uint32_t)-in_cone(c, ss[i], ts[i]);
}

/* A blocker reaching the emitter's plane: blocked iff in the cone and the
 * hit is short of hi (g >= 0).  Returns nonzero if some sample's ray meets
 * it between hi and tau = 1 (g < 0 < g2): then the 3D test decides. */
LIE_HOT static uint32_t cone_5(const float *f, const lie_light_samples *ls, uint32_t *occ_out)
{
    const cone c = cone_of(f);
    const float g0 = f[9], gu = f[10], gv = f[11], k0 = f[12], ku = f[13], kv = f[14];
    const float *restrict ss = ls->s, *restrict ts = ls->t;
    uint32_t *restrict occ = occ_out;
    const int n = lie_light_samples_padded(ls);
    uint32_t unsure = 0;
#pragma omp simd reduction(| : unsure)
    for (int i = 0; i < n; i++) {
        float s = ss[i], t = ts[i];
        float g = fmaf(t, gv, fmaf(s, gu, g0));
        float g2 = fmaf(t, kv, fmaf(s, ku, k0));
        int in = in_cone(c, s, t);
        occ[i] |= (uint32_t)-(in & (g >= 0.0f));
        unsure |= (uint32_t)(in & (g < 0.0f) & (g2 > 0.0f));
    }
    return unsure;
}

/* A segment from o to a light sample, both outside a convex solid, that
 * crosses it enters through a face that faces o.  When some selected face
 * of a solid faces o (so o is outside it; every light is, by
 * lie_solids_find), that solid's faces turned away from o can block
 * nothing more: they are dropped.  A closed column seen from the floor
 * has half its faces in a shadow's lists. */
LIE_HOT static void drop_far_faces(const int32_t *solid, const uint32_t *blockers, int nb, uint32_t *kind)
{
    enum { MAX_SOLIDS = 16 };
    int32_t seen[MAX_SOLIDS];
    int n_seen = 0;
    for (int j = 0; j < nb; j++) {
        int32_t id = solid[blockers[j]];
        if (id < 0 || (kind[j] & B_KIND) == B_NONE || !(kind[j] & B_FRONT))
            continue;
        int k = 0;
        while (k < n_seen && seen[k] != id)
            k++;
        if (k == n_seen && n_seen < MAX_SOLIDS)
            seen[n_seen++] = id;
    }
    if (n_seen == 0)
        return;
    for (int j = 0; j < nb; j++) {
        int32_t id = solid[blockers[j]];
        if (id < 0 || (kind[j] & B_FRONT) || (kind[j] & B_KIND) == B_NONE)
            continue;
        for (int k = 0; k < n_seen; k++)
            if (seen[k] == id) {
                kind[j] = B_NONE;
                break;
            }
    }
}

/* The 2D set-up shared by the per-sample and the bitmask answers: the
 * plane view and each selected blocker's kind and forms in q->work (and
 * the far faces of convex solids dropped).  Returns 0 when the segments
 * are to be tested in 3D (not a planar emitter, o at its plane), 2 when
 * some blocker blocks every sample, else 1. */
LIE_HOT static int prepare_2d(const lie_env_shadows *v, const uint32_t *blockers, int n_blockers, lie_shadow_query *q,
                      plane_view *pv_out)
{
    const lie_light_samples *ls = q->ls;
    if (!ls || !ls->planar)
        return 0;
    plane_view pv = {0};
    pv.wx = ls->po[0] - q->o.x;
    pv.wy = ls->po[1] - q->o.y;
    pv.wz = ls->po[2] - q->o.z;
    float d = pv.wx * ls->pn[0] + pv.wy * ls->pn[1] + pv.wz * ls->pn[2];
    float sg = d > 0.0f ? 1.0f : -1.0f;
    pv.kx = sg * ls->pn[0];
    pv.ky = sg * ls->pn[1];
    pv.kz = sg * ls->pn[2];
    pv.D = sg * d;
    pv.hi = pv.D - 2.0f * q->eps;
    const float ext[4] = {ls->smin, ls->smax, ls->tmin, ls->tmax};
    pv.end = unreached_depth(pv.D, q->eps, pv.wx, pv.wy, pv.wz, ext);
    if (!(pv.hi > 0.0f))
        return 0;
    if (pv_out)
        *pv_out = pv;
    setup_2d(v, blockers, n_blockers, q->o, &pv, ls, q->work, q->work_stride, q->kind);
    for (int j = 0; j < n_blockers; j++)
        if ((q->kind[j] & B_KIND) == B_ALL)
            return 2;
    if (v->solid)
        drop_far_faces(v->solid, blockers, n_blockers, q->kind);
    return 1;
}

/* The first blocker from j on that prepare_2d left something to do
 * (n_blockers if none), its kind and its forms, out of the work arrays. */
static int next_blocker(const lie_shadow_query *q, int n_blockers, int j, uint32_t *kind, float f[LIE_BLOCKER_WORK])
{
    while (j < n_blockers && (q->kind[j] & B_KIND) == B_NONE)
        j++;
    if (j == n_blockers)
        return j;
    *kind = q->kind[j] & B_KIND;
    for (int k = 0; k < LIE_BLOCKER_WORK; k++)
        f[k] = q->work[(size_t)k * q->work_stride + (size_t)j];
    return j;
}

/* The query's segments against the selected blockers: in 2D where the
 * emitter is planar and the blocker lies between (prepare_2d), else in 3D. */
static void occluded(void *ctx, const uint32_t *blockers, int n_blockers, lie_shadow_query *q, uint32_t *occ)
{
    const lie_env_shadows *v = ctx;
    const int n = q->n;
    memset(occ, 0, sizeof *occ * (size_t)n);
    const lie_light_samples *ls = q->ls;
    const int planar = prepare_2d(v, blockers, n_blockers, q, NULL);
    if (planar == 0) {
        lie_shadow_query_segments(q);
        for (int j = 0; j < n_blockers; j++)
            blocker_3d(&v->tris[blockers[j]], q->o, q->dx, q->dy, q->dz, n, occ);
        return;
    }
    if (planar == 2) {
        for (int i = 0; i < n; i++)
            occ[i] = ~0u;
        return;
    }
    uint32_t kind = B_NONE;
    float f[LIE_BLOCKER_WORK] = {0.0f};
    for (int j = 0; (j = next_blocker(q, n_blockers, j, &kind, f)) < n_blockers; j++) {
        if (kind == B_CONE) {
            cone_3(f, ls, occ);
        } else if (cone_5(f, ls, occ)) {
            lie_shadow_query_segments(q);
            blocker_3d(&v->tris[blockers[j]], q->o, q->dx, q->dy, q->dz, n, occ);
        }
    }
}

/* The same as a bitmask over the samples of bm (bitmask.h; q->ls must be
 * bm's pattern): the same forms, every blocker's covered samples ORed in.
 * Returns 0, mask undefined, where only 3D tests decide (then occluded()
 * answers the pair). */
/* The set-up both bitmask answers share: prepare_2d, then the mask full
 * (2: some blocker blocks every sample) or empty (1), or 0 (3D tests). */
static int mask_start(const lie_env_shadows *v, const uint32_t *blockers, int n_blockers, lie_shadow_query *q,
                      const lie_bitmask *bm, uint64_t *mask, plane_view *pv)
{
    const int words = lie_bitmask_words(bm);
    const int planar = prepare_2d(v, blockers, n_blockers, q, pv);
    if (planar == 2) {
        for (int w = 0; w < words; w++)
            mask[w] = ~0ull;
        mask[words - 1] = bm->last;
    } else if (planar == 1) {
        memset(mask, 0, sizeof *mask * (size_t)words);
    }
    return planar;
}

static int occluded_mask(void *ctx, const uint32_t *blockers, int n_blockers, lie_shadow_query *q,
                         const lie_bitmask *bm, uint64_t *mask)
{
    const int planar = mask_start(ctx, blockers, n_blockers, q, bm, mask, NULL);
    if (planar != 1)
        return planar != 0;
    uint32_t kind = B_NONE;
    float f[LIE_BLOCKER_WORK] = {0.0f};
    for (int j = 0; (j = next_blocker(q, n_blockers, j, &kind, f)) < n_blockers; j++) {
        if (kind == B_CONE)
            lie_bitmask_cone(bm, f, mask);
        else if (lie_bitmask_cone_depth(bm, f, mask))
            return 0;
        if (lie_bitmask_all(bm, mask))
            break; /* every sample blocked: the rest can add nothing (usually one word read) */
    }
    return 1;
}

static void describe(void *ctx, const lie_surface *sf, int e, int *cls, uint32_t *count, uint64_t *patch_id)
{
    const lie_env_shadows *v = ctx;
    lie_patch_path path;
    const lie_pnode *n = lie_env_find_leaf_path(v->env, sf->tri, e, sf->b1, sf->b2, &path);
    *cls = (int)n->cls;
    *count = n->count;
    *patch_id = lie_hash_u64x4(sf->tri, path.digits, (uint64_t)path.depth, (uint64_t)e);
}

/* A sphere around points (lie_bound_sphere). */
static sphere bounding_sphere(const lie_vec3 *p, uint32_t n)
{
    float f[4];
    lie_bound_sphere(p, n, f);
    sphere b = {f[0], f[1], f[2], f[3]};
    return b;
}

lie_status lie_env_shadows_create(const lie_scene *s, const lie_env *env, lie_env_shadows **out, lie_error *err)
{
    *out = NULL;
    if (env->n_tris != s->n_tris || env->n_clusters != s->n_clusters)
        return lie_error_set(err, LIE_ERR_ARG, s->path,
                             "the cache has %u triangles and %d emitter clusters, the scene %u and %d", env->n_tris,
                             env->n_clusters, s->n_tris, s->n_clusters);
    lie_env_shadows *v = calloc(1, sizeof *v);
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
    v->emitter_sphere = malloc(sizeof *v->emitter_sphere * ((size_t)s->n_clusters + 1));
    if (!v->tri_sphere || !v->emitter_sphere) {
        lie_env_shadows_destroy(v);
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    }
    for (uint32_t t = 0; t < s->n_tris; t++)
        v->tri_sphere[t] = bounding_sphere(&s->tri_p[3 * (size_t)t], 3);
    for (int e = 0; e < s->n_clusters; e++) {
        const lie_cluster *cl = &s->clusters[e];
        float f[4];
        if (s->emitters[cl->emitter].n_clusters == 1) {
            lie_emitter_bounding_sphere(s, cl->emitter, f); /* r < 0: at infinity, no culling */
        } else {
            lie_vec3 *pts = malloc(sizeof *pts * 3 * ((size_t)cl->n_tris + 1));
            if (!pts) {
                lie_env_shadows_destroy(v);
                return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
            }
            for (uint32_t k = 0; k < cl->n_tris; k++)
                memcpy(pts + 3 * k, &s->tri_p[3 * (size_t)s->cluster_tris[cl->first + k]], sizeof *pts * 3);
            lie_bound_sphere(pts, 3 * cl->n_tris, f);
            free(pts);
        }
        sphere b = {f[0], f[1], f[2], f[3]};
        v->emitter_sphere[e] = b;
    }
    const size_t nt = (size_t)s->n_tris + 1;
    for (int k = 0; k < 4; k++)
        v->soa_sphere[k] = malloc(sizeof(float) * nt);
    for (int k = 0; k < 9; k++)
        v->soa_vert[k] = malloc(sizeof(float) * nt);
    for (int k = 0; k < 13; k++)
        if (!(k < 4 ? v->soa_sphere[k] : v->soa_vert[k - 4])) {
            lie_env_shadows_destroy(v);
            return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
        }
    for (uint32_t t = 0; t < s->n_tris; t++) {
        const sphere b = v->tri_sphere[t];
        v->soa_sphere[0][t] = b.x;
        v->soa_sphere[1][t] = b.y;
        v->soa_sphere[2][t] = b.z;
        v->soa_sphere[3][t] = b.r;
        const lie_vec3 *Q = &s->tri_p[3 * (size_t)t];
        for (int q = 0; q < 3; q++) {
            v->soa_vert[3 * q + 0][t] = Q[q].x;
            v->soa_vert[3 * q + 1][t] = Q[q].y;
            v->soa_vert[3 * q + 2][t] = Q[q].z;
        }
    }
    v->solid = lie_solids_find(s);
    if (!v->solid) {
        lie_env_shadows_destroy(v);
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    }
    v->s = s;
    v->env = env;
    v->oracle.ctx = v;
    v->oracle.classify = classify;
    v->oracle.occluded = occluded;
    v->oracle.occluded_mask = occluded_mask;
    v->oracle.select = select_blockers;
    uint32_t longest = 0;
    for (uint32_t i = 0; i < env->n_nodes; i++)
        if (env->nodes[i].cls == LIE_CLASS_PARTIAL && env->nodes[i].count > longest)
            longest = env->nodes[i].count;
    v->oracle.max_blockers = (int)longest;
    v->oracle.describe = describe;
    v->oracle.solid = v->solid;
    *out = v;
    return LIE_OK;
}

const lie_vis_oracle *lie_env_shadows_oracle(const lie_env_shadows *v) { return &v->oracle; }

void lie_env_shadows_record_unbuilt(lie_env_shadows *v, uint8_t *mask) { v->unbuilt = mask; }

void lie_env_shadows_grow(lie_env_shadows *v, uint32_t longest)
{
    if ((int)longest > v->oracle.max_blockers)
        v->oracle.max_blockers = (int)longest;
}

void lie_env_shadows_destroy(lie_env_shadows *v)
{
    if (!v)
        return;
    free(v->tris);
    free(v->tri_sphere);
    free(v->emitter_sphere);
    for (int k = 0; k < 4; k++)
        free(v->soa_sphere[k]);
    for (int k = 0; k < 9; k++)
        free(v->soa_vert[k]);
    free(v->solid);
    free(v);
}
