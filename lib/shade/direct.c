/* SPDX-License-Identifier: Apache-2.0 */
/* Direct lighting: for each emitter, the unshadowed contribution of every
 * light sample is computed in one branch-free loop over structure-of-arrays
 * samples (vectorised by the compiler), then visibility is answered by the
 * chosen strategy and the visible contributions are summed.
 *
 *   L_direct = sum_e sum_i  f(wi, wo) cos(theta_i) cos(theta_e) / d^2 * Le * A_e / n * V_i
 *
 * (area emitters; point lights: I cos(theta_i) / d^2, directional: E cos). */
#include "shade/internal.h"
#include "shade/ltc.h"

#include <stdlib.h>
#include <string.h>

lie_status lie_shade_scratch_init(lie_shade_scratch *sc, int cap, int max_blockers)
{
    memset(sc, 0, sizeof *sc);
    if (cap < 1)
        cap = 1;
    size_t stride = ((size_t)cap + 15) & ~(size_t)15;
    float *block = aligned_alloc(64, sizeof(float) * 15 * stride);
    sc->occ = aligned_alloc(64, sizeof *sc->occ * stride);
    sc->occ2 = aligned_alloc(64, sizeof *sc->occ2 * stride);
    sc->idx = malloc(sizeof(int) * stride);
    sc->mask = malloc(sizeof *sc->mask * (stride / 64 + 1));
    if (!block || !sc->occ || !sc->occ2 || !sc->idx || !sc->mask) {
        free(block);
        free(sc->occ);
        free(sc->occ2);
        free(sc->idx);
        free(sc->mask);
        memset(sc, 0, sizeof *sc);
        return LIE_ERR_NOMEM;
    }
    memset(block, 0, sizeof(float) * 15 * stride);
    float **arr[15] = {&sc->wr, &sc->wg, &sc->wb, &sc->dx, &sc->dy, &sc->dz, &sc->dist,
                       &sc->batch.ox, &sc->batch.oy, &sc->batch.oz, &sc->batch.dx,
                       &sc->batch.dy, &sc->batch.dz, &sc->batch.tnear, &sc->batch.tfar};
    for (int k = 0; k < 15; k++)
        *arr[k] = block + (size_t)k * stride;
    sc->batch.occluded = malloc(stride);
    sc->blockers = malloc(sizeof *sc->blockers * ((size_t)(max_blockers > 0 ? max_blockers : 0) + 1));
    sc->bstride = ((size_t)(max_blockers > 0 ? max_blockers : 0) + 16) & ~(size_t)15;
    sc->bwork = aligned_alloc(64, sizeof(float) * LIE_BLOCKER_WORK * sc->bstride);
    sc->bkind = malloc(sizeof *sc->bkind * sc->bstride);
    if (!sc->batch.occluded || !sc->blockers || !sc->bwork || !sc->bkind ||
        lie_light_samples_alloc(&sc->rotated, cap) != LIE_OK || lie_polylight_work_init(&sc->poly, max_blockers) != LIE_OK ||
        lie_sil_work_init(&sc->sil, max_blockers) != LIE_OK) {
        lie_shade_scratch_free(sc);
        return LIE_ERR_NOMEM;
    }
    sc->cap = cap;
    return LIE_OK;
}

void lie_shade_scratch_free(lie_shade_scratch *sc)
{
    if (!sc)
        return;
    free(sc->wr);
    free(sc->occ);
    free(sc->occ2);
    free(sc->idx);
    free(sc->mask);
    free(sc->batch.occluded);
    free(sc->blockers);
    free(sc->bwork);
    free(sc->bkind);
    lie_light_samples_free(&sc->rotated);
    lie_polylight_work_free(&sc->poly);
    lie_sil_work_free(&sc->sil);
    memset(sc, 0, sizeof *sc);
}

/* sum of w[i] over the samples not blocked (occ[i] == 0), in a fixed order:
 * eight lanes, then their pairwise sum, then the tail.  Eight named lanes
 * rather than `omp simd reduction`, whose order follows the vector width
 * and which GCC kept in memory (a store and reload per 8 samples, 40% of
 * the shading time). */
LIE_HOT static float unblocked_sum(const float *w, const uint32_t *occ, int n)
{
    int i = 0;
    float acc[8] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    for (; i + 8 <= n; i += 8)
        for (int k = 0; k < 8; k++)
            acc[k] += occ[i + k] ? 0.0f : w[i + k];
    float sum = lie_sum8(acc);
    for (; i < n; i++)
        sum += occ[i] ? 0.0f : w[i];
    return sum;
}

/* unblocked_sum with nothing blocked, in the same order (the same bits),
 * without reading a mask: the sum of a visible pair */
LIE_HOT static float plain_sum(const float *w, int n)
{
    int i = 0;
    float acc[8] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    for (; i + 8 <= n; i += 8)
        for (int k = 0; k < 8; k++)
            acc[k] += w[i + k];
    float sum = lie_sum8(acc);
    for (; i < n; i++)
        sum += w[i];
    return sum;
}

/* The weights w of the samples not blocked: by the bitmask sc->mask when
 * `bits`, else by occ (NULL: none blocked). */
LIE_HOT static float visible_sum(const lie_shade_scratch *sc, const float *w, const uint32_t *occ, int bits, int n)
{
    if (bits)
        return lie_bitmask_unblocked_sum(w, sc->mask, n);
    return occ ? unblocked_sum(w, occ, n) : plain_sum(w, n);
}

/* Add the pair's contributions to rgb: the samples' weights, masked by
 * occ (or the bitmask) unless every sample is visible (occ NULL). */
static void add_pair(const lie_shade_scratch *sc, const uint32_t *occ, int bits, int n, float rgb[3])
{
    if (sc->scalar) {
        float sum = visible_sum(sc, sc->wr, occ, bits, n);
        rgb[0] += sum * sc->scale[0];
        rgb[1] += sum * sc->scale[1];
        rgb[2] += sum * sc->scale[2];
        return;
    }
    rgb[0] += visible_sum(sc, sc->wr, occ, bits, n);
    rgb[1] += visible_sum(sc, sc->wg, occ, bits, n);
    rgb[2] += visible_sum(sc, sc->wb, occ, bits, n);
}

/* A Lambert receiver under an emitter of one colour: wr holds the
 * geometric term alone, the colour is applied once, to the sum. */
static void lambert_colour(const lie_surface *sf, const lie_light_samples *ls, lie_shade_scratch *sc)
{
    sc->scalar = 1;
    sc->scale[0] = ls->r[0] * sf->diffuse[0] * (float)M_1_PI;
    sc->scale[1] = ls->g[0] * sf->diffuse[1] * (float)M_1_PI;
    sc->scale[2] = ls->b[0] * sf->diffuse[2] * (float)M_1_PI;
}

/* Unshadowed contributions of an area emitter's samples, seen from origin o
 * (the surface point lifted off the surface).  Branch-free: invalid samples
 * get weight 0 by selection, so NaNs from degenerate geometry never leak. */
LIE_HOT static void kernel_area(const lie_surface *sf, lie_vec3 o, const lie_light_samples *ls, int two_sided,
                        lie_shade_scratch *sc)
{
    const int n = ls->n;
    const float px = o.x, py = o.y, pz = o.z;
    const float nx = sf->n.x, ny = sf->n.y, nz = sf->n.z;
    const float gx = sf->ng.x, gy = sf->ng.y, gz = sf->ng.z;
    const float *restrict lx = ls->x, *restrict ly = ls->y, *restrict lz = ls->z;
    const float *restrict lnx = ls->nx, *restrict lny = ls->ny, *restrict lnz = ls->nz;
    const float *restrict lr = ls->r, *restrict lg = ls->g, *restrict lb = ls->b;
    float *restrict wr = sc->wr, *restrict wg = sc->wg, *restrict wb = sc->wb;
    const float sgn = two_sided ? -1.0f : 1.0f; /* two-sided: |cos| via max(c, -c) */
    if (sf->lambert && ls->uniform && ls->planar) {
        /* ... and a planar emitter: the emitter's cosine is one number,
         * the receiver's cosines are linear forms in (s, t), and G needs
         * one division and no square root (internal.h). */
        lie_planar_lambert P;
        const float *restrict ss = ls->s, *restrict ts = ls->t;
        float *restrict G_out = sc->wr;
        if (!lie_planar_lambert_setup(ls, o, sf->n, sf->ng, two_sided, &P)) {
            memset(G_out, 0, sizeof *G_out * (size_t)n); /* behind the emitter */
        } else {
#pragma omp simd
            for (int i = 0; i < n; i++)
                G_out[i] = lie_planar_lambert_g(P, ss[i], ts[i]);
        }
        lambert_colour(sf, ls, sc);
        return;
    }
    if (sf->lambert && ls->uniform) {
        /* The common case: a Lambert receiver and an emitter of one colour.
         * Only the geometric term varies per sample; colour is applied
         * once, to the sum (sc->scalar). */
        float *restrict G_out = sc->wr;
#pragma omp simd
        for (int i = 0; i < n; i++) {
            float dx = lx[i] - px, dy = ly[i] - py, dz = lz[i] - pz;
            float d2 = dx * dx + dy * dy + dz * dz;
            float inv = 1.0f / sqrtf(d2);
            float cr = (nx * dx + ny * dy + nz * dz) * inv;
            float cg = gx * dx + gy * dy + gz * dz;
            float ce = -(lnx[i] * dx + lny[i] * dy + lnz[i] * dz) * inv;
            ce = ce > sgn * ce ? ce : sgn * ce;
            int ok = (cr > 0.0f) & (cg > 0.0f) & (ce > 0.0f) & (d2 > 0.0f);
            float G = cr * ce * (inv * inv);
            G_out[i] = ok ? G : 0.0f;
        }
        lambert_colour(sf, ls, sc);
        return;
    }
    sc->scalar = 0;
    if (sf->lambert) {
        const float kr = sf->diffuse[0] * (float)M_1_PI, kg = sf->diffuse[1] * (float)M_1_PI,
                    kb = sf->diffuse[2] * (float)M_1_PI;
#pragma omp simd
        for (int i = 0; i < n; i++) {
            float dx = lx[i] - px, dy = ly[i] - py, dz = lz[i] - pz;
            float d2 = dx * dx + dy * dy + dz * dz;
            float inv = 1.0f / sqrtf(d2);
            float cr = (nx * dx + ny * dy + nz * dz) * inv;
            float cg = gx * dx + gy * dy + gz * dz;
            float ce = -(lnx[i] * dx + lny[i] * dy + lnz[i] * dz) * inv;
            ce = ce > sgn * ce ? ce : sgn * ce;
            int ok = (cr > 0.0f) & (cg > 0.0f) & (ce > 0.0f) & (d2 > 0.0f);
            float G = cr * ce * (inv * inv);
            G = ok ? G : 0.0f;
            wr[i] = lr[i] * G * kr;
            wg[i] = lg[i] * G * kg;
            wb[i] = lb[i] * G * kb;
        }
        return;
    }
    /* glTF metallic-roughness BRDF (spec Appendix B): GGX D, height-
     * correlated Smith V, Schlick F with F0 = mix(0.04, base, metallic). */
    const float vx = sf->wo.x, vy = sf->wo.y, vz = sf->wo.z;
    const float nv = fmaxf(nx * vx + ny * vy + nz * vz, 1e-4f);
    const float a2 = sf->alpha * sf->alpha;
    const float nv_term = sqrtf(nv * nv * (1.0f - a2) + a2);
    const float cdr = sf->diffuse[0] * (float)M_1_PI, cdg = sf->diffuse[1] * (float)M_1_PI,
                cdb = sf->diffuse[2] * (float)M_1_PI;
    const float f0r = sf->f0[0], f0g = sf->f0[1], f0b = sf->f0[2];
    const float inv_pi = (float)M_1_PI;
#pragma omp simd
    for (int i = 0; i < n; i++) {
        float dx = lx[i] - px, dy = ly[i] - py, dz = lz[i] - pz;
        float d2 = dx * dx + dy * dy + dz * dz;
        float inv = 1.0f / sqrtf(d2);
        float wx = dx * inv, wy = dy * inv, wz = dz * inv;
        float cr = nx * wx + ny * wy + nz * wz;
        float cg = gx * wx + gy * wy + gz * wz;
        float ce = -(lnx[i] * wx + lny[i] * wy + lnz[i] * wz);
        ce = ce > sgn * ce ? ce : sgn * ce;
        float G = cr * ce * (inv * inv);
        int ok = (cr > 0.0f) & (cg > 0.0f) & (ce > 0.0f) & (d2 > 0.0f);
        float hx = wx + vx, hy = wy + vy, hz = wz + vz;
        float h2 = hx * hx + hy * hy + hz * hz;
        float hinv = 1.0f / sqrtf(h2 > 1e-12f ? h2 : 1e-12f);
        float nh = (nx * hx + ny * hy + nz * hz) * hinv;
        nh = nh > 0.0f ? nh : 0.0f;
        float vh = (vx * hx + vy * hy + vz * hz) * hinv;
        vh = vh > 0.0f ? vh : 0.0f;
        float dd = nh * nh * (a2 - 1.0f) + 1.0f;
        float D = a2 * inv_pi / (dd * dd);
        float nl = cr > 1e-6f ? cr : 1e-6f;
        float V = 0.5f / (nl * nv_term + nv * sqrtf(nl * nl * (1.0f - a2) + a2));
        float x = 1.0f - vh, x2 = x * x, s5 = x2 * x2 * x;
        float spec = D * V;
        float Fr = f0r + (1.0f - f0r) * s5, Fg = f0g + (1.0f - f0g) * s5, Fb = f0b + (1.0f - f0b) * s5;
        float fr = cdr * (1.0f - Fr) + Fr * spec;
        float fg = cdg * (1.0f - Fg) + Fg * spec;
        float fb = cdb * (1.0f - Fb) + Fb * spec;
        G = ok ? G : 0.0f;
        wr[i] = lr[i] * G * fr;
        wg[i] = lg[i] * G * fg;
        wb[i] = lb[i] * G * fb;
    }
}

/* One delta light's sample (point, spot or directional), scalar: its
 * light at o in closed form (lie_emitter_incident) times the BRDF. */
static void kernel_delta(const lie_shade_ctx *c, const lie_surface *sf, lie_vec3 o, int e, lie_shade_scratch *sc)
{
    lie_emitter_incident li;
    lie_emitter_light_at(c->s, e, o, c->ray_far, &li);
    float f[3] = {0.0f, 0.0f, 0.0f};
    if (lie_v3_dot(sf->ng, li.wi) > 0.0f)
        lie_brdf_eval_cos(sf, li.wi, f);
    sc->wr[0] = li.li[0] * f[0];
    sc->wg[0] = li.li[1] * f[1];
    sc->wb[0] = li.li[2] * f[2];
    sc->dx[0] = li.wi.x;
    sc->dy[0] = li.wi.y;
    sc->dz[0] = li.wi.z;
    sc->dist[0] = li.dist;
    sc->scalar = 0;
}

/* Each shadow ray is the segment o -> o + d_i, d_i the vector to the
 * sample shortened by eps: the same segments for Embree and for blocker
 * lists. */
LIE_HOT void lie_shadow_query_segments(lie_shadow_query *q)
{
    if (q->have_segments)
        return;
    q->have_segments = 1;
    float *restrict sdx = q->dx, *restrict sdy = q->dy, *restrict sdz = q->dz;
    const float *restrict lx = q->ls->x, *restrict ly = q->ls->y, *restrict lz = q->ls->z;
    const float ox = q->o.x, oy = q->o.y, oz = q->o.z, eps = q->eps;
    const int n = q->n;
#pragma omp simd
    for (int i = 0; i < n; i++) {
        float dx = lx[i] - ox, dy = ly[i] - oy, dz = lz[i] - oz;
        float d2 = dx * dx + dy * dy + dz * dz;
        float k = lie_ray_end_scale(d2, eps);
        sdx[i] = dx * k;
        sdy[i] = dy * k;
        sdz[i] = dz * k;
    }
}

/* Where the closed form serves a pair: the colour that multiplies its
 * projected solid angle, radiance x diffuse / pi. */
static void closed_colour(const lie_polylight *pl, const lie_surface *sf, float k[3])
{
    for (int c = 0; c < 3; c++)
        k[c] = pl->radiance[c] * sf->diffuse[c] * (float)M_1_PI;
}

/* Embree answers the segments (sc->dx, dy, dz from o) of the samples that
 * would contribute (and, when `want` is given, have want[i] set), into
 * sc->occ; returns how many rays it cast. */
static int embree_occluded(const lie_shade_ctx *c, lie_vec3 o, int n, lie_shade_scratch *sc, const uint32_t *want)
{
    lie_ray_batch *b = &sc->batch;
    int m = 0;
    for (int i = 0; i < n; i++) {
        float w = sc->scalar ? sc->wr[i] : sc->wr[i] + sc->wg[i] + sc->wb[i];
        if (!(w > 0.0f) || (want && !want[i]))
            continue;
        b->ox[m] = o.x;
        b->oy[m] = o.y;
        b->oz[m] = o.z;
        b->dx[m] = sc->dx[i];
        b->dy[m] = sc->dy[i];
        b->dz[m] = sc->dz[i];
        b->tnear[m] = 0.0f;
        b->tfar[m] = 1.0f;
        sc->idx[m] = i;
        m++;
    }
    b->n = m;
    if (m > 0) {
        lie_rt_occluded_batch(c->rt, b, c->opt->rays);
        for (int k = 0; k < m; k++)
            sc->occ[sc->idx[k]] = b->occluded[k] ? ~0u : 0u;
    }
    return m;
}

static void add_scaled(const float k[3], double omega, float rgb[3])
{
    float w = (float)omega;
    rgb[0] += k[0] * w;
    rgb[1] += k[1] * w;
    rgb[2] += k[2] * w;
}

/* A pair's light in closed form: a Lambert surface's colour kc times the
 * solid angle omega it sees of the emitter, or the LTC integral kl. */
static void add_closed(const lie_surface *sf, const float kc[3], double omega, const float kl[3], float rgb[3])
{
    if (sf->lambert)
        add_scaled(kc, omega, rgb);
    else
        add_scaled(kl, 1.0, rgb);
}

/* An emitter of several clusters (lie_cluster) under the LIE: the samples
 * are the emitter's, as ever; each sample's shadow test goes to the pair of
 * the cluster holding its triangle.  classify_clusters looks every
 * cluster's pair up: OCCLUDED if all are occluded or unlit, VISIBLE if all
 * are visible, else VISCLASS_CLUSTERS with each pair in sc->ccls/cpair.  A
 * dark cluster's samples carry no light: they count as either. */
#define VISCLASS_CLUSTERS ((lie_vis_class)5)
static lie_vis_class classify_clusters(const lie_shade_ctx *c, const lie_surface *sf, const lie_emitter *em,
                                       lie_shade_scratch *sc, int *unbuilt)
{
    const lie_vis_oracle *vo = c->opt->oracle;
    int all_occ = 1, all_vis = 1;
    for (int j = 0; j < em->n_clusters; j++) {
        const void *pair = NULL;
        if (c->s->clusters[em->first_cluster + j].dark) {
            sc->ccls[j] = LIE_VISCLASS_VISIBLE; /* its samples weigh 0: any answer serves */
            sc->cpair[j] = NULL;
            continue;
        }
        lie_vis_class k = vo->classify(vo->ctx, sf, em->first_cluster + j, &pair);
        if (k == LIE_VISCLASS_UNBUILT) {
            *unbuilt = 1;
            k = LIE_VISCLASS_TEST_ALL;
        }
        if ((k == LIE_VISCLASS_TEST_ALL && (c->opt->lie_skip & LIE_SKIP_FALLBACK)) ||
            (k == LIE_VISCLASS_BLOCKERS && (c->opt->lie_skip & LIE_SKIP_BLOCKERS)))
            k = LIE_VISCLASS_VISIBLE;
        sc->ccls[j] = (int)k;
        sc->cpair[j] = pair;
        all_occ &= k == LIE_VISCLASS_OCCLUDED;
        all_vis &= k == LIE_VISCLASS_VISIBLE;
    }
    return all_occ ? LIE_VISCLASS_OCCLUDED : all_vis ? LIE_VISCLASS_VISIBLE : VISCLASS_CLUSTERS;
}

/* sc->occ for the query's samples, each by its cluster's pair.  The
 * samples are bucketed by cluster first (sc->idx), so that a partial
 * cluster tests only its own samples against its own list: the segments of
 * its samples are gathered (into the ray batch's direction arrays, free
 * until the Embree pass at the end) and answered in 3D. */
static void clustered_occlusion(const lie_shade_ctx *c, lie_shade_scratch *sc, lie_shadow_query *q, int n,
                                const lie_emitter *em)
{
    const lie_scene *s = c->s;
    const lie_vis_oracle *vo = c->opt->oracle;
    const uint32_t *tri = q->ls->tri;
    const int first = em->first_cluster, nc = em->n_clusters;
    lie_render_stats *st = &sc->stats;
    int at[LIE_CLUSTER_MAX + 1] = {0};
    for (int i = 0; i < n; i++)
        at[s->tri_cluster[tri[i]] - first + 1]++;
    for (int j = 0; j < nc; j++)
        at[j + 1] += at[j];
    int fill[LIE_CLUSTER_MAX];
    memcpy(fill, at, sizeof(int) * (size_t)nc);
    for (int i = 0; i < n; i++)
        sc->idx[fill[s->tri_cluster[tri[i]] - first]++] = i;
    memset(sc->occ, 0, sizeof *sc->occ * (size_t)n);
    int any_embree = 0;
    for (int j = 0; j < nc; j++) {
        const int k = sc->ccls[j], m = at[j + 1] - at[j];
        const int *ix = sc->idx + at[j];
        if (m == 0)
            continue;
        if (k == LIE_VISCLASS_OCCLUDED) {
            for (int i = 0; i < m; i++)
                sc->occ[ix[i]] = ~0u;
            st->pairs_occluded++;
        } else if (k == LIE_VISCLASS_BLOCKERS) {
            int nb = vo->select(vo->ctx, sc->cpair[j], first + j, q->o, q->eps, sc->blockers);
            if (nb == 0)
                continue;
            if (c->opt->exact == LIE_EXACT_AUTO && c->opt->bitmask == LIE_BITMASK_AUTO &&
                lie_render_embree_cost(m) < lie_render_samples_cost(m, nb)) {
                sc->ccls[j] = LIE_VISCLASS_TEST_ALL; /* never slower than full, as a single pair */
                any_embree = 1;
                continue;
            }
            lie_shadow_query_segments(q);
            float *gx = sc->batch.dx, *gy = sc->batch.dy, *gz = sc->batch.dz;
            for (int i = 0; i < m; i++) {
                gx[i] = q->dx[ix[i]];
                gy[i] = q->dy[ix[i]];
                gz[i] = q->dz[ix[i]];
            }
            lie_shadow_query g = {q->o, q->eps, NULL, m, 1, gx, gy, gz, q->work, q->kind, q->work_stride, NULL};
            vo->occluded(vo->ctx, sc->blockers, nb, &g, sc->occ2);
            for (int i = 0; i < m; i++)
                sc->occ[ix[i]] = sc->occ2[i];
            st->pairs_blockers++;
        } else if (k == LIE_VISCLASS_TEST_ALL) {
            any_embree = 1;
        }
    }
    if (any_embree) {
        for (int i = 0; i < n; i++)
            sc->occ2[i] = sc->ccls[s->tri_cluster[tri[i]] - first] == LIE_VISCLASS_TEST_ALL;
        lie_shadow_query_segments(q);
        sc->stats.shadow_rays += (uint64_t)embree_occluded(c, q->o, n, sc, sc->occ2);
        st->pairs_embree++;
    }
}

