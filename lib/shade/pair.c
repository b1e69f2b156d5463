/* SPDX-License-Identifier: Apache-2.0 */
/* What the ways of answering a pair (answer.h) share: per-worker scratch,
 * the kernels that weigh each light sample's unshadowed contribution in one
 * branch-free loop over structure-of-arrays samples (vectorised by the
 * compiler), the sums of the visible ones, and the closed forms.
 *
 *   L = sum_i  f(wi, wo) cos(theta_i) cos(theta_e) / d^2 * Le / (pdf n) * V_i
 *
 * (area emitters; point lights: I cos(theta_i) / d^2, directional: E cos). */
#include "shade/answer.h"

#include <stdlib.h>
#include <string.h>

lie_status lie_shade_scratch_init(lie_shade_scratch *sc, int cap, int max_blockers, int n_emitters)
{
    memset(sc, 0, sizeof *sc);
    if (cap < 1)
        cap = 1;
    size_t stride = ((size_t)cap + 15) & ~(size_t)15;
    float *block = aligned_alloc(64, sizeof(float) * 15 * stride);
    sc->blocked = aligned_alloc(64, sizeof *sc->blocked * stride);
    sc->blocked_part = aligned_alloc(64, sizeof *sc->blocked_part * stride);
    sc->idx = malloc(sizeof(int) * stride);
    sc->mask = malloc(sizeof *sc->mask * (stride / 64 + 1));
    if (!block || !sc->blocked || !sc->blocked_part || !sc->idx || !sc->mask) {
        free(block);
        free(sc->blocked);
        free(sc->blocked_part);
        free(sc->idx);
        free(sc->mask);
        memset(sc, 0, sizeof *sc);
        return LIE_ERR_NOMEM;
    }
    memset(block, 0, sizeof(float) * 15 * stride);
    float **arr[15] = {&sc->contrib_r, &sc->contrib_g, &sc->contrib_b, &sc->dx, &sc->dy, &sc->dz, &sc->dist,
                       &sc->batch.ox, &sc->batch.oy, &sc->batch.oz, &sc->batch.dx,
                       &sc->batch.dy, &sc->batch.dz, &sc->batch.tnear, &sc->batch.tfar};
    for (int k = 0; k < 15; k++)
        *arr[k] = block + (size_t)k * stride;
    sc->batch.occluded = malloc(stride);
    sc->blockers = malloc(sizeof *sc->blockers * ((size_t)(max_blockers > 0 ? max_blockers : 0) + 1));
    sc->blocker_stride = ((size_t)(max_blockers > 0 ? max_blockers : 0) + 16) & ~(size_t)15;
    sc->blocker_work = aligned_alloc(64, sizeof(float) * LIE_BLOCKER_WORK * sc->blocker_stride);
    sc->blocker_kind = malloc(sizeof *sc->blocker_kind * sc->blocker_stride);
    if (!sc->batch.occluded || !sc->blockers || !sc->blocker_work || !sc->blocker_kind ||
        lie_light_samples_alloc(&sc->rotated, cap) != LIE_OK || lie_polylight_work_init(&sc->poly, max_blockers) != LIE_OK ||
        !(sc->picks = malloc(sizeof *sc->picks * ((size_t)n_emitters + 1))) ||
        !(sc->weights = malloc(sizeof *sc->weights * ((size_t)n_emitters + 1))) ||
        !(sc->ids = malloc(sizeof *sc->ids * ((size_t)n_emitters + 1))) ||
        !(sc->by_tree = calloc((size_t)n_emitters + 1, 1))) {
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
    free(sc->contrib_r);
    free(sc->blocked);
    free(sc->blocked_part);
    free(sc->idx);
    free(sc->mask);
    free(sc->batch.occluded);
    free(sc->blockers);
    free(sc->blocker_work);
    free(sc->blocker_kind);
    lie_light_samples_free(&sc->rotated);
    lie_polylight_work_free(&sc->poly);
    free(sc->picks);
    free(sc->weights);
    free(sc->ids);
    free(sc->by_tree);
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
        float sum = visible_sum(sc, sc->contrib_r, occ, bits, n);
        rgb[0] += sum * sc->scale[0];
        rgb[1] += sum * sc->scale[1];
        rgb[2] += sum * sc->scale[2];
        return;
    }
    rgb[0] += visible_sum(sc, sc->contrib_r, occ, bits, n);
    rgb[1] += visible_sum(sc, sc->contrib_g, occ, bits, n);
    rgb[2] += visible_sum(sc, sc->contrib_b, occ, bits, n);
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

/* A Lambert receiver's geometric term cos_r cos_e / d^2 toward a sample
 * at offset d, 0 where a cosine (or the geometric normal's) is not
 * positive or d is 0; sgn -1 takes |cos_e| (a two-sided emitter).  Inline
 * in kernel_area's vector loops. */
static inline float lambert_g(float dx, float dy, float dz, float lnx, float lny, float lnz, float nx, float ny,
                              float nz, float gx, float gy, float gz, float sgn)
{
    float d2 = dx * dx + dy * dy + dz * dz;
    float inv = 1.0f / sqrtf(d2);
    float cr = (nx * dx + ny * dy + nz * dz) * inv;
    float cg = gx * dx + gy * dy + gz * dz;
    float ce = -(lnx * dx + lny * dy + lnz * dz) * inv;
    ce = ce > sgn * ce ? ce : sgn * ce;
    int ok = (cr > 0.0f) & (cg > 0.0f) & (ce > 0.0f) & (d2 > 0.0f);
    float G = cr * ce * (inv * inv);
    return ok ? G : 0.0f;
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
    float *restrict wr = sc->contrib_r, *restrict wg = sc->contrib_g, *restrict wb = sc->contrib_b;
    const float sgn = two_sided ? -1.0f : 1.0f; /* two-sided: |cos| via max(c, -c) */
    if (sf->lambert && ls->uniform && ls->planar) {
        /* ... and a planar emitter: the emitter's cosine is one number,
         * the receiver's cosines are linear forms in (s, t), and G needs
         * one division and no square root (internal.h). */
        lie_planar_lambert P;
        const float *restrict ss = ls->s, *restrict ts = ls->t;
        float *restrict G_out = sc->contrib_r;
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
        float *restrict G_out = sc->contrib_r;
#pragma omp simd
        for (int i = 0; i < n; i++)
            G_out[i] =
                lambert_g(lx[i] - px, ly[i] - py, lz[i] - pz, lnx[i], lny[i], lnz[i], nx, ny, nz, gx, gy, gz, sgn);
        lambert_colour(sf, ls, sc);
        return;
    }
    sc->scalar = 0;
    if (sf->lambert) {
        const float kr = sf->diffuse[0] * (float)M_1_PI, kg = sf->diffuse[1] * (float)M_1_PI,
                    kb = sf->diffuse[2] * (float)M_1_PI;
#pragma omp simd
        for (int i = 0; i < n; i++) {
            float G =
                lambert_g(lx[i] - px, ly[i] - py, lz[i] - pz, lnx[i], lny[i], lnz[i], nx, ny, nz, gx, gy, gz, sgn);
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
    sc->contrib_r[0] = li.li[0] * f[0];
    sc->contrib_g[0] = li.li[1] * f[1];
    sc->contrib_b[0] = li.li[2] * f[2];
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

/* (answer.h) */
int lie_pair_embree(const lie_shade_ctx *c, lie_vec3 o, int n, lie_shade_scratch *sc, const uint32_t *want)
{
    lie_ray_batch *b = &sc->batch;
    int m = 0;
    for (int i = 0; i < n; i++) {
        float w = sc->scalar ? sc->contrib_r[i] : sc->contrib_r[i] + sc->contrib_g[i] + sc->contrib_b[i];
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
            sc->blocked[sc->idx[k]] = b->occluded[k] ? ~0u : 0u;
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

void lie_pair_colour(lie_pair *p)
{
    if (p->sf->lambert) {
        closed_colour(p->pl, p->sf, p->kc);
    } else if (!*p->ltc_ready) {
        lie_ltc_shading_from_surface(lie_ltc_table_default(), p->sf, p->ltc);
        *p->ltc_ready = 1;
    }
}

void lie_pair_ltc(const lie_pair *p, float kl[3]) { lie_polylight_ltc(p->pl, p->ltc, p->o, &p->sc->poly, kl); }

void lie_pair_closed(lie_pair *p)
{
    if (p->have_closed)
        return;
    const int timers = p->c->opt->timers;
    double t0 = lie_clock_if(timers);
    lie_pair_colour(p);
    p->omega = lie_polylight_unshadowed(p->pl, p->o, p->sf->n, p->sf->ng, &p->sc->poly);
    if (!p->sf->lambert)
        lie_polylight_ltc(p->pl, p->ltc, p->o, &p->sc->poly, p->kl);
    if (timers)
        p->sc->stats.t_analytic += lie_time_now() - t0;
    p->have_closed = 1;
}

void lie_pair_add_closed(const lie_pair *p, double omega, const float kl[3], float rgb[3])
{
    add_closed(p->sf, p->kc, omega, kl, rgb);
}

const lie_light_samples *lie_pair_samples(lie_pair *p, int bits)
{
    const lie_shade_ctx *c = p->c;
    const lie_render_options *opt = c->opt;
    if (lie_emitter_is_delta(p->em))
        return NULL;
    if (c->sampler_on || opt->pattern == LIE_PATTERN_ROTATED) {
        /* this point's own rotation of the pattern (Cranley and Patterson
         * 1976): a hash of the pixel, the emitter, the depth and the seed */
        uint64_t h = lie_hash_u64x4(p->key, (uint64_t)p->e, (uint64_t)p->sc->depth, 0x726f74ull ^ opt->seed);
        if (p->group >= 0) {
            h = lie_hash_u64x4(h, (uint64_t)p->group, 0, 0x67726f7570ull);
            lie_light_samples_generate_group(c->s, c->groups, p->group, p->n, lie_hash_to_unit(h),
                                             lie_hash_to_unit(h << 24), c->texlights ? c->texlights[p->e] : NULL,
                                             &p->o, &p->sc->rotated);
            return &p->sc->rotated;
        }
        lie_light_samples_generate_with(c->s, p->e, p->n, lie_hash_to_unit(h), lie_hash_to_unit(h << 24),
                                        c->texlights ? c->texlights[p->e] : NULL, &p->sc->rotated);
        return &p->sc->rotated;
    }
    return bits ? &p->bm->ls : &c->fixed[p->e];
}

/* Each contributing sample's light times the transmittance of its shadow
 * segment (the segment lie_shadow_query_segments makes, origin o): light
 * reaching the point through glass, tinted.  Occluded samples are masked
 * later, as ever.  A scalar (one colour) pair becomes a per-channel one. */
static void transmit_samples(const lie_shade_ctx *c, lie_vec3 o, float eps, const lie_light_samples *ls, int n,
                             lie_shade_scratch *sc)
{
    float *wr = sc->contrib_r, *wg = sc->contrib_g, *wb = sc->contrib_b;
    if (sc->scalar) {
        for (int i = 0; i < n; i++) {
            float w = wr[i];
            wr[i] = w * sc->scale[0];
            wg[i] = w * sc->scale[1];
            wb[i] = w * sc->scale[2];
        }
        sc->scalar = 0;
    }
    for (int i = 0; i < n; i++) {
        if (!(wr[i] + wg[i] + wb[i] > 0.0f))
            continue;
        lie_vec3 d;
        if (ls) {
            d = lie_v3(ls->x[i] - o.x, ls->y[i] - o.y, ls->z[i] - o.z);
            d = lie_v3_scale(d, lie_ray_end_scale(lie_v3_dot(d, d), eps));
        } else {
            d = lie_v3_scale(lie_v3(sc->dx[0], sc->dy[0], sc->dz[0]), lie_ray_end(sc->dist[0], eps));
        }
        float t[3];
        if (lie_rt_transmittance(c->rt, o, d, 0.0f, 1.0f, t)) {
            wr[i] *= t[0];
            wg[i] *= t[1];
            wb[i] *= t[2];
        }
    }
}

int lie_pair_kernel(lie_pair *p, const lie_light_samples *ls)
{
    const int timers = p->c->opt->timers;
    double t0 = lie_clock_if(timers);
    int n = 1;
    if (ls) {
        kernel_area(p->sf, p->o, ls, p->em->double_sided, p->sc);
        n = ls->n;
    } else {
        kernel_delta(p->c, p->sf, p->o, p->e, p->sc);
    }
    if (p->c->transmit)
        transmit_samples(p->c, p->o, p->eps, ls, n, p->sc);
    if (timers)
        p->sc->stats.t_sampled_shading += lie_time_now() - t0;
    p->sc->stats.light_samples += (uint64_t)n;
    return n;
}

lie_shadow_query lie_pair_query(lie_pair *p, const lie_light_samples *ls, int n)
{
    lie_shade_scratch *sc = p->sc;
    lie_shadow_query q = {p->o,  p->eps, ls, n, ls == NULL, sc->dx, sc->dy, sc->dz, sc->blocker_work, sc->blocker_kind,
                          sc->blocker_stride};
    if (!ls) {
        float len = lie_ray_end(sc->dist[0], p->eps);
        sc->dx[0] *= len;
        sc->dy[0] *= len;
        sc->dz[0] *= len;
    }
    return q;
}

void lie_pair_blockers(lie_pair *p, lie_shadow_query *q)
{
    const lie_vis_oracle *vo = p->c->opt->oracle;
    memset(p->sc->blocked, 0, sizeof *p->sc->blocked * (size_t)q->n);
    vo->occluded(vo->ctx, p->sc->blockers, p->n_blockers, q, p->sc->blocked);
}

void lie_pair_combine(lie_pair *p, const uint32_t *occ, int bits, int n, float rgb[3])
{
    lie_shade_scratch *sc = p->sc;
    if ((p->pl || p->group_closed) && p->sf->lambert) {
        /* the ratio estimator: the closed form times the share of the
         * samples' weight that is visible (sc->scalar: a Lambert receiver
         * under an emitter of one colour; Heitz, Hill, McGuire 2018) */
        float all = plain_sum(sc->contrib_r, n);
        float vis = visible_sum(sc, sc->contrib_r, occ, bits, n);
        if (all > 0.0f && vis == 0.0f && !p->have_closed)
            return; /* every sample blocked: the closed form times 0 adds nothing (a point in the
                       umbra of a partial pair, often, at the few samples a pick takes) */
        lie_pair_closed(p);
        add_scaled(p->kc, all > 0.0f ? p->omega * (double)(vis / all) : p->omega, rgb);
        return;
    }
    if (p->pl) {
        /* the same per channel for the glTF BRDF */
        lie_pair_closed(p);
        const float *wc[3] = {sc->contrib_r, sc->scalar ? sc->contrib_r : sc->contrib_g,
                              sc->scalar ? sc->contrib_r : sc->contrib_b};
        for (int k = 0; k < 3; k++) {
            float all = plain_sum(wc[k], n);
            float vis = visible_sum(sc, wc[k], occ, bits, n);
            rgb[k] += all > 0.0f ? p->kl[k] * (vis / all) : p->kl[k];
        }
        return;
    }
    add_pair(sc, occ, bits, n, rgb);
}
