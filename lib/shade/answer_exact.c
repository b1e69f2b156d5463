/* SPDX-License-Identifier: Apache-2.0 */
/* A partial pair's visible part found exactly: its blockers
 * back-projected onto the emitter's plane and integrated in closed form
 * (polylight.h), no samples.  It pays where the blockers are few against
 * the samples (lie_cost_exact); it cannot answer past its workspace (then
 * the next cheapest answer does). */
#include "shade/answer.h"

static int exact_applies(const lie_pair *p) { return p->cls == LIE_CLASS_PARTIAL && p->pl && p->c->exact; }

static double exact_cost(const lie_pair *p)
{
    return p->c->opt->exact == LIE_EXACT_ONLY ? 2.0 * LIE_COST_FORCED : lie_cost_exact_pieces(p->n_blockers, p->pl->n_polys);
}

static int exact_shade(lie_pair *p, float rgb[3])
{
    const lie_shade_ctx *c = p->c;
    lie_shade_scratch *sc = p->sc;
    const int timers = c->opt->timers;
    lie_pair_colour(p);
    double t0 = lie_clock_if(timers), omega = 0.0;
    float kl[3] = {0.0f, 0.0f, 0.0f};
    int ok = lie_polylight_visible(p->pl, p->o, p->sf->n, p->sf->ng, c->s->tri_p, c->opt->oracle->solid, sc->blockers,
                                   p->n_blockers, p->eps, &sc->poly, &omega) == 0;
    if (ok && !p->sf->lambert)
        lie_pair_ltc(p, kl);
    if (timers)
        sc->stats.t_exact += lie_time_now() - t0;
    if (!ok) {
        sc->stats.exact_overflows++;
        return 0;
    }
    lie_pair_add_closed(p, omega, kl, rgb);
    sc->stats.pairs_exact++;
    sc->stats.shadow_rays_skipped += (uint64_t)p->n;
    return 1;
}

const lie_answer lie_answer_exact = {"exact", exact_applies, exact_cost, exact_shade};
