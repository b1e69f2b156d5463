/* SPDX-License-Identifier: Apache-2.0 */
/* A pair seen whole toward an emitter a closed form integrates: Lambert's
 * edge sum, or the LTC integral where asked (answer.h).  No samples. */
#include "shade/answer.h"

static int closed_applies(const lie_pair *p) { return p->cls == LIE_CLASS_VISIBLE && p->pl; }

static double closed_cost(const lie_pair *p)
{
    (void)p;
    return LIE_COST_FORCED; /* exact and cheaper than any sample */
}

static int closed_shade(lie_pair *p, float rgb[3])
{
    lie_pair_closed(p);
    lie_pair_add_closed(p, p->omega, p->kl, rgb);
    p->sc->stats.pairs_analytic++;
    p->sc->stats.shadow_rays_skipped += (uint64_t)p->n;
    return 1;
}

const lie_answer lie_answer_closed = {"closed", closed_applies, closed_cost, closed_shade};
