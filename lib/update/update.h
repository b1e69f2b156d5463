/* SPDX-License-Identifier: Apache-2.0 */
/* lib/update: updating a cache's local illumination environments after
 * scene edits (§5), in two phases so that an interactive program can show
 * an edit at once and refine its frames while the environments catch up.
 *
 *   phase 1, lie_update_edit: apply an edit file to the scene, query the
 *     ray segment trees (lib/rst) with the bounds of every node it moved,
 *     before and after, tighten the answer with the exact hulls down the
 *     patch trees, and mark the units (triangle x emitter) that need work
 *     *pending*: those whose patch or emitter changed (rebuilt afresh) and
 *     those with a flagged node (recomputed where flagged).  Cheap.
 *   phase 2, lie_update_step: recompute pending units, a chunk at a time.
 *     When the last one is done the update is *committed*: the cache gets
 *     the new environments, the scene's triangle count, emitter summary
 *     and state hash, and the edit log gains the edit files.
 *
 * Pending units in a render: lie_update_snapshot gives an env for the
 * edited scene in which every leaf still to be recomputed, and the root of
 * every unit still to be rebuilt, has class LIE_CLASS_NONE; the renderer
 * (lib/shade, lie_env_shadows) already answers those pairs with Embree over
 * the whole scene, so a frame rendered from a snapshot equals a frame
 * rendered with full visibility wherever a unit is pending, and with the
 * finished update everywhere else (unflagged leaves are exactly what the
 * update keeps).  No other flag or field is involved.
 *
 * lie_update_apply is phase 1 for every file and phase 2 to completion: the
 * cache it leaves is byte for byte what lie-build gives for the edited
 * scene, and what rst-update wrote before this module existed.
 *
 * Threads.  An update borrows a cache and its scene (the one
 * lie_cache_load_scene loaded) from create to destroy.
 *   - lie_update_edit writes the scene and the update: nothing may read
 *     either meanwhile (no render, no step, no snapshot).  After it, the
 *     caller's Embree scene and lie_env_shadows for the old scene are stale:
 *     rebuild them (from a snapshot) before rendering again.
 *   - lie_update_step and lie_update_snapshot only read the scene, so
 *     rendering may run concurrently with them, from a snapshot or any
 *     other structure the caller owns.  The two must not run at the same
 *     time as each other (call both from one constructor thread, or lock).
 *     A step that commits replaces cache->env: do not render from
 *     cache->env while steps run.  Snapshots are the caller's, immutable,
 *     and stay valid after later steps, edits and lie_update_destroy.
 * Publishing results to a concurrent renderer is therefore: the
 * constructor thread calls lie_update_step, then lie_update_snapshot, and
 * hands the new env to the renderer (for example swapping a pointer under
 * a lock between frames); the renderer frees the env it no longer uses.
 *
 * A cache built for views (lie-build --view) keeps them: the views are
 * sampled again on the edited scene (lib/shade, lie_camera_pixels), and the
 * units of every triangle whose pixels changed are built afresh, with the
 * pixel rule of the new pixels, as lie-build --view would for the edited
 * scene.  That costs lie_update_edit an Embree build and the views' rays.
 *
 * Costs.  lie_update_edit: two passes over the scene's triangles, the tree
 * queries, the exact hull tests of the flagged nodes and one copy of the
 * environments (milliseconds where a step takes tenths of a second).
 * lie_update_step: the chosen units' recomputation, plus one pass over the
 * whole environments to re-lay them out, plus an Embree build in the first
 * step after an edit.  Units differ widely in work (a floor under a moved
 * object holds most of it), so max_units bounds a step's units, not its
 * time.  lie_update_snapshot: one copy of the environments.
 *
 * An edit that arrives while units are pending is added to the update:
 * the pending set is recomputed for all edits since the last commit,
 * against the environments of that commit, and the chunks already
 * recomputed are done again (a unit's result depends on the final scene
 * only). */
#ifndef LIE_UPDATE_H
#define LIE_UPDATE_H

#include "cache/cache.h"
#include "core/core.h"
#include "edit/edit.h"
#include "lie/lie.h"
#include "rst/rst.h"
#include "scene/scene.h"

#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

#ifdef __cplusplus
extern "C" {
#endif

typedef struct lie_update_options {
    int threads;            /* workers (0 = all cores); results never depend on it */
    int full;               /* recompute every unit, trees unused (the reference for update = rebuild) */
    int keep_trees;         /* rebuild the ray segment trees in the step that commits, so that the
                               next lie_update_edit stays cheap (interactive use); 0: rebuild them
                               only when another edit comes */
    lie_scene_options scene;/* for the scenes that `add` operations load */
} lie_update_options;
lie_update_options lie_update_options_default(void);

/* What an update did, summed over the edits since the last commit. */
typedef struct lie_update_stats {
    int edits;                 /* edit files applied */
    uint64_t units;            /* units of the edited scene */
    uint64_t units_rebuilt;    /* patch or emitter edited: built afresh */
    uint64_t units_flagged;    /* continuing units with a flagged root */
    uint64_t units_changed;    /* of those, units whose content really changed (known at commit) */
    uint64_t units_pending;    /* rebuilt + flagged units not yet recomputed */
    uint64_t nodes_flagged_5d; /* unit roots the trees flagged */
    uint64_t nodes_flagged;    /* patch-tree nodes flagged after the exact hull tests */
    uint64_t nodes_recomputed; /* patch-tree nodes computed by the steps */
    lie_rst_stats rst;         /* the trees the flags came from */
    uint64_t units_views;      /* of the rebuilt units: their triangle's pixels in the views, or the
                                  cost model's decision (an edit of the light), changed */
    double seconds_rst, seconds_edit, seconds_query, seconds_bvh, seconds_update;
    double seconds_views;      /* sampling a view-built cache's views, before and after the edits */
    /* the recomputation's parallel loops (lie_build_stats): CPU seconds of
     * all workers, of the busiest worker per loop, idle tails */
    double seconds_cpu_workers, seconds_cpu_worker_max, seconds_tail;
} lie_update_stats;

typedef struct lie_update lie_update;

/* Start updating `cache`, whose scene `scene` is (same triangles, emitters
 * and state hash); builds the ray segment trees unless opt->full.  Both are
 * borrowed until lie_update_destroy. */
lie_status lie_update_create(lie_cache *cache, lie_scene *scene, const lie_update_options *opt, lie_update **out,
                             lie_error *err);
/* Free the update (NULL is fine).  Pending work is dropped: the cache
 * keeps its last committed state, the scene its edits. */
void lie_update_destroy(lie_update *u);

/* Phase 1: apply one edit to the scene and mark the units it may change
 * pending.  The edit log gets edit->name and the edit's text (lie_edit_text:
 * a parsed file's text as it was, a built edit's written form).  On an error the
 * scene may be partly edited and the update is unusable (every later call
 * fails); the cache is untouched. */
lie_status lie_update_edit(lie_update *u, const lie_edit *edit, lie_error *err);

/* Phase 2: recompute up to max_units pending units (0 = all), in unit
 * order; commit when none is left.  *remaining (may be NULL) receives the
 * pending units left.  Any thread count and any chunking give the same
 * bytes.  On an error the update is unusable and the cache untouched. */
lie_status lie_update_step(lie_update *u, size_t max_units, size_t *remaining, lie_error *err);

/* Pending units (0: committed, nothing to do). */
size_t lie_update_pending(const lie_update *u);

/* An env for the scene as it is now: finished units hold their final
 * content, pending ones LIE_CLASS_NONE where they are not yet known (see
 * above).  The caller owns *out (lie_env_destroy). */
lie_status lie_update_snapshot(const lie_update *u, lie_env **out, lie_error *err);

/* Statistics since the last commit (after a commit: of the update it
 * committed, until the next edit). */
void lie_update_get_stats(const lie_update *u, lie_update_stats *stats);

/* All of it: create, every edit in order (lie_update_edit), steps to
 * completion, destroy.  The cache then holds the
 * edited scene's environments and longer edit log; scene is edited.
 * stats may be NULL. */
lie_status lie_update_apply(lie_cache *cache, lie_scene *scene, const lie_edit *const *edits, int n_edits,
                            const lie_update_options *opt, lie_update_stats *stats, lie_error *err);


/* ---- the asynchronous constructor (§4.3, §4.3.1; lib/update/ctor.c) -------
 *
 * Local illumination environments built on threads of their own while a
 * program renders from them: a program opens a scene (or a partial cache),
 * renders its first frame at once with every unit unbuilt (answered by
 * Embree, lie_env_shadows), and its frames get faster as units land.  Units
 * land a triangle at a time, those covering most pixels of the current view
 * first (mirrors included); a new view reorders the rest.  What lands is
 * what lie-build --view gives for the same views (every view the program
 * handed to lie_ctor_view), or lie-build's whole build (whole): a saved
 * cache (lie_ctor_cache) equals that build byte for byte once nothing is
 * pending, and is a valid partial cache before (lie-build --resume and
 * --into continue it).
 *
 * Threads.  The constructor borrows the scene and its Embree scene.  A
 * renderer reads lie_ctor_env between lie_ctor_read_lock and
 * lie_ctor_read_unlock: the env is changed in place (each landing appends
 * what landed, never copies the whole env) under the write side of that
 * lock.  A builder never waits for the lock: what it cannot land at once
 * lands at the next chance, at the latest when a reader next takes the
 * lock (so hold it for a band of a frame, not for the frame).  To edit the scene: lie_ctor_hold (builds stop, the unit in
 * progress is dropped), edit, make the new Embree scene, lie_ctor_edited,
 * lie_ctor_release. */
typedef struct lie_ctor lie_ctor;

typedef struct lie_ctor_options {
    int threads;             /* constructor threads (0: one a core, as rst-update's update has) */
    lie_build_params params; /* as lie-build's (params.threads is ignored: one per constructor thread) */
    int whole;               /* build every unit, as lie-build without --view; the views only order it */
    int view_width, view_height, max_depth; /* how views are sampled (lie_cache_views) */
    /* The views, all known at the start (a camera path's frames): the
     * units are built for them, and lie_ctor_view only orders the work. */
    const lie_camera *views;
    int n_views;
    int manual;              /* no constructor threads: units are built by lie_ctor_build only */
} lie_ctor_options;
lie_ctor_options lie_ctor_options_default(void);

/* Start building for scene s (borrowed, with rt, until lie_ctor_destroy).
 * `from` (may be NULL) is a cache of s to go on from: its units are kept,
 * its views (if any) are the views, its parameters the parameters; the
 * unbuilt units of a partial one are built. */
lie_status lie_ctor_create(lie_scene *s, const lie_rt *rt, const lie_ctor_options *opt, const lie_cache *from,
                           lie_ctor **out, lie_error *err);
/* Stop the threads (a unit in progress is dropped) and free. */
void lie_ctor_destroy(lie_ctor *c);

/* The live env, for lie_env_shadows_create and renders (under the read lock). */
const lie_env *lie_ctor_env(const lie_ctor *c);
void lie_ctor_read_lock(lie_ctor *c);
void lie_ctor_read_unlock(lie_ctor *c);
/* The longest blocker list landed so far (under the read lock). */
uint32_t lie_ctor_longest(const lie_ctor *c);
/* Changes whenever units land or go: a frame of an older version used fewer units. */
uint64_t lie_ctor_version(const lie_ctor *c);

/* The camera now: what it sees is built first, and (unless whole) it is one
 * of the views the units are built for.  Returns at once; a constructor
 * thread samples its pixels. */
void lie_ctor_view(lie_ctor *c, const lie_camera *cam);

/* Hold the constructor: no unit lands until the matching release (holds
 * nest).  Returns once the threads are idle; a unit in progress is dropped
 * (and built again after the release), so a hold waits for one unit's
 * current patch at most, never for the pending work. */
void lie_ctor_hold(lie_ctor *c);
void lie_ctor_release(lie_ctor *c);

/* After an edit of the scene (held): rt is the edited scene's Embree scene.
 * The views are sampled again; every landed triangle whose units the edit
 * may change is built again: its own triangle moved, its pixels changed, or
 * a box holding its units' shafts meets the moved triangles before or
 * after (a superset of what the ray segment trees flag, so update ≡
 * rebuild holds).  geometry_only: the edit only moved nodes (move, rotate,
 * scale, set-transform); otherwise every unit is built again.  An edit that
 * changes the number of triangles or emitter clusters is refused. */
lie_status lie_ctor_edited(lie_ctor *c, const lie_rt *rt, int geometry_only, lie_error *err);

/* Build now, on `threads` workers of the caller (0: all cores), every
 * pending triangle with mask[t] set (n_tris bytes), or (mask NULL) every
 * pending triangle the camera `cam` sees in the views' sampling (as
 * lie_camera_mark_visible).  *built (may be NULL): triangles built.  For a
 * manual constructor (the caller renders between builds), or a held one. */
lie_status lie_ctor_build(lie_ctor *c, const uint8_t *mask, const lie_camera *cam, int threads, uint64_t *built,
                          lie_error *err);

/* Wait until nothing is pending (seconds < 0: no limit); 1: done, 0: not
 * yet (or held), -1: the constructor failed (err filled, may be NULL). */
int lie_ctor_wait(lie_ctor *c, double seconds, lie_error *err);

/* What has landed over time. */
typedef struct lie_ctor_sample {
    double seconds;    /* since lie_ctor_create */
    uint64_t units;    /* units landed by then */
} lie_ctor_sample;
typedef struct lie_ctor_stats {
    uint64_t units, units_pending, units_built;
    /* patch-tree nodes the builders computed: after an edit, only the
     * nodes it reached, the rest of a unit sent back being copied (as
     * lie_update_stats.nodes_recomputed counts them) */
    uint64_t nodes_built;
    int views;
    int sampling;      /* a view or an edit is being sampled: more units may be pending */
    const lie_ctor_sample *samples; /* valid until the next call on c */
    size_t n_samples;
} lie_ctor_stats;
void lie_ctor_get_stats(lie_ctor *c, lie_ctor_stats *st);

/* A cache of what has landed, laid out as one build lays it out (partial
 * where units are pending: lie-build --resume with the same views finishes
 * it, lie-build --into adds views to it), with the scene path, scene hash
 * and edit log of `provenance` and the state of the scene as edited.  Holds
 * the constructor while it copies (a unit in progress is dropped).
 * *out: lie_cache_destroy. */
lie_status lie_ctor_cache(lie_ctor *c, const lie_cache *provenance, lie_cache **out, lie_error *err);

#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif
