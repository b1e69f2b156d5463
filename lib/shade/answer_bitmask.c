/* SPDX-License-Identifier: Apache-2.0 */
/* A partial pair toward a planar emitter answered with all the samples of
 * its fixed pattern at once, as a bitmask (bitmask.h).  A Lambert receiver
 * under an emitter of one colour then shades only the fewer of the blocked
 * and the visible samples (lie_bitmask_lambert); others shade every
 * sample.  Where the mask cannot be made, the same samples are tested one
 * by one. */
#include "shade/answer.h"

static int bitmask_applies(const lie_pair *p) { return p->cls == LIE_CLASS_PARTIAL && p->bm; }

static double bitmask_cost(const lie_pair *p)
{
    if (p->c->opt->bitmask == LIE_BITMASK_ONLY)
        return LIE_COST_FORCED;
    return lie_cost_bitmask(p->n, p->n_blockers, !(p->pl && p->sf->lambert && p->bm->ls.uniform));
}

static void count(lie_render_stats *st, double t0, int timers)
{
    st->pairs_bitmask++;
    if (timers)
        st->t_bitmask += lie_time_now() - t0;
}

static int bitmask_shade(lie_pair *p, float rgb[3])
{
    const lie_vis_oracle *vo = p->c->opt->oracle;
    const lie_bitmask *bm = p->bm;
    lie_shade_scratch *sc = p->sc;
    lie_render_stats *st = &sc->stats;
    const int timers = p->c->opt->timers;
    if (p->pl && p->sf->lambert && bm->ls.uniform) {
        lie_pair_closed(p);
        double t0 = lie_clock_if(timers);
        lie_planar_lambert P;
        const int lit = lie_planar_lambert_setup(&bm->ls, p->o, p->sf->n, p->sf->ng, p->em->double_sided, &P);
        lie_shadow_query q = lie_pair_query(p, &bm->ls, bm->n);
        if (!lit || vo->occluded_mask(vo->ctx, sc->blockers, p->n_blockers, &q, bm, sc->mask)) {
            if (lit) {
                float w = (float)lie_bitmask_lambert(bm, &P, sc->mask, p->omega, p->em->area);
                for (int k = 0; k < 3; k++)
                    rgb[k] += p->kc[k] * w;
            }
            st->shadow_rays_skipped += (uint64_t)bm->n;
            count(st, t0, timers);
            return 1;
        }
    }
    const lie_light_samples *ls = lie_pair_samples(p, 1);
    int n = lie_pair_kernel(p, ls);
    lie_shadow_query q = lie_pair_query(p, ls, n);
    double t0 = lie_clock_if(timers);
    st->shadow_rays_skipped += (uint64_t)n;
    if (vo->occluded_mask(vo->ctx, sc->blockers, p->n_blockers, &q, bm, sc->mask)) {
        count(st, t0, timers);
        lie_pair_combine(p, NULL, 1, n, rgb);
        return 1;
    }
    lie_pair_blockers(p, &q);
    st->pairs_blockers++;
    if (timers)
        st->t_blockers += lie_time_now() - t0;
    lie_pair_combine(p, sc->blocked, 0, n, rgb);
    return 1;
}

const lie_answer lie_answer_bitmask = {"bitmask", bitmask_applies, bitmask_cost, bitmask_shade};
