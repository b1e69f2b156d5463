/* SPDX-License-Identifier: Apache-2.0 */
/* Direct lighting at a shading point: which emitters take its light
 * samples (a light sampler, sampler.h, or the LIE's classes), what each
 * (point, emitter) pair's class is, and the cheapest answer for it
 * (answer.h).
 *
 *   L_direct = sum_e  count_e / (n pmf_e) * L_e
 *
 * with L_e the pair's estimate from its count_e samples (or its closed
 * form); the per-emitter sampler takes count_e = n, pmf_e = 1 for every e. */
#include "shade/answer.h"

#include <string.h>

/* The answers, in the order that breaks ties of cost. */
static const lie_answer *const answers[] = {&lie_answer_closed,  &lie_answer_exact,   &lie_answer_unshadowed,
                                            &lie_answer_samples, &lie_answer_bitmask, &lie_answer_embree,
                                            &lie_answer_clusters};
#define N_ANSWERS (int)(sizeof answers / sizeof answers[0])

/* The cheapest answer that applies, then the next where one cannot. */
static void answer_pair(lie_pair *p, float rgb[3])
{
    double cost[N_ANSWERS];
    int tried = 0;
    for (int k = 0; k < N_ANSWERS; k++)
        cost[k] = answers[k]->applies(p) ? answers[k]->cost(p) : INFINITY;
    while (tried < N_ANSWERS) {
        int best = -1;
        for (int k = 0; k < N_ANSWERS; k++)
            if (cost[k] < INFINITY && (best < 0 || cost[k] < cost[best]))
                best = k;
        if (best < 0 || answers[best]->shade(p, rgb))
            return;
        cost[best] = INFINITY;
        tried++;
    }
}

/* The pair's class: the whole scene for full visibility, the LIE's leaf
 * (and of a partial pair, the blockers this point can meet) for LIE
 * visibility, seen whole with no shadows.  Returns 0 when it takes no light
 * (occluded or unlit). */
static int classify(lie_pair *p, int *unbuilt_seen)
{
    const lie_render_options *opt = p->c->opt;
    lie_shade_scratch *sc = p->sc;
    lie_render_stats *st = &sc->stats;
    p->cls = LIE_CLASS_COMPLEX;
    p->n_blockers = 0;
    if (opt->visibility == LIE_VIS_NONE) {
        p->cls = LIE_CLASS_VISIBLE;
    } else if (opt->visibility == LIE_VIS_LIE && opt->oracle) {
        int unbuilt = 0;
        const void *pair = NULL;
        if (p->em->n_clusters > 1) {
            p->cls = lie_clusters_classify(p->c, p->sf, p->em, sc, &unbuilt);
        } else {
            p->cls = opt->oracle->classify(opt->oracle->ctx, p->sf, p->em->first_cluster, &pair);
            unbuilt = p->cls == LIE_CLASS_NONE;
            if (unbuilt)
                p->cls = LIE_CLASS_COMPLEX;
        }
        if (unbuilt) {
            st->pairs_unbuilt++;
            st->points_unbuilt += !*unbuilt_seen;
            *unbuilt_seen = 1;
        }
        if (p->cls == LIE_CLASS_OCCLUDED || p->cls == LIE_CLASS_UNLIT) {
            st->shadow_rays_skipped += (uint64_t)p->n;
            st->pairs_occluded++;
            return 0;
        }
        if (p->cls == LIE_CLASS_PARTIAL) {
            /* of the patch's blockers, those this point's segments can meet */
            p->n_blockers = opt->oracle->select(opt->oracle->ctx, pair, p->em->first_cluster, p->o, p->eps, sc->blockers);
            if (p->n_blockers == 0 || (opt->ablate & LIE_ABLATE_BLOCKERS))
                p->cls = LIE_CLASS_VISIBLE;
        } else if (p->cls == LIE_CLASS_COMPLEX && p->em->n_clusters == 1 && (opt->ablate & LIE_ABLATE_FALLBACK)) {
            p->cls = LIE_CLASS_VISIBLE;
        }
    }
    /* A receiver under a planar emitter of one radiance: the closed form
     * (polylight.h) for the unshadowed part, and for the visible part of
     * a partial pair.  Lambert's edge sum is exact; the glTF BRDF's LTC
     * (ltc.h) is a fit, a few per cent off (more at grazing views), so it
     * serves only where closed forms were asked for (--light-samples
     * exact) and the sampled shading stays the default. */
    const lie_shade_ctx *c = p->c;
    p->pl = c->analytic && c->poly && p->group < 0 && (p->sf->lambert || opt->exact == LIE_EXACT_ONLY) && !c->transmit
                ? c->poly[p->e]
                : NULL;
    p->bm = p->cls == LIE_CLASS_PARTIAL && c->bits && !c->transmit ? c->bits[p->e] : NULL;
    return 1;
}

/* A shading point's state, shared by its pairs. */
typedef struct point {
    const lie_shade_ctx *c;
    const lie_surface *sf;
    lie_shade_scratch *sc;
    lie_vec3 o;
    float eps;
    uint64_t key;
    lie_ltc_shading ltc; /* set up at the first pair that needs it */
    int ltc_ready, unbuilt_seen;
} point;

static void pair_init(point *pt, int e, int n, lie_pair *p)
{
    memset(p, 0, sizeof *p);
    p->c = pt->c;
    p->sf = pt->sf;
    p->sc = pt->sc;
    p->o = pt->o;
    p->eps = pt->eps;
    p->e = e;
    p->em = &pt->c->s->emitters[e];
    p->n = lie_emitter_sample_count(p->em, n);
    p->group = -1;
    p->key = pt->key;
    p->ltc = &pt->ltc;
    p->ltc_ready = &pt->ltc_ready;
}

/* Emitter e's light at the point from n samples (of its light group
 * `group`, or of all of it: -1), weighed by `scale`. */
static void shade_part(point *pt, int e, int group, int n, float scale, float rgb[3])
{
    lie_pair p;
    pair_init(pt, e, n, &p);
    p.group = group;
    if (lie_emitter_owns(p.em, pt->sf->tri) || !classify(&p, &pt->unbuilt_seen))
        return; /* an emitter does not light itself */
    if (group >= 0 && pt->sf->lambert && lie_emitter_uniform(pt->c->s, e) && !pt->c->transmit) {
        /* a group of few triangles of one radiance: their closed form,
         * which the samples' visible share scales (lie_pair_combine) */
        const lie_scene *s = pt->c->s;
        const lie_light_groups *G = pt->c->groups;
        const lie_light_group *g = &G->g[group];
        double omega = 0.0;
        for (uint32_t i = g->first; i < g->first + g->n; i++)
            omega += lie_triangle_unshadowed(&s->tri_p[3 * (size_t)G->tris[i]], p.em->double_sided, p.o, pt->sf->n,
                                             pt->sf->ng);
        if (!(omega > 0.0))
            return; /* nothing of it above the point's horizon */
        for (int k = 0; k < 3; k++)
            p.kc[k] = p.em->radiance[k] * pt->sf->diffuse[k] * (float)M_1_PI;
        p.omega = omega;
        p.have_closed = 1;
        p.group_closed = 1;
    }
    float prgb[3] = {0.0f, 0.0f, 0.0f};
    answer_pair(&p, prgb);
    for (int k = 0; k < 3; k++)
        rgb[k] += scale == 1.0f ? prgb[k] : scale * prgb[k];
}

/* The budget shared by the LIE's classes: unlit and occluded pairs take
 * nothing, delta lights their one sample, pairs seen whole toward a closed
 * form their closed form, and so do partial ones whose exact shadow costs
 * less than the samples that would match it (LIE_GUIDED_SAMPLES); the rest (partial pairs, and pairs no closed
 * form serves) share the n samples systematically in proportion to their
 * unshadowed light: the closed form for Lambert, the LTC integral for the
 * glTF BRDF, else a bound (lie_light_importance).  No light tree can know
 * which pairs are occluded; the LIE does, for the patch. */
