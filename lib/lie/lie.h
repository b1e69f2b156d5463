/* SPDX-License-Identifier: Apache-2.0 */
/* lib/lie: local illumination environments (§4).
 *
 * For every triangle t and emitter cluster c (lie_cluster: an emitter, or a
 * part of a large one) there is one *unit*: a patch tree over
 * t (lib/patch) whose leaves each hold one patch–cluster pair's class —
 * unlit, visible, occluded, partial with a blocker list, or complex.  Trees
 * are per (triangle, cluster), so a pair's subdivision depends on that pair
 * alone and rebuilding one unit gives exactly what a full build gives
 * (lib/update relies on this, in chunks of units of any size).
 *
 * Storage is flat: node arrays and a pooled array of blocker triangle
 * indices, units in the order u = t * n_clusters + c. */
#ifndef LIE_LIE_H
#define LIE_LIE_H

#include "core/core.h"
#include "lie/pair.h"
#include "patch/patch.h"
#include "rt/rt.h"
#include "scene/scene.h"

#include <signal.h>

#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

#ifdef __cplusplus
extern "C" {
#endif

typedef enum lie_class {
    LIE_CLASS_UNLIT = 0,    /* cannot interact: emitter behind the patch or patch behind the emitter */
    LIE_CLASS_VISIBLE = 1,  /* every sampled segment free */
    LIE_CLASS_OCCLUDED = 2, /* every sampled segment blocked */
    LIE_CLASS_PARTIAL = 3,  /* some blocked: test the blocker list */
    LIE_CLASS_COMPLEX = 4,  /* list too long even at the smallest size: use the whole scene */
    LIE_CLASS_SPLIT = 5,    /* interior node: see the four children */
    LIE_CLASS_NONE = 6      /* not built (lie-build --view): the renderer uses the whole scene */
} lie_class;
#define LIE_CLASS_COUNT 7
const char *lie_class_name(lie_class c);

typedef enum lie_blocker_mode {
    LIE_BLOCKERS_SAMPLED = 0,      /* §4.1: shadow segments sampled between patch and emitter */
    LIE_BLOCKERS_CONSERVATIVE = 1  /* §4.1.2 shaft culling: every triangle meeting the hull */
} lie_blocker_mode;

typedef struct lie_build_params {
    uint32_t samples;      /* segments in the first round (--samples) */
    uint32_t max_samples;  /* adaptive rounds stop here (--max-samples) */
    uint32_t max_blockers; /* subdivide when a list is longer (--max-blockers) */
    uint32_t complex_cap;  /* a leaf list longer than this is complex (--complex-cap) */
    float min_patch;       /* smallest patch area / largest triangle area (--min-patch): a floor */
    float split_gain;      /* a split is kept only if it shortens the lists by this share (--split-gain) */
    lie_blocker_mode mode;
    /* Leave a unit that will be complex unbuilt (--complex-predict): a root
     * that would split, on a triangle larger than 1% of the largest, whose
     * smallest patches at its corners and centre (lie_subdiv_may_split's
     * floor) each see more than complex_cap triangles in their shafts, is
     * one complex leaf with the segments of its first sampling alone
     * (lib/lie/subdiv.c).  Its shadow rays go to Embree, as a complex
     * unit's would: the image is unchanged. */
    uint32_t complex_predict;
    int threads;           /* not stored in caches: results never depend on it */
    uint64_t max_nodes;    /* patch-tree nodes a build may make (--max-nodes); 0: the default.
                              Not stored in caches: a build within it gives the same cache */
    /* The cost model (§4.3.3; Table 2's "simple cost model"), in time units,
     * used where a build knows the pixels that see each patch (views): a
     * split pays if the render time it saves over `frames` frames of
     * `light_samples` shadow rays per pixel and emitter beats its build
     * time.  The constants are measured (make bench-build prints them). */
    uint32_t frames;        /* frames the cache is expected to serve (--frames) */
    uint32_t light_samples; /* shadow rays per pixel and emitter in those frames */
    float ns_segment;       /* build: one sampled shadow segment, in ns */
    float ns_blocker;       /* render: one blocker-list triangle test, in ns */
    float ns_ray;           /* render: one Embree shadow ray (complex and unbuilt pairs), in ns */
    /* A whole build (no views) has no pixels: it assumes each of the
     * frames shows this many pixels spread over the scene's surface in
     * proportion to area (lie_whole_pixels), and decides units and splits
     * by the model as a view build does.  0: no model, every unit built,
     * patches as fine as their lists need (as before cache format 7). */
    uint32_t whole_pixels;
} lie_build_params;

#define LIE_SAMPLES_DEFAULT 128u
#define LIE_MAX_SAMPLES_DEFAULT 512u
#define LIE_MAX_BLOCKERS_DEFAULT 8u
#define LIE_COMPLEX_CAP_DEFAULT 128u
#define LIE_MIN_PATCH_DEFAULT 1e-4f
#define LIE_SPLIT_GAIN_DEFAULT 0.25f
#define LIE_FRAMES_DEFAULT 10u
/* Off: on scifi_hallway the probes cost more than the subtrees they save
 * (docs/measurements.md, "Complex units predicted") */
#define LIE_COMPLEX_PREDICT_DEFAULT 0u
#define LIE_MODEL_LIGHT_SAMPLES_DEFAULT 100u
/* The frames a whole build assumes: --view-size's default image */
#define LIE_WHOLE_PIXELS_DEFAULT (512u * 512u)
/* Measured on museum3 at 512x512 (CPU time per event; bench/build.sh
 * prints the measured values beside these).  A blocker test is an
 * effective figure, per light sample and list entry: the renderer answers
 * lists per shading point (lib/shade/polylight.c), so it is far below an
 * Embree ray's share. */
#define LIE_NS_SEGMENT_DEFAULT 300.0f
#define LIE_NS_BLOCKER_DEFAULT 0.3f
#define LIE_NS_RAY_DEFAULT 33.0f
/* --min-patch's lower bound: 1e-8 of the largest triangle is about 13
 * subdivision levels; below that the trees grow by 4x a level for nothing
 * an image can show. */
#define LIE_MIN_PATCH_MIN 1e-8f
/* The node budget: a node is 20 bytes (lie_pnode), held twice while the
 * trees are joined, so the default is about 5 GiB at most. */
#define LIE_MAX_NODES_DEFAULT (UINT64_C(1) << 27)
lie_build_params lie_build_params_default(void);
/* Check ranges; fills err with which parameter is wrong. */
lie_status lie_build_params_check(const lie_build_params *p, lie_error *err);

/* A node of a patch tree.  Leaves have child == 0 (a child is never node 0
 * of the whole array: node 0 is a root, the first unit's or a shared leaf). */
typedef struct lie_pnode {
    uint32_t child;   /* first of four consecutive children, or 0 */
    uint32_t cls;     /* lie_class */
    uint32_t quality; /* segments sampled for this pair (0 for unlit / conservative) */
    uint32_t list;    /* partial: offset of the blocker list in the pool */
    uint32_t count;   /* partial: blockers; complex: blockers found before giving up */
} lie_pnode;

/* A lone leaf: a unit's whole tree when it is one unlit or none leaf, with
 * no segments and no list.  Such a unit holds no node of its own: its root
 * is one of the env's shared leaves, which any number of roots reference
 * and no split node does (the cache writes it as a tag in ROOTS,
 * formats/lie-cache.md).  A build lays an env out so: every other unit's
 * nodes in unit order, then the shared unlit leaf and the shared none
 * leaf, each only if a unit takes it.  A scene's unlit and unbuilt units,
 * most of its units where it has many emitters, then cost a root each. */
static inline int lie_pnode_lone(const lie_pnode *x)
{
    return !x->child && (x->cls == LIE_CLASS_UNLIT || x->cls == LIE_CLASS_NONE) && !x->quality && !x->list &&
           !x->count;
}

typedef struct lie_env {
    uint32_t n_tris;
    int n_clusters;       /* units per triangle: the scene's clusters (lie_scene.n_clusters) */
    uint32_t *root;       /* per unit: its root node */
    lie_pnode *nodes;
    uint32_t n_nodes;
    uint32_t *pool;       /* blocker lists, each sorted and unique */
    uint32_t n_pool;
    lie_build_params params;
    uint64_t scene_hash;
    int partial;          /* an interrupted build: some units left LIE_CLASS_NONE were not built yet
                             (lie_env_build_with's stop; lie-build --resume completes it) */
} lie_env;

typedef struct lie_build_stats {
    uint64_t pairs[LIE_CLASS_COUNT];   /* leaf pairs per class */
    uint64_t patches_per_depth[LIE_PATCH_MAX_DEPTH + 1];
    uint64_t list_hist[18];            /* leaf partial lists: 1,2,3-4,5-8,...,>2^16 */
    uint64_t segments;                 /* shadow segments cast */
    uint64_t blocker_total;            /* sum of partial list lengths */
    uint64_t splits_undone;            /* splits classified but not kept: they did not pay */
    uint64_t units_copied;             /* units copied whole from an old or resumed env */
    uint64_t units_interrupted;        /* units a stop left unbuilt (LIE_CLASS_NONE) */
    /* views: units left to Embree (LIE_CLASS_NONE) by the cost model,
     * lie_unit_pays: the triangle unseen; its emitter's light there too
     * small a share of the point's for the budget's samples to pay for a
     * first round of segments over the frames served */
    uint64_t units_unseen, units_unpaid;
    uint64_t splits_pixels;            /* splits not tried: too few pixels see the patch (views) */
    uint64_t splits_kept;              /* splits made */
    /* sampled leaves whose segments said occluded, or visible though
     * triangles enter the shaft, without proof: each got its exact list
     * instead (lib/lie/subdiv.c), where sampling alone would leak light */
    uint64_t unproven_occluded, unproven_visible;
    /* units that will be complex (lie_build_params.complex_predict): named
     * so before their trees were built (left one complex leaf each, or, in
     * an audit, built anyway); built units whose every leaf came out
     * complex; and, in an audit, the named that came out complex */
    uint64_t complex_predicted, complex_measured, complex_predicted_measured;
    /* the model against the build, over the splits made: the render time
     * they save per frame as the model predicts it before the lookahead
     * (half the parent's list), and as the children's lists give it */
    double split_saving_predicted_ns;
    double split_saving_measured_ns;
    /* a whole build's model (lie_whole_pixels): the shadow-ray time one of
     * its assumed frames saves with the units built, against Embree, in
     * CPU ns: each leaf's pixels (its share by area of its triangle's) x
     * the unit's share of the light samples x (a ray less the leaf's cost) */
    double frame_saving_ns;
    double seconds;
    /* the parallel phase: workers, their summed and largest CPU seconds (each
     * thread's own clock, so other processes do not count), and the wall
     * seconds from the first worker out of work to the end (idle cores) */
    int workers;
    double seconds_cpu_sum, seconds_cpu_max, seconds_tail;
} lie_build_stats;

/* Build every unit of the scene.  Deterministic: the same scene and
 * parameters give the same env for any thread count.  `progress` may be
 * NULL. */
lie_status lie_env_build(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                         lie_progress *progress, lie_env **out, lie_build_stats *stats, lie_error *err);

/* The same, building only the triangles with tri_mask[t] set (NULL: all);
 * the others' units are single LIE_CLASS_NONE nodes. */
lie_status lie_env_build_masked(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                                const uint8_t *tri_mask, lie_progress *progress, lie_env **out,
                                lie_build_stats *stats, lie_error *err);

/* Where a build's units go as they are made (lie_build_control.sink), so
 * that no build holds them all (lie-build writes them to the cache file,
 * lie_cache_stream): called in unit order, from one thread at a time, with
 * each unit's tree from node `root` of `nodes` (children and lists index
 * nodes and pool, valid during the call only), or with root one of the
 * tags below for a unit that is one lone leaf (lie_pnode_lone).  A status
 * other than LIE_OK fails the build with it. */
#define LIE_UNIT_LONE_UNLIT 0xFFFFFFFFu
#define LIE_UNIT_LONE_NONE 0xFFFFFFFEu
typedef lie_status (*lie_unit_sink_fn)(void *ctx, const lie_pnode *nodes, const uint32_t *pool, uint32_t root);

/* How a build runs, beyond its parameters; zeroed means lie_env_build. */
struct lie_pixels;
typedef struct lie_build_control {
    const uint8_t *tri_mask;   /* build only these triangles (NULL: all), as lie_env_build_masked */
    const struct lie_pixels *pixels; /* or build for these views, as lie_env_build_views (NULL: none) */
    lie_progress *progress;    /* may be NULL */
    /* An interrupted build of the same scene, parameters and tri_mask or
     * pixels (its
     * partial flag set, or not): its built units are copied, its unbuilt
     * ones built, so the result is exactly the uninterrupted build's. */
    const lie_env *resume;
    /* Polled by the workers (a signal handler sets it): once nonzero, no
     * further unit is built, a unit in progress is dropped, and the build
     * returns LIE_OK with what it finished, the rest LIE_CLASS_NONE and
     * env->partial set (unless every unit was done). */
    const volatile sig_atomic_t *stop;
    /* Name the units complex_predict would leave unbuilt without leaving
     * them (params->complex_predict 0; lie-build --complex-predict audit):
     * what the prediction says beside what the build measures
     * (lie_build_stats.complex_predicted_measured). */
    int audit_complex;
    /* Give every unit to sink (with sink_ctx) as its triangle is done, in
     * unit order, and keep none: the env returned holds the parameters,
     * counts and partial flag, and no trees (root, nodes and pool NULL).
     * NULL: the env holds them all. */
    lie_unit_sink_fn sink;
    void *sink_ctx;
} lie_build_control;
lie_status lie_env_build_with(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                              const lie_build_control *ctl, lie_env **out, lie_build_stats *stats, lie_error *err);

/* Part of an env, for builds shared out among processes (lie-build under
 * mpirun): units [first_unit, first_unit + n_units), root[i] the root of
 * unit first_unit + i in nodes; child and list offsets index this part's
 * own nodes and pool.  A unit depends on its triangle and emitter alone, so
 * parts built anywhere join into the bytes of one build. */
typedef struct lie_env_part {
    uint64_t first_unit, n_units;
    uint32_t *root;
    lie_pnode *nodes;
    uint32_t n_nodes;
    uint32_t *pool;
    uint32_t n_pool;
} lie_env_part;

/* Build units [first_unit, first_unit + n_units) of lie_env_build_masked's
 * env into *out (freed by lie_env_part_free).  Statistics count these units
 * only, so the sums over a partition are lie_env_build_masked's. */
lie_status lie_env_build_range(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                               const uint8_t *tri_mask, uint64_t first_unit, uint64_t n_units, lie_env_part *out,
                               lie_build_stats *stats, lie_error *err);
/* Join parts that cover every unit of s in order (parts[i + 1] starts where
 * parts[i] ends) into the env lie_env_build_masked builds.  Every child and
 * list offset is checked against its part. */
lie_status lie_env_join(const lie_scene *s, const lie_build_params *p, const lie_env_part *parts, size_t n_parts,
                        lie_env **out, lie_error *err);
void lie_env_part_free(lie_env_part *part);
/* The sum of two build statistics (counts; seconds are a's). */
void lie_build_stats_add(lie_build_stats *a, const lie_build_stats *b);

/* Rebuild the listed units (sorted, unique) in place, with env's own
 * parameters, exactly as lie_env_build would. */
lie_status lie_env_rebuild_units(lie_env *env, const lie_scene *s, const lie_rt *rt,
                                 const uint32_t *units, size_t n_units, int threads,
                                 lie_build_stats *stats, lie_error *err);

/* Update env for scene s (its state after edits).  old_unit has one entry
 * per unit of s: the unit of env it continues (copied, or updated where
 * node_flags marks env nodes to recompute), or -1 to build it afresh.  The
 * result is exactly what lie_env_build gives for s, provided every node
 * whose shaft an edit touched is flagged, and every unit whose patch or
 * emitter changed is built afresh. */
lie_status lie_env_update(lie_env *env, const lie_scene *s, const lie_rt *rt, const int32_t *old_unit,
                          const uint8_t *node_flags, int threads, lie_build_stats *stats, lie_error *err);

/* ---- views: pixels per patch (§4.3.3) ------------------------------------
 *
 * The hits of a view's pixel rays (several per pixel, directly and through
 * mirrors), per triangle: each hit's key is the path of the patch holding
 * it down LIE_PIXEL_LEVELS levels (level 1 in the top bits), sorted, so a
 * patch's pixels are one range of its triangle's keys. */
#define LIE_PIXEL_LEVELS 16
typedef struct lie_pixels {
    uint32_t n_tris;
    uint32_t rays_per_pixel; /* hits that make one pixel */
    uint64_t n_hits;
    uint64_t *first;         /* n_tris + 1: triangle t's keys are key[first[t] .. first[t + 1]) */
    uint32_t *key;
} lie_pixels;
/* The key of local point (b1, b2). */
uint32_t lie_pixels_key(float b1, float b2);
/* From hits (triangle << 32 | key), which are sorted in place: any order
 * of the same hits gives the same result.  *out: lie_pixels_destroy. */
lie_status lie_pixels_create(uint32_t n_tris, uint32_t rays_per_pixel, uint64_t *hits, size_t n_hits,
                             lie_pixels **out, lie_error *err);
void lie_pixels_destroy(lie_pixels *px);
/* The hits of a and b together: the pixels of both sets of views, as if
 * sampled at once. */
lie_status lie_pixels_merge(const lie_pixels *a, const lie_pixels *b, lie_pixels **out, lie_error *err);
/* Hits inside patch `path` of triangle tri (0 when px is NULL). */
uint64_t lie_pixels_hits(const lie_pixels *px, uint32_t tri, lie_patch_path path);
/* A hash of triangle tri's keys (0: no hit): equal hashes, equal decisions. */
uint64_t lie_pixels_tri_hash(const lie_pixels *px, uint32_t tri);

/* The model's render cost of one shadow ray answered by a node of class
 * cls with n_list blockers, in ns. */
double lie_cost_list_ns(const lie_build_params *p, lie_class cls, size_t n_list);

/* What the model predicts one frame of the views costs in shadow rays:
 * with full visibility and with env (per pixel, light_samples rays shared
 * among the emitters by their light, lie_unit_shares; unlit pairs none,
 * visible and occluded ones nothing with env).
 * Times are CPU ns summed over threads. */
typedef struct lie_prediction {
    double pixels;                        /* pixels the views see */
    double pair_pixels[LIE_CLASS_COUNT];  /* pixel x emitter, by the class of its leaf */
    double full_ns, lie_ns;
    /* the counts those times come from, to calibrate the constants */
    double full_rays;     /* shadow rays with full visibility */
    double list_entries;  /* blocker tests with env: light samples x list length */
    double env_rays;      /* Embree rays with env (complex and unbuilt pairs) */
} lie_prediction;
void lie_env_predict(const lie_env *env, const lie_scene *s, const lie_pixels *px, lie_prediction *pred);

/* The cost model's unit rule (§4.3.3, the "simple cost model" of Table 2)
 * for whole units.  A frame's budget of light_samples per pixel is shared
 * among the emitters in proportion to their light (the default light
 * sampler, lib/shade/sampler.h), so the shadow rays a unit (tri, cluster)
 * can save are its pixels x light_samples x its share: its cluster's
 * unshadowed light at the triangle's centroid (lie_cluster_unshadowed)
 * over every cluster's.  share[c] for each cluster: that share, or -1
 * where the cluster cannot reach the triangle (an unlit unit, which costs
 * nothing to build).  `far`: lie_pair_ray_far. */
void lie_unit_shares(const lie_scene *s, uint32_t tri, float far, double *share);
/* Whether the unit, seen by the views' px, pays for its first round of
 * segments over the frames served: at best it saves every shadow ray its
 * share of the budget casts (lie_unit_shares).  A unit that does not is
 * left unbuilt and the renderer answers it with Embree.  Always 1 without
 * views or with frames 0. */
int lie_unit_pays(const lie_build_params *p, const lie_pixels *px, uint32_t tri, double share);
/* The same rule for a unit whose triangle `pixels` pixels see per frame. */
int lie_unit_pays_pixels(const lie_build_params *p, double pixels, double share);

/* ---- whole builds: pixels estimated from area ----------------------------
 *
 * A build without views cannot count pixels.  It assumes that each of the
 * frames it serves shows p->whole_pixels pixels spread over the scene's
 * surface in proportion to area: triangle t gets whole_pixels x area(t) /
 * lie_whole_area(s) per frame, a patch of it its share by area.  The
 * surface is rounded up to a power of two, so an edit rarely changes it;
 * when it does, rst-update rebuilds every unit (lib/update/mark.c). */
double lie_whole_area(const lie_scene *s);
/* Pixels per frame a whole build with p assumes triangle tri gets (0:
 * no model: frames or whole_pixels is 0).  `area`: lie_whole_area(s). */
double lie_whole_pixels(const lie_scene *s, const lie_build_params *p, double area, uint32_t tri);
/* Whether no unit of triangle tri can pay, whatever its share: then a
 * unit is built only where its emitter cannot reach (unlit), and the
 * shares need not be computed (the same decisions: a share is at most 1). */
int lie_unit_none_pays(const lie_build_params *p, double pixels);

/* Builds for views: as lie_env_build_masked with the triangles px sees (no
 * px: all), and, where px is not NULL, patches only as fine as the cost
 * model finds their pixels need. */
lie_status lie_env_build_views(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                               const lie_pixels *px, lie_progress *progress, lie_env **out,
                               lie_build_stats *stats, lie_error *err);
lie_status lie_env_build_range_views(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                                     const lie_pixels *px, uint64_t first_unit, uint64_t n_units,
                                     lie_env_part *out, lie_build_stats *stats, lie_error *err);
/* The expected cost of building each of units [first_unit, first_unit +
 * n_units) of lie_env_build_range_views's env, in relative terms: the
 * estimate a build's workers take triangles by, costliest first (the
 * leaves a shadow boundary can reach in the unit's patch tree; next to
 * nothing outside the views).  out[i] is unit first_unit + i's.  For
 * sharing units out among processes so that they balance. */
lie_status lie_env_unit_weights(const lie_scene *s, const lie_build_params *p, const lie_pixels *px,
                                uint64_t first_unit, uint64_t n_units, double *out, lie_error *err);
/* What a range of units continues after an edit, as lie_env_update
 * continues an env: old_unit[i] is the unit of env that unit first_unit + i
 * continues (its nodes flagged in node_flags recomputed, the others
 * copied), or -1 to build it afresh.  Only env's root, nodes and pool are
 * read. */
typedef struct lie_units_old {
    const lie_env *env;
    const int32_t *old_unit;
    const uint8_t *node_flags;
} lie_units_old;
/* lie_env_build_range_views, stopped by *stop (may be NULL) as
 * lie_build_control.stop stops a build: units the stop reaches are left
 * LIE_CLASS_NONE and counted in stats->units_interrupted.  With `from`
 * (may be NULL) the units are updated, not built: the part is what
 * lie_env_update_views gives these units, provided the flags hold every
 * node whose shaft an edit touched.  An asynchronous constructor builds a
 * triangle's units at a time with it, and after an edit recomputes the
 * nodes it reached (lib/update, lie_ctor). */
lie_status lie_env_build_units(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                               const lie_pixels *px, uint64_t first_unit, uint64_t n_units,
                               const lie_units_old *from, const volatile sig_atomic_t *stop, lie_env_part *out,
                               lie_build_stats *stats, lie_error *err);
/* An env laid out as a build lays it out (every unit's tree in unit order,
 * nodes depth first as built, lists in node order), from one whose units
 * were put together in any order and may hold unreachable nodes: the same
 * trees, the bytes one build gives.  *out: lie_env_destroy. */
lie_status lie_env_compact(const lie_env *src, lie_env **out, lie_error *err);
/* The same, a unit holding an unbuilt leaf below its root (an update's
 * pending leaves: lib/update, lie_update_snapshot) left unbuilt whole, and
 * then partial set: a cache lie-build --resume finishes. */
lie_status lie_env_compact_units(const lie_env *src, lie_env **out, lie_error *err);
/* Whether the units of triangle tri, built for the views whose pixels are
 * old_px, differ from what a build for new_px (the old views and more)
 * gives: a unit the new pixels make pay, or a leaf whose split they may
 * now make pay (the rule lie_env_add_views refines by). */
int lie_env_tri_stale(const lie_env *env, const lie_scene *s, const lie_pixels *old_px, const lie_pixels *new_px,
                      uint32_t tri);

/* lie_env_update for an env built for views: px are the views' pixels on s
 * (NULL: an env built without views). */
lie_status lie_env_update_views(lie_env *env, const lie_scene *s, const lie_rt *rt, const lie_pixels *px,
                                const int32_t *old_unit, const uint8_t *node_flags, int threads,
                                lie_build_stats *stats, lie_error *err);

/* Add views to an env built for views old_px (a lie_env_build_views
 * result for s): new_px are the pixels of the old views and the new ones
 * together.  Units the old views did not see are built; units whose
 * pixels grew are refined where a patch kept from splitting by too few
 * pixels may now split (only those nodes and their ancestors are
 * recomputed); the others are kept.  An interrupted env (partial) is
 * finished on the way: its unbuilt units that the views see and that pay
 * are built.  The result is exactly lie_env_build_views(s, new_px). */
typedef struct lie_add_stats {
    uint64_t units_kept, units_refined, units_new;
    uint64_t nodes_flagged;   /* old nodes recomputed */
} lie_add_stats;
lie_status lie_env_add_views(lie_env *env, const lie_scene *s, const lie_rt *rt, const lie_pixels *old_px,
                             const lie_pixels *new_px, int threads, lie_build_stats *stats, lie_add_stats *as,
                             lie_error *err);

/* Statistics of an existing env (no build time). */
void lie_env_stats(const lie_env *env, lie_build_stats *stats);

void lie_env_destroy(lie_env *env);

/* The leaf of unit (tri, cluster c) holding local point (b1, b2): the renderer's
 * hot path, a few steps down a quad-tree. */
static inline const lie_pnode *lie_env_find_leaf(const lie_env *env, uint32_t tri, int c, float b1,
                                                 float b2)
{
    const lie_pnode *n = &env->nodes[env->root[(size_t)tri * (size_t)env->n_clusters + (size_t)c]];
    while (n->child)
        n = &env->nodes[n->child + (uint32_t)lie_patch_descend(&b1, &b2)];
    return n;
}

/* The same, also giving the leaf's patch path. */
static inline const lie_pnode *lie_env_find_leaf_path(const lie_env *env, uint32_t tri, int c, float b1,
                                                      float b2, lie_patch_path *path)
{
    const lie_pnode *n = &env->nodes[env->root[(size_t)tri * (size_t)env->n_clusters + (size_t)c]];
    lie_patch_path p = lie_patch_root();
    while (n->child) {
        int d = lie_patch_descend(&b1, &b2);
        p = lie_patch_child(p, d);
        n = &env->nodes[n->child + (uint32_t)d];
    }
    *path = p;
    return n;
}

#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif
