/* SPDX-License-Identifier: Apache-2.0 */
/* All light samples of an emitter at once: blocked samples as bitmasks
 * (the idea of Schwarz & Stamminger 2007, "Bitmask soft shadows": a pixel's
 * shadow is the OR over its blockers of the samples each covers, one bit
 * per sample, 64 per word).
 *
 * A blocker between a shading point and a planar emitter covers the
 * samples whose (s, t) in the emitter's plane satisfy three linear forms,
 * its edge planes through the point (lie_vis.c sets them up; a blocker
 * reaching the emitter's plane adds a depth form).  Schwarz and Stamminger
 * look the samples inside each half-plane up in a table quantised by
 * angle and offset, which moves shadow edges by up to a bin.  Here the
 * answer is exact instead, and the same bit for bit as testing every
 * sample: the fixed pattern is put in an order where every 8 consecutive
 * samples (a byte of the mask), every 64 (a word) and every 8^k are
 * compact in the plane, with a box each.  A blocker's forms are evaluated
 * on 8 boxes at a time: a box wholly inside sets its bits at once, one
 * wholly outside is skipped, and only the samples of the words its edges
 * cross are tested one by one (8 at a time).  So a blocker costs about
 * its shadow's perimeter in words rather than N tests: O(sqrt N).  The
 * boxes are decided with a margin that covers rounding, so a sample near
 * an edge is always decided by the per-sample test, the one the
 * sample-by-sample path uses. */
#ifndef LIE_SHADE_BITMASK_H
#define LIE_SHADE_BITMASK_H

#include "shade/shade.h"

#define LIE_BITMASK_MAXL 8 /* levels of boxes: 8^8 samples */

typedef struct lie_bitmask {
    int n;                          /* samples */
    int n_words;                    /* ceil(n / 64) */
    int levels;                     /* level l groups 8^l samples; the top level has <= 8 groups */
    int n_groups[LIE_BITMASK_MAXL + 1];
    float *box[LIE_BITMASK_MAXL + 1]; /* per level: s0, s1, t0, t1 arrays of a padded group count each */
    size_t box_stride[LIE_BITMASK_MAXL + 1];
    uint64_t last;                  /* the valid bits of the last word */
    float s_abs, t_abs;             /* the samples' largest |s|, |t| (rounding margins) */
    lie_light_samples ls;           /* the pattern in this order */
} lie_bitmask;

/* The samples of a planar pattern (ls->planar) in mask order, with their
 * boxes.  *out = NULL (LIE_OK) for a pattern that is not planar.  The
 * caller owns *out. */
lie_status lie_bitmask_create(const lie_light_samples *ls, lie_bitmask **out);
void lie_bitmask_destroy(lie_bitmask *b);

/* Words a mask of b needs. */
static inline int lie_bitmask_words(const lie_bitmask *b) { return b->n_words; }

/* OR into mask the samples inside a cone: the forms f[3 k] + s f[3 k + 1] +
 * t f[3 k + 2] >= 0 for k = 0, 1, 2 (each evaluated as fmaf(t, ., fmaf(s,
 * ., .)), as the per-sample test does). */
void lie_bitmask_cone(const lie_bitmask *b, const float f[9], uint64_t *mask);

/* The same for a blocker reaching the emitter's plane: a sample inside the
 * cone is blocked if also g = f[9] + s f[10] + t f[11] >= 0.  Returns
 * nonzero if some sample inside the cone has g < 0 < g2 (g2 = f[12] +
 * s f[13] + t f[14]): its segment meets the blocker's plane between the two
 * depth bounds, and only a 3D test can decide (lie_vis.c). */
int lie_bitmask_cone_depth(const lie_bitmask *b, const float f[15], uint64_t *mask);

/* Sum of w[i] over the samples whose bit is clear, in a fixed order (eight
 * lanes, then their pairwise sum, then the tail). */
float lie_bitmask_unblocked_sum(const float *w, const uint64_t *mask, int n);

/* A Lambert receiver under a planar emitter of one radiance, seen from
 * P's point with projected solid angle omega unshadowed (polylight.h),
 * the samples of b standing for `area` (the emitter's): the projected
 * solid angle the samples not in mask leave.  Whichever set is smaller is
 * summed, so the cost follows min(blocked, visible), not N: few blocked,
 * omega minus their Monte Carlo part (omega is the control variate); most
 * blocked, the Monte Carlo sum of the visible ones. */
typedef struct lie_planar_lambert lie_planar_lambert;
double lie_bitmask_lambert(const lie_bitmask *b, const lie_planar_lambert *P, const uint64_t *mask, double omega,
                           double area);

/* Group g of level l (8^l samples from 8^l g): 1 if all its bits are set;
 * set them all. */
int lie_bitmask_group_full(const lie_bitmask *b, const uint64_t *mask, int l, int g);
void lie_bitmask_set_group(const lie_bitmask *b, uint64_t *mask, int l, int g);

/* 1 if every sample's bit is set. */
int lie_bitmask_all(const lie_bitmask *b, const uint64_t *mask);

#endif