static void shade_guided(point *pt, int n, double u, float rgb[3])
{
    const lie_shade_ctx *c = pt->c;
    const lie_scene *s = c->s;
    lie_shade_scratch *sc = pt->sc;
    const lie_surface *sf = pt->sf;
    int m = 0, n_tree_e = 0;
    double total = 0.0, w_tree = 0.0;
    const float brdf = 0.2126f * (sf->diffuse[0] + sf->f0[0]) + 0.7152f * (sf->diffuse[1] + sf->f0[1]) +
                       0.0722f * (sf->diffuse[2] + sf->f0[2]);
    for (int e = 0; e < s->n_emitters; e++) {
        lie_pair p;
        pair_init(pt, e, n, &p);
        if (lie_emitter_owns(p.em, sf->tri) || !classify(&p, &pt->unbuilt_seen))
            continue;
        float w;
        if (lie_emitter_is_delta(p.em) || (p.cls == LIE_CLASS_VISIBLE && p.pl)) {
            answer_pair(&p, rgb);
            continue;
        }
        if (p.cls == LIE_CLASS_COMPLEX && c->groups) {
            /* the LIE knows nothing of its shadow: the light tree's
             * groups serve it, as they serve full visibility */
            float b = lie_light_importance(&c->bounds[e], pt->o, &sf->n);
            if (b > 0.0f) {
                sc->by_tree[e] = 1;
                sc->ids[s->n_emitters - 1 - n_tree_e++] = e; /* from the end: to clear */
                w_tree += (double)(brdf * (1.0 / (M_PI * M_PI))) * b;
            }
            continue;
        }
        if (p.pl) {
            lie_pair_closed(&p);
            const float *k = sf->lambert ? p.kc : p.kl;
            double l = 0.2126 * k[0] + 0.7152 * k[1] + 0.0722 * k[2];
            w = (float)(sf->lambert ? l * p.omega : l);
        } else {
            w = (float)(brdf * (1.0 / (M_PI * M_PI))) * lie_light_importance(&c->bounds[e], pt->o, &sf->n);
        }
        if (!(w > 0.0f))
            continue; /* nothing of it reaches the point */
        if (p.pl && lie_answer_exact.applies(&p) &&
            (c->opt->exact == LIE_EXACT_ONLY ||
             lie_cost_exact_pieces(p.n_blockers, p.pl->n_polys) <= lie_cost_embree(LIE_GUIDED_SAMPLES))) {
            float prgb[3] = {0.0f, 0.0f, 0.0f};
            if (lie_answer_exact.shade(&p, prgb)) {
                for (int k = 0; k < 3; k++)
                    rgb[k] += prgb[k];
                continue;
            }
        }
        sc->ids[m] = e;
        sc->weights[m++] = w;
        total += w;
    }
    /* the complex pairs' share of the budget, by their bound against the
     * others' light, drawn from the tree (picks of other emitters are
     * left out: the sum over the complex ones stays unbiased) */
    int n_tree = 0;
    if (w_tree > 0.0) {
        n_tree = total > 0.0 ? (int)ceil((double)n * w_tree / (w_tree + total)) : n;
        double ut =
            (double)lie_hash_to_unit(lie_hash_u64x4(pt->key, (uint64_t)sc->depth, c->opt->seed, 0x74726565ull));
        int k = c->sampler.cls->distribute(c->sampler.state, pt->o, sf->n, n_tree, ut, sc->picks);
        const lie_light_groups *G = c->groups;
        for (int i = 0; i < k; i++) {
            const lie_light_pick *pk = &sc->picks[i];
            const lie_light_group *g = &G->g[pk->emitter];
            if (sc->by_tree[g->emitter])
                shade_part(pt, g->emitter, g->whole ? -1 : pk->emitter, pk->count,
                           (float)pk->count / ((float)n_tree * pk->pmf), rgb);
        }
        n = n - n_tree > 1 ? n - n_tree : 1;
    }
    for (int i = 0; i < n_tree_e; i++)
        sc->by_tree[sc->ids[s->n_emitters - 1 - i]] = 0; /* for the next point */
    if (!(total > 0.0))
        return;
    if (m > n) {
        /* more pairs than samples: each is chosen in proportion to its
         * light, and weighed by the inverse */
        int k = lie_light_pick_weights(sc->weights, sc->ids, m, total, n, u, sc->picks);
        for (int i = 0; i < k; i++) {
            const lie_light_pick *pk = &sc->picks[i];
            shade_part(pt, pk->emitter, -1, pk->count, (float)pk->count / ((float)n * pk->pmf), rgb);
        }
        return;
    }
    /* Every pair takes a sample and the rest go by light: each pair's
     * estimate is then its own, with no selection to weigh. */
    int k = n > m ? lie_light_pick_weights(sc->weights, sc->ids, m, total, n - m, u, sc->picks) : 0;
    for (int i = 0, j = 0; i < m; i++) {
        int extra = j < k && sc->picks[j].emitter == sc->ids[i] ? sc->picks[j++].count : 0;
        shade_part(pt, sc->ids[i], -1, 1 + extra, 1.0f, rgb);
    }
}

LIE_HOT void lie_shade_direct(const lie_shade_ctx *c, const lie_surface *sf, uint64_t pixel, int depth,
                      lie_shade_scratch *sc, float rgb[3])
{
    const lie_render_options *opt = c->opt;
    if (sf->mirror)
        return; /* a delta BRDF sees area lights only through reflection rays */
    /* Shadow rays leave from the surface lifted along the geometric normal
     * and stop as far short of the emitter (lib/rt/rt.h). */
    point pt;
    pt.c = c, pt.sf = sf, pt.sc = sc, pt.key = pixel;
    pt.eps = lie_ray_eps(sf->p);
    pt.o = lie_ray_origin(sf->p, sf->ng, pt.eps);
    pt.ltc_ready = 0, pt.unbuilt_seen = 0;
    sc->depth = depth;
    const int n = opt->light_samples;
    if (!c->sampler_on) {
        pt.key = pixel & ((1ull << 40) - 1); /* the paper's pattern: the same for every eye sample */
        for (int e = 0; e < c->s->n_emitters; e++)
            shade_part(&pt, e, -1, n, 1.0f, rgb);
        return;
    }
    /* the point's rotation of the sampler's systematic picks */
    double u = (double)lie_hash_to_unit(lie_hash_u64x4(pixel, (uint64_t)depth, opt->seed, 0x73656cull));
    if (c->guided) {
        shade_guided(&pt, n, u, rgb);
        return;
    }
    for (int i = 0; i < c->n_delta_apart; i++)
        shade_part(&pt, c->delta_ids[i], -1, 1, 1.0f, rgb);
    int k = c->sampler.cls->distribute(c->sampler.state, pt.o, sf->n, n, u, sc->picks);
    const lie_light_groups *G = c->groups;
    for (int i = 0; i < k; i++) {
        const lie_light_pick *pk = &sc->picks[i];
        const lie_light_group *g = &G->g[pk->emitter];
        shade_part(&pt, g->emitter, g->whole ? -1 : pk->emitter, pk->count, (float)pk->count / ((float)n * pk->pmf),
                   rgb);
    }
}