static inline double clock_if(int on) { return on ? lie_time_now() : 0.0; }

/* a pair answered as a bitmask, by the walk per blocker or through
 * silhouette edges, and its time */
static void count_bitmask(lie_render_stats *st, int sil, double dt)
{
    if (sil) {
        st->pairs_silhouette++;
        st->t_silhouette += dt;
    } else {
        st->pairs_bitmask++;
        st->t_bitmask += dt;
    }
}

LIE_HOT void lie_shade_direct(const lie_shade_ctx *c, const lie_surface *sf, uint64_t pixel, int depth,
                      lie_shade_scratch *sc, float rgb[3])
{
    const lie_scene *s = c->s;
    const lie_render_options *opt = c->opt;
    if (sf->mirror)
        return; /* a delta BRDF sees area lights only through reflection rays */
    /* Shadow rays leave from the surface lifted along the geometric normal
     * and stop as far short of the emitter (lib/rt/rt.h). */
    float eps = lie_ray_eps(sf->p);
    lie_vec3 o = lie_ray_origin(sf->p, sf->ng, eps);
    const int timers = opt->timers;
    lie_render_stats *st = &sc->stats;
    lie_ltc_shading ltc; /* set up at the first pair that needs it */
    int ltc_ready = 0, unbuilt_seen = 0;
    for (int e = 0; e < s->n_emitters; e++) {
        const lie_emitter *em = &s->emitters[e];
        if (lie_emitter_owns(em, sf->tri))
            continue; /* an emitter does not light itself */
        lie_vis_class cls = LIE_VISCLASS_TEST_ALL;
        const void *pair = NULL;
        int n_blockers = 0;
        const int clustered = opt->visibility == LIE_VIS_LIE && opt->oracle && em->n_clusters > 1;
        if (clustered) {
            int unbuilt = 0;
            cls = classify_clusters(c, sf, em, sc, &unbuilt);
            if (unbuilt) {
                st->pairs_unbuilt++;
                st->points_unbuilt += !unbuilt_seen;
                unbuilt_seen = 1;
            }
            if (cls == LIE_VISCLASS_OCCLUDED) {
                sc->stats.shadow_rays_skipped += (uint64_t)opt->light_samples;
                st->pairs_occluded++;
                continue;
            }
        } else if (opt->visibility == LIE_VIS_LIE && opt->oracle) {
            cls = opt->oracle->classify(opt->oracle->ctx, sf, em->first_cluster, &pair);
            if (cls == LIE_VISCLASS_UNBUILT) {
                st->pairs_unbuilt++;
                st->points_unbuilt += !unbuilt_seen;
                unbuilt_seen = 1;
                cls = LIE_VISCLASS_TEST_ALL;
            }
            if (cls == LIE_VISCLASS_OCCLUDED) {
                sc->stats.shadow_rays_skipped += (uint64_t)lie_emitter_sample_count(em, opt->light_samples);
                st->pairs_occluded++;
                continue;
            }
            if (cls == LIE_VISCLASS_BLOCKERS) {
                /* of the patch's blockers, those this point's segments can meet */
                n_blockers = opt->oracle->select(opt->oracle->ctx, pair, em->first_cluster, o, eps, sc->blockers);
                if (n_blockers == 0 || (opt->lie_skip & LIE_SKIP_BLOCKERS))
                    cls = LIE_VISCLASS_VISIBLE;
            } else if (cls == LIE_VISCLASS_TEST_ALL && (opt->lie_skip & LIE_SKIP_FALLBACK)) {
                cls = LIE_VISCLASS_VISIBLE;
            }
        } else if (opt->visibility == LIE_VIS_NONE) {
            cls = LIE_VISCLASS_VISIBLE;
        }
        /* A receiver under a planar emitter of one radiance: the closed
         * form (polylight.h) for the unshadowed part, and for the visible
         * part of a partial pair.  Lambert's edge sum is exact; the glTF
         * BRDF's LTC (ltc.h) is a fit, a few per cent off (more at grazing
         * views), so it serves only where closed forms were asked for
         * (--light-samples exact) and the sampled shading stays the
         * default. */
        const lie_polylight *pl =
            c->analytic && c->poly && (sf->lambert || opt->exact == LIE_EXACT_ONLY) ? c->poly[e] : NULL;
        /* A partial pair toward a planar emitter: all samples at once
         * (bitmask.h) where asked, or where cheaper than testing them one by
         * one (the exact shadow is weighed against both below). */
        const lie_bitmask *bm = cls == LIE_VISCLASS_BLOCKERS && c->bits ? c->bits[e] : NULL;
        const int ns = opt->light_samples;
        const double bits_cost = bm ? lie_render_bitmask_cost(ns, n_blockers, !(pl && sf->lambert && bm->ls.uniform)) : 0.0;
        int use_bits = bm && (opt->bitmask == LIE_BITMASK_ONLY || bits_cost < lie_render_samples_cost(ns, n_blockers));
        /* and of those, the ones counted through silhouette edges
         * (silhouette.h): the same bits */
        const int use_sil = bm && opt->oracle && opt->oracle->occluded_sil && opt->silhouette == LIE_SILHOUETTE_ONLY;
        if (cls == LIE_VISCLASS_BLOCKERS && opt->exact == LIE_EXACT_AUTO && opt->bitmask == LIE_BITMASK_AUTO &&
            !lie_emitter_is_delta(em)) {
            /* a list so long that its cheapest answer costs more than
             * Embree's rays (item 8 of issue 12: never slower than full) */
            double best = use_bits ? bits_cost : lie_render_samples_cost(ns, n_blockers);
            if (pl && c->exact && lie_render_exact_cost(n_blockers) < best)
                best = lie_render_exact_cost(n_blockers);
            if (lie_render_embree_cost(ns) < best) {
                cls = LIE_VISCLASS_TEST_ALL;
                bm = NULL;
                use_bits = 0;
            }
        }
        double omega = 0.0;
        float kc[3] = {0.0f, 0.0f, 0.0f}, kl[3] = {0.0f, 0.0f, 0.0f};
        if (pl) {
            if (sf->lambert) {
                closed_colour(pl, sf, kc);
            } else if (!ltc_ready) {
                lie_ltc_shading_from_surface(lie_ltc_table_default(), sf, &ltc);
                ltc_ready = 1;
            }
            if (cls == LIE_VISCLASS_BLOCKERS && c->exact &&
                (opt->exact == LIE_EXACT_ONLY ||
                 (lie_render_exact_pays(opt->light_samples, n_blockers) &&
                  !(use_bits && (opt->bitmask == LIE_BITMASK_ONLY || bits_cost < lie_render_exact_cost(n_blockers)))))) {
                double t0 = clock_if(timers);
                int ok = lie_polylight_visible(pl, o, sf->n, sf->ng, s->tri_p, opt->oracle->solid, sc->blockers, n_blockers, eps,
                                               &sc->poly, &omega) == 0;
                if (ok && !sf->lambert)
                    lie_polylight_ltc(pl, &ltc, o, &sc->poly, kl);
                if (timers)
                    st->t_exact += lie_time_now() - t0;
                if (ok) {
                    add_closed(sf, kc, omega, kl, rgb);
                    st->pairs_exact++;
                    st->shadow_rays_skipped += (uint64_t)opt->light_samples;
                    continue;
                }
                st->exact_overflows++;
            }
            double t0 = clock_if(timers);
            omega = lie_polylight_unshadowed(pl, o, sf->n, sf->ng, &sc->poly);
            if (!sf->lambert)
                lie_polylight_ltc(pl, &ltc, o, &sc->poly, kl);
            if (timers)
                st->t_analytic += lie_time_now() - t0;
            if (cls == LIE_VISCLASS_VISIBLE) {
                add_closed(sf, kc, omega, kl, rgb);
                st->pairs_analytic++;
                st->shadow_rays_skipped += (uint64_t)opt->light_samples;
                continue;
            }
        }
        if (use_bits && pl && sf->lambert && bm->ls.uniform) {
            /* All samples at once, and of the blocked and the visible
             * samples only the fewer shaded (lie_bitmask_lambert): no
             * per-sample pass over the pattern. */
            double t0 = clock_if(timers);
            lie_planar_lambert P;
            const int lit = lie_planar_lambert_setup(&bm->ls, o, sf->n, sf->ng, em->double_sided, &P);
            lie_shadow_query q = {o,         eps,       &bm->ls,    bm->n, 0, sc->dx, sc->dy, sc->dz,
                                  sc->bwork, sc->bkind, sc->bstride, use_sil ? &sc->sil : NULL};
            if (!lit || (use_sil ? opt->oracle->occluded_sil : opt->oracle->occluded_mask)(
                            opt->oracle->ctx, sc->blockers, n_blockers, &q, bm, sc->mask)) {
                if (lit)
                    add_scaled(kc, lie_bitmask_lambert(bm, &P, sc->mask, omega, em->area), rgb);
                st->shadow_rays_skipped += (uint64_t)bm->n;
                count_bitmask(st, use_sil, timers ? lie_time_now() - t0 : 0.0);
                continue;
            }
        }
        double t_shade = clock_if(timers);
        int n;
        const lie_light_samples *ls = NULL;
        if (!lie_emitter_is_delta(em)) {
            ls = use_bits ? &bm->ls : &c->fixed[e];
            if (opt->pattern == LIE_PATTERN_ROTATED) {
                uint64_t h = lie_hash_u64x4(pixel, (uint64_t)e, (uint64_t)depth, 0x726f74ull);
                lie_light_samples_generate(s, e, opt->light_samples, lie_hash_to_unit(h),
                                           lie_hash_to_unit(h << 24), &sc->rotated);
                ls = &sc->rotated;
            }
            kernel_area(sf, o, ls, em->double_sided, sc);
            n = ls->n;
        } else {
            kernel_delta(c, sf, o, e, sc);
            n = 1;
        }
        if (timers)
            st->t_sampled_shading += lie_time_now() - t_shade;
        sc->stats.light_samples += (uint64_t)n;
        if (cls == LIE_VISCLASS_VISIBLE) {
            sc->stats.shadow_rays_skipped += (uint64_t)n;
            st->pairs_unshadowed++;
            add_pair(sc, NULL, 0, n, rgb);
            continue;
        }
        int bits = 0; /* sc->mask answers, not sc->occ */
        if (!use_bits)
            memset(sc->occ, 0, sizeof *sc->occ * (size_t)n);
        {
            lie_shadow_query q = {o,     eps,       ls,       n, ls == NULL, sc->dx, sc->dy, sc->dz,
                                  sc->bwork, sc->bkind, sc->bstride, use_sil ? &sc->sil : NULL};
            float *sdx = sc->dx, *sdy = sc->dy, *sdz = sc->dz;
            if (!ls) {
                float len = lie_ray_end(sc->dist[0], eps);
                sdx[0] *= len;
                sdy[0] *= len;
                sdz[0] *= len;
            }
            double t0 = clock_if(timers);
            if (cls == VISCLASS_CLUSTERS) {
                clustered_occlusion(c, sc, &q, n, em);
                sc->stats.shadow_rays_skipped += (uint64_t)n;
                if (timers)
                    st->t_blockers += lie_time_now() - t0;
            } else if (use_bits && (use_sil ? opt->oracle->occluded_sil : opt->oracle->occluded_mask)(
                                       opt->oracle->ctx, sc->blockers, n_blockers, &q, bm, sc->mask)) {
                bits = 1;
                sc->stats.shadow_rays_skipped += (uint64_t)n;
                count_bitmask(st, use_sil, timers ? lie_time_now() - t0 : 0.0);
            } else if (cls == LIE_VISCLASS_BLOCKERS) {
                /* short lists: test every sample, no compaction */
                opt->oracle->occluded(opt->oracle->ctx, sc->blockers, n_blockers, &q, sc->occ);
                sc->stats.shadow_rays_skipped += (uint64_t)n;
                st->pairs_blockers++;
                if (timers)
                    st->t_blockers += lie_time_now() - t0;
            } else {
                lie_shadow_query_segments(&q);
                sc->stats.shadow_rays += (uint64_t)embree_occluded(c, o, n, sc, NULL);
                st->pairs_embree++;
                if (timers)
                    st->t_embree += lie_time_now() - t0;
            }
        }
        if (pl && sf->lambert) {
            /* the ratio estimator: the closed form times the share of the
             * samples' weight that is visible (sc->scalar: a Lambert
             * receiver under an emitter of one colour) */
            float all = plain_sum(sc->wr, n);
            float vis = visible_sum(sc, sc->wr, sc->occ, bits, n);
            add_scaled(kc, all > 0.0f ? omega * (double)(vis / all) : omega, rgb);
            continue;
        }
        if (pl) {
            /* the same per channel for the glTF BRDF (weights in wr, wg, wb) */
            const float *wc[3] = {sc->wr, sc->scalar ? sc->wr : sc->wg, sc->scalar ? sc->wr : sc->wb};
            for (int k = 0; k < 3; k++) {
                float all = plain_sum(wc[k], n);
                float vis = visible_sum(sc, wc[k], sc->occ, bits, n);
                rgb[k] += all > 0.0f ? kl[k] * (vis / all) : kl[k];
            }
            continue;
        }
        add_pair(sc, sc->occ, bits, n, rgb);
    }
}
