/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/shade: the ways a (shading point, emitter) pair's light
 * is answered, behind one interface (pbrt-v4's shape: a table of functions
 * per kind, a file per kind):
 *   closed     a pair seen whole, in closed form (answer_closed.c)
 *   exact      a partial pair's visible part by back-projection (answer_exact.c)
 *   unshadowed a pair seen whole, its samples shaded (answer_samples.c)
 *   samples    a partial pair's samples tested against its blocker list (answer_samples.c)
 *   bitmask    a partial pair's fixed pattern answered at once (answer_bitmask.c)
 *   embree     samples against the whole scene (answer_embree.c)
 *   clusters   an emitter of several clusters, each sample by its own pair (answer_clusters.c)
 * Each says whether it applies to a pair, what it costs (lib/shade/cost.h;
 * a mode that forces it costs less than any model) and shades it.
 * lie_shade_direct takes the cheapest that applies, and the next when one
 * cannot answer (an exact shadow past its workspace). */
#ifndef LIE_SHADE_ANSWER_H
#define LIE_SHADE_ANSWER_H

#include "shade/internal.h"
#include "shade/ltc.h"

/* One pair at one shading point, as the answers see it. */
typedef struct lie_pair {
    const lie_shade_ctx *c;
    const lie_surface *sf;
    lie_shade_scratch *sc;
    lie_vec3 o;                 /* the shadow rays' origin (the point lifted) */
    float eps;                  /* and how short of the emitter they stop */
    int e;
    const lie_emitter *em;
    lie_class cls;              /* VISIBLE, PARTIAL, COMPLEX (the whole scene) or SPLIT (clusters) */
    int n_blockers;             /* PARTIAL: the selected blockers in sc->blockers */
    int n;                      /* its light samples */
    int group;                  /* the light group they are drawn from (sampler.h), -1: all the emitter */
    uint64_t key;               /* the pattern's rotation (rotated patterns) */
    const lie_polylight *pl;    /* where a closed form serves, else NULL */
    const lie_bitmask *bm;      /* PARTIAL toward a planar emitter with a fixed pattern, else NULL */
    lie_ltc_shading *ltc;       /* the point's LTC set-up, made at the first pair that needs it */
    int *ltc_ready;
    /* the unshadowed closed form (lie_pair_closed): omega times kc
     * (Lambert) or kl (the LTC integral) */
    int have_closed;
    int group_closed;           /* omega and kc are its light group's (no polylight) */
    double omega;
    float kc[3], kl[3];
} lie_pair;

typedef struct lie_answer {
    const char *name;
    int (*applies)(const lie_pair *p);
    double (*cost)(const lie_pair *p);
    /* the pair's light added to rgb: 1; or 0 where it cannot answer (then
     * the next cheapest does) */
    int (*shade)(lie_pair *p, float rgb[3]);
} lie_answer;

extern const lie_answer lie_answer_closed, lie_answer_exact, lie_answer_unshadowed, lie_answer_samples,
    lie_answer_bitmask, lie_answer_embree, lie_answer_clusters;

/* A cost below every model's: what a mode that forces an answer says. */
#define LIE_COST_FORCED (-1.0)

/* ---- shared by the answers (lib/shade/pair.c) ------------------------- */

static inline double lie_clock_if(int on) { return on ? lie_time_now() : 0.0; }
/* The colour that multiplies a Lambert pair's projected solid angle (kc),
 * or the point's LTC set-up; the LTC integral over the pieces the last
 * polylight call left in sc->poly. */
void lie_pair_colour(lie_pair *p);
void lie_pair_ltc(const lie_pair *p, float kl[3]);
/* The unshadowed closed form of a pair with p->pl, once. */
void lie_pair_closed(lie_pair *p);
/* A pair's light in closed form: kc omega (Lambert) or kl, scaled by `visible` (the visible share). */
void lie_pair_add_closed(const lie_pair *p, double omega, const float kl[3], float rgb[3]);
/* The unshadowed contribution of each of the pair's samples (ls; NULL: a
 * delta light's one sample) into the scratch; returns how many. */
int lie_pair_kernel(lie_pair *p, const lie_light_samples *ls);
/* The pair's samples: the fixed pattern (or, with `bits`, the bitmask's
 * order of it), or this point's rotation of it. */
const lie_light_samples *lie_pair_samples(lie_pair *p, int bits);
/* Its shadow query over ls's n samples (delta: the one segment set up). */
lie_shadow_query lie_pair_query(lie_pair *p, const lie_light_samples *ls, int n);
/* Sum the samples' light into rgb: all (occ NULL) or those free in occ
 * (or in the bitmask sc->mask, `bits`), through the ratio estimator where
 * a closed form serves. */
void lie_pair_combine(lie_pair *p, const uint32_t *occ, int bits, int n, float rgb[3]);
/* sc->blocked for n samples against the pair's blocker list, per sample. */
void lie_pair_blockers(lie_pair *p, lie_shadow_query *q);
/* Embree answers the segments of the samples that would contribute (and,
 * when `want` is given, have want[i] set) into sc->blocked; returns how
 * many rays it cast. */
int lie_pair_embree(const lie_shade_ctx *c, lie_vec3 o, int n, lie_shade_scratch *sc, const uint32_t *want);
/* An emitter of several clusters: every cluster's pair looked up, into
 * sc->cluster_class and cluster_pair; OCCLUDED if all are occluded or
 * unlit, VISIBLE if all are visible, else SPLIT.  *unbuilt set when one
 * was not built. */
lie_class lie_clusters_classify(const lie_shade_ctx *c, const lie_surface *sf, const lie_emitter *em,
                                lie_shade_scratch *sc, int *unbuilt);

#endif
