/* SPDX-License-Identifier: Apache-2.0 */
/* Sampled pairs without Embree (answer.h): one seen whole shades its
 * samples and tests none; a partial one tests each sample against its
 * blocker list (a loop the compiler vectorises over the samples). */
#include "shade/answer.h"

static int unshadowed_applies(const lie_pair *p) { return p->cls == LIE_CLASS_VISIBLE; }
static double unshadowed_cost(const lie_pair *p) { return lie_cost_samples(p->n, 0); }

static int unshadowed_shade(lie_pair *p, float rgb[3])
{
    int n = lie_pair_kernel(p, lie_pair_samples(p, 0));
    p->sc->stats.shadow_rays_skipped += (uint64_t)n;
    p->sc->stats.pairs_unshadowed++;
    lie_pair_combine(p, NULL, 0, n, rgb);
    return 1;
}

const lie_answer lie_answer_unshadowed = {"unshadowed", unshadowed_applies, unshadowed_cost, unshadowed_shade};

static int samples_applies(const lie_pair *p) { return p->cls == LIE_CLASS_PARTIAL; }
static double samples_cost(const lie_pair *p) { return lie_cost_samples(p->n, p->n_blockers); }

static int samples_shade(lie_pair *p, float rgb[3])
{
    const lie_light_samples *ls = lie_pair_samples(p, 0);
    int n = lie_pair_kernel(p, ls);
    lie_shadow_query q = lie_pair_query(p, ls, n);
    double t0 = lie_clock_if(p->c->opt->timers);
    lie_pair_blockers(p, &q);
    p->sc->stats.shadow_rays_skipped += (uint64_t)n;
    p->sc->stats.pairs_blockers++;
    if (p->c->opt->timers)
        p->sc->stats.t_blockers += lie_time_now() - t0;
    lie_pair_combine(p, p->sc->blocked, 0, n, rgb);
    return 1;
}

const lie_answer lie_answer_samples = {"samples", samples_applies, samples_cost, samples_shade};
