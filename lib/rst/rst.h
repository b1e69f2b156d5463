/* SPDX-License-Identifier: Apache-2.0 */
/* lib/rst: ray segment trees (§5).
 *
 * Every node of every patch tree depends on the region of space its
 * segments sweep: the convex hull of the (offset) patch and the emitter.
 * A child's patch lies in its parent's, so its region lies in its
 * parent's: the trees hold the regions of the units' roots, and the
 * patch trees themselves refine an answer (lie_rst_refine).
 * In ray segment space (§5.1) that region is a 5D box: for a pair of
 * parallel planes a = A0 and a = A1 around the scene, a line crossing them
 * at (p, q) and (r, s) and the stretch t of the a axis the segments cover.
 * There is one tree per axis (§5.2: the paper's six trees are the three
 * axes with either orientation; segments are unoriented here, so three
 * suffice); a region goes into the tree of the axis along which its patch
 * and emitter are farthest apart, and a region that no axis separates is
 * kept in a short list tested by its world bounds.  Nodes split into 32
 * children (halving all five axes) when they hold too many regions; regions
 * are copied down, clipped to each child.  A query (§5.3) walks only nodes
 * whose shaft meets the world box, and reports every region that may. */
#ifndef LIE_RST_H
#define LIE_RST_H

#include "core/core.h"
#include "lie/lie.h"
#include "scene/scene.h"

#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

#ifdef __cplusplus
extern "C" {
#endif

typedef struct lie_rst lie_rst;

typedef struct lie_rst_stats {
    uint64_t regions;      /* inserted (one per unit whose root is not unlit) */
    uint64_t fallback;     /* regions no axis could parameterise */
    uint64_t tree_nodes;
    uint64_t stored;       /* region copies held in leaves */
    size_t bytes;          /* memory held */
    double seconds;
} lie_rst_stats;

/* The trees for every unit root of env over scene s (which env was built for),
 * regions computed on `threads` workers (0 = all cores); the trees are the
 * same for any thread count. */
lie_status lie_rst_build(const lie_scene *s, const lie_env *env, int threads, lie_rst **out, lie_rst_stats *stats,
                         lie_error *err);
void lie_rst_destroy(lie_rst *r);

/* Set flags[n] = 1 for every unit root n of env whose region may meet
 * world box b (flags has env->n_nodes entries; set flags are never
 * cleared).  Returns the number of regions tested. */
uint64_t lie_rst_query(const lie_rst *r, lie_box3 b, uint8_t *flags);

/* Tighten flags from lie_rst_query and extend them down the patch trees:
 * a 5D box bounds a shaft loosely (long thin shafts most), so each flagged
 * root's hull — the exact region its segments sweep — is tested against
 * the boxes (GJK) and unflagged if it meets none; the children of a node
 * that stays flagged are flagged and tested in turn.  Afterwards exactly
 * the nodes whose hull meets a box and whose ancestors' hulls all do are
 * flagged.  s and env are the state the trees were built for.  Returns how
 * many flags were cleared (out of memory, it spreads the flags as
 * lie_rst_spread does instead, which is looser but still safe).  On
 * `threads` workers (0: every core), by triangles: the same flags for any
 * count. */
uint64_t lie_rst_refine(const lie_scene *s, const lie_env *env, const lie_box3 *boxes, int n_boxes,
                        uint8_t *flags, int threads);

/* Where hulls cannot be tested (lie_rst_refine's scene would not match
 * env's emitters): flag every node below a flagged one. */
void lie_rst_spread(const lie_env *env, uint8_t *flags);

#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif
