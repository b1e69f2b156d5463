/* SPDX-License-Identifier: Apache-2.0 */
/* Samples against the whole scene through Embree (answer.h): full
 * visibility's one answer, a complex pair's, and a partial pair's whose
 * blocker list would cost more (so that no pair is slower than full
 * visibility; the default modes only, as --exact off and --bitmask only
 * keep the lists). */
#include "shade/answer.h"

#include <string.h>

static int embree_applies(const lie_pair *p)
{
    const lie_render_options *opt = p->c->opt;
    return p->cls == LIE_CLASS_COMPLEX ||
           (p->cls == LIE_CLASS_PARTIAL && opt->exact == LIE_EXACT_AUTO && opt->bitmask == LIE_BITMASK_AUTO &&
            !lie_emitter_is_delta(p->em));
}

static double embree_cost(const lie_pair *p) { return lie_cost_embree(p->n); }

static int embree_shade(lie_pair *p, float rgb[3])
{
    lie_shade_scratch *sc = p->sc;
    const lie_light_samples *ls = lie_pair_samples(p, 0);
    int n = lie_pair_kernel(p, ls);
    lie_shadow_query q = lie_pair_query(p, ls, n);
    memset(sc->blocked, 0, sizeof *sc->blocked * (size_t)n);
    double t0 = lie_clock_if(p->c->opt->timers);
    lie_shadow_query_segments(&q);
    sc->stats.shadow_rays += (uint64_t)lie_pair_embree(p->c, p->o, n, sc, NULL);
    sc->stats.pairs_embree++;
    if (p->c->opt->timers)
        sc->stats.t_embree += lie_time_now() - t0;
    lie_pair_combine(p, sc->blocked, 0, n, rgb);
    return 1;
}

const lie_answer lie_answer_embree = {"embree", embree_applies, embree_cost, embree_shade};
