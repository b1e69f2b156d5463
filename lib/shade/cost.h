/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/shade: the fitted cost model by which a pair's shadow is
 * answered the cheapest way (lib/shade/answer.h), the thresholds below which
 * a frame takes a simpler path, and the benchmark ablations.  Not part of
 * the API: the constants were fitted on one machine and change with it. */
#ifndef LIE_SHADE_COST_H
#define LIE_SHADE_COST_H

#include <math.h>

/* Closed forms (polylight.h) from this many light samples of a pair on:
 * below, a few samples cost less than an edge sum. */
#define LIE_ANALYTIC_MIN_SAMPLES 16
/* Below this many light samples a LIE frame of the per-emitter sampler is
 * answered by full visibility: one or two rays cost less than the leaf
 * lookup and the classes (museum1 at 1 sample: 40 ms against 33 ms). */
#define LIE_ENV_MIN_SAMPLES 4
/* Bitmasks (bitmask.h) from this many samples of the fixed pattern on. */
#define LIE_BITMASK_MIN_SAMPLES 64

/* The cost model of LIE_EXACT_AUTO, in tenths of a nanosecond.  Fitted
 * (least squares on relative error) to --timers of museum1, museum3 and
 * cornell with conservative caches, 256x256, one thread, 256, 1024 and
 * 4096 samples, each path forced in turn, best of 2 (2026-12-01, on 2
 * cores shared with other jobs): testing n samples against b selected
 * blockers costs about n (4 + 2 b), the exact shadow 1400 + 2700 b.  So
 * exact shadows pay from about 1350 samples on.  The fits are within a
 * factor of 1.5 of the measured totals per scene (the cost of a blocker
 * depends on how early it is culled, which b does not see). */
static inline double lie_cost_samples(int n, int b) { return (double)n * (4.0 + 2.0 * b); }
static inline double lie_cost_exact(int b) { return 1400.0 + 2700.0 * b; }
/* The fit is of emitters of one convex piece (the museums' quads); an
 * emitter of m pieces (lib/shade/polybuild.c) back-projects every blocker
 * onto each, so its exact shadow costs m times as much (ccity_buildings'
 * signs of hundreds of pieces went exact at a hundred times the cost of
 * their samples). */
static inline double lie_cost_exact_pieces(int b, int pieces) { return lie_cost_exact(b) * (pieces > 1 ? pieces : 1); }
static inline int lie_cost_exact_pays(int n, int b) { return lie_cost_samples(n, b) >= lie_cost_exact(b); }
/* A bitmask's cost in the same units, fitted the same way: a set-up and
 * the sum over the fewer of the blocked and the visible samples, 500, and
 * per blocker a walk whose cost grows with its shadow's perimeter in
 * groups of 8 samples, 600 + 20 sqrt(n).  A receiver that is not Lambert's
 * still shades every sample (shade_all), 4 n. */
static inline double lie_cost_bitmask(int n, int b, int shade_all)
{
    return 500.0 + (shade_all ? 4.0 * n : 0.0) + (double)b * (600.0 + 20.0 * sqrt((double)n));
}
/* Embree's rays over the whole scene, in the same units: the complex
 * pairs' rays of museum1 and museum3 (--timers, fitted as above), 800 a
 * ray, 70 to 120 ns each on this machine.  (The last fit, 160, sent lists
 * of more than about 230 blockers to Embree at 1024 samples, where the
 * lists cost less: museum3 built with --complex-cap 1024 took 0.68 CPU s
 * a frame at 256 samples with it, 0.49 s with 800.)  A pair whose list
 * answers cost more (hundreds of blockers) asks Embree instead, so that no
 * pair is slower than full visibility (with the default modes; --exact off
 * and --bitmask only keep the lists). */
static inline double lie_cost_embree(int n) { return 800.0 * n; }

/* Under the LIE-guided budget, a partial pair's exact shadow (noiseless)
 * is taken wherever it costs less than this many of Embree's rays: the
 * samples a sampled pair needs before its noise is as small as the exact
 * shadow's rounding (the museums reach p99 <= 2% from about 4096 samples
 * per emitter; docs/measurements.md, "Equal quality"). */
#define LIE_GUIDED_SAMPLES 4096
/* The guided budget visits every emitter at every point (its class, its
 * closed form): it serves while each emitter has this many of the
 * point's samples, else the light tree chooses.  Measured on
 * ccity_buildings (155 emitters, docs/measurements.md, "Light groups"):
 * guided at 256 samples took 3.5 s for p99 46%, the tree 1.7 s for 35%. */
#define LIE_GUIDED_EMITTER_SAMPLES 8

/* Benchmark ablations of --visibility=lie (lie_render_options.ablate;
 * lie-render --lie-skip): answer partial pairs (their blocker tests) or
 * complex pairs (their Embree rays) as unshadowed, so that side-by-side
 * runs show where a LIE frame's time goes.  The images are wrong. */
enum { LIE_ABLATE_BLOCKERS = 1u << 0, LIE_ABLATE_FALLBACK = 1u << 1 };

#endif
