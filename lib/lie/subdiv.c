/* SPDX-License-Identifier: Apache-2.0 */
/* The patch tree of one unit (§4.1.1): classify a patch-emitter pair, split
 * a patch whose list is too long while it is large, and in an update copy
 * what no edit reached (lib/lie/subdiv.h).
 * Size: just past the size CONTRIBUTING.md asks: classification, the split's
 * lookahead and the update's copy share one node walk. */
#include "lie/subdiv.h"
#include "lie/cull.h"
#include "lie/memo.h"
#include "lie/pair.h"
#include "lie/sample.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int push_node(unit_buf *u, worker *w)
{
    /* the total only grows, so it passes the budget in some schedule iff
     * it does in all: the outcome does not depend on the threads */
    if (atomic_fetch_add_explicit(w->nodes_made, 1, memory_order_relaxed) >= w->max_nodes) {
        w->over = w->nomem = 1;
        return -1;
    }
    if (!LIE_GROW(u->nodes, u->cap_nodes, (size_t)u->n_nodes + 1)) {
        w->nomem = 1;
        return -1;
    }
    memset(&u->nodes[u->n_nodes], 0, sizeof *u->nodes);
    return (int)u->n_nodes++;
}

static int push_list(unit_buf *u, worker *w, const uint32_t *list, uint32_t n)
{
    if (!LIE_GROW(u->pool, u->cap_pool, (size_t)u->n_pool + n)) {
        w->nomem = 1;
        return 0;
    }
    memcpy(u->pool + u->n_pool, list, sizeof *list * n);
    u->n_pool += n;
    return 1;
}

/* A patch large enough to split (§4.1.1): the one size test of
 * lie_subdiv_splits() and of lie_sample_pair's early stop, which must agree. */
int lie_subdiv_may_split(const build_ctx *c, uint32_t tri, lie_patch_path path)
{
    float area = c->s->tri_area[tri] / (float)(1u << (2 * (path.depth < 15 ? path.depth : 15)));
    return area > c->min_area && path.depth < LIE_PATCH_MAX_DEPTH;
}

/* §4.1.1: a patch whose list is too long is split while it is large.  But
 * a closed, double-sided emitter hides its far side behind its near side:
 * those blockers are the emitter's own triangles, and smaller patches keep
 * seeing about as many; when they alone pass the complex cap, splitting
 * cannot help and the pair is complex at once. */
int lie_subdiv_splits(const build_ctx *c, uint32_t tri, lie_patch_path path, int e, lie_class cls,
                      const uint32_t *list, size_t n_list)
{
    const lie_scene *s = c->s;
    if (!(cls == LIE_CLASS_PARTIAL && n_list > c->p->max_blockers && lie_subdiv_may_split(c, tri, path)))
        return 0;
    const lie_emitter *em = &s->emitters[s->clusters[e].emitter];
    size_t own = 0;
    for (size_t k = 0; k < n_list; k++)
        own += lie_emitter_owns(em, list[k]);
    return own <= c->p->complex_cap;
}

static void copy_node(const lie_env *old, uint32_t from, worker *w, unit_buf *u, uint32_t idx);

int lie_subdiv_seen(const build_ctx *c, uint32_t tri)
{
    if (c->tri_mask && !c->tri_mask[tri])
        return 0;
    return !c->pix || c->pix->first[tri + 1] > c->pix->first[tri];
}

/* The share of a node's list cost a kept split removes, measured: with 0.5
 * `lie-build --view Camera --stats=json` (model) gave the kept splits'
 * saving as 0.43 of the list on museum1 and 0.21 on museum3, 0.24 pooled
 * over both (weighted by the saving).  Per-node predictions lost to it:
 * from the shaft's width (patch against emitter diameters) it was 1.3 and
 * 2.9 times too high, and applying the share to the list's length (so a
 * list past complex_cap saves nothing until it falls under) stopped the
 * splits of complex patches that paid most: museum3's frame 1.6 times
 * slower. */
#define LIE_SPLIT_SHORTENING 0.24

/* The model's saving per frame of splitting a node of class cls with this
 * list, before its children are known: LIE_SPLIT_SHORTENING of the list's
 * cost (bench/build.sh prints what splits really gave), on every pixel and
 * light sample of the patch. */
static double predicted_saving_ns(const build_ctx *c, double pixels, lie_class cls, size_t n_list)
{
    return LIE_SPLIT_SHORTENING * pixels * (double)c->p->light_samples * lie_cost_list_ns(c->p, cls, n_list);
}

/* §4.3.3 with the cost model: a patch is worth splitting only if the
 * render time the split can save over the frames the cache serves beats
 * what finding out costs: four children sampled with about as many
 * segments as the node took.  Pixels grow with views, never shrink, so a
 * node this lets split still splits when a view is added (lie-build
 * --into relies on it, tools/lie-build). */
int lie_subdiv_modelled(const build_ctx *c) { return c->pix || c->whole_area > 0.0; }

double lie_subdiv_pixels(const build_ctx *c, uint32_t tri, lie_patch_path path)
{
    if (c->pix)
        return (double)lie_pixels_hits(c->pix, tri, path) / (double)c->pix->rays_per_pixel;
    if (c->whole_area > 0.0) /* a patch of depth d holds 4^-d of its triangle's area */
        return ldexp(lie_whole_pixels(c->s, c->p, c->whole_area, tri), -2 * path.depth);
    return 0.0;
}

int lie_subdiv_pixels_pay(const build_ctx *c, uint32_t tri, lie_patch_path path, lie_class cls, size_t n_list,
                      uint32_t quality)
{
    if (c->p->frames == 0)
        return 1; /* --frames 0: the views choose units, not patches */
    double pixels = lie_subdiv_pixels(c, tri, path);
    double segs = (double)(quality > c->p->samples ? quality : c->p->samples);
    return (double)c->p->frames * predicted_saving_ns(c, pixels, cls, n_list) > 4.0 * segs * (double)c->p->ns_segment;
}

/* A node's classification, before it becomes a leaf or splits. */
typedef struct node_class {
    lie_class cls;
    uint32_t quality;
    size_t n_list;
    uint32_t *list; /* lookahead only: an owned copy of the list (NULL when empty) */
} node_class;

/* Classify the pair of patch `path` of unit (tri, e); the list is left in
 * w->hits[0..n_list).  `old` is the old env's node in an update (its memo
 * entry, computed in parallel), or -1. */
static void classify(const build_ctx *c, worker *w, uint32_t tri, lie_patch_path path, int e, int two_sided,
                     const uint32_t *parent, size_t n_parent, int64_t old, node_class *nc)
{
    const lie_scene *s = c->s;
    lie_vec3 V[3];
    lie_patch_world(path, &s->tri_p[3 * (size_t)tri], V);
    nc->quality = 0;
    nc->n_list = 0;
    nc->list = NULL;
    int32_t mi = old >= 0 && c->memo_of ? c->memo_of[old] : lie_memo_find_new(c, tri, path, e);
    if (mi >= 0) {
        /* computed already, in parallel with the other flagged nodes */
        const memo_entry *m = &c->memo[mi];
        nc->cls = m->cls;
        nc->quality = m->quality;
        nc->n_list = m->n_list;
        if (!LIE_GROW(w->hits, w->cap_hits, nc->n_list)) {
            w->nomem = 1;
            return;
        }
        if (nc->n_list)
            memcpy(w->hits, m->list, nc->n_list * sizeof *w->hits);
    } else if (lie_pair_unlit(c->s, tri, V, two_sided, e)) {
        nc->cls = LIE_CLASS_UNLIT;
    } else if (c->p->mode == LIE_BLOCKERS_SAMPLED) {
        nc->cls = lie_sample_pair(c, w, tri, path, V, two_sided, e, &nc->quality, &nc->n_list);
    } else {
        nc->cls = lie_cull_conservative(c, w, tri, V, two_sided, e, parent, n_parent, SIZE_MAX, &nc->n_list);
    }
}

/* What a node costs the renderer per light sample, in blocker tests: none
 * for unlit, visible and occluded pairs, its list's length otherwise (past
 * complex_cap the pair is complex: an Embree ray, costlier than any list
 * once visibility is exact, lib/shade/polylight.h). */
static double render_weight(lie_class cls, size_t n_list)
{
    return cls == LIE_CLASS_PARTIAL || cls == LIE_CLASS_SPLIT || cls == LIE_CLASS_COMPLEX ? (double)n_list : 0.0;
}

/* Whether an old node an update copies still tells its sampled list's
 * length, which the lookahead weighs: a split node does (count), and so
 * do unlit and occluded leaves (proven, as sampled).  Any other sampled
 * leaf holds its exact list instead (complete_leaf), and with conservative
 * lists a leaf large enough to split may hold a list its split did not
 * shorten: those are classified again. */
static int old_weight_known(const build_ctx *c, uint32_t tri, lie_patch_path path, const lie_pnode *x)
{
    if (x->child || x->cls == LIE_CLASS_UNLIT || x->cls == LIE_CLASS_OCCLUDED)
        return 1;
    return c->p->mode != LIE_BLOCKERS_SAMPLED && !lie_subdiv_may_split(c, tri, path);
}

/* The exact list of a leaf: every triangle entering the pair's shaft
 * (§4.1.2; lie_cull_exact), counted up to `cap` (more: the count only);
 * left in w->hits. */
static size_t exact_leaf_list(const build_ctx *c, worker *w, uint32_t tri, lie_patch_path path, int e, int two_sided,
                              size_t cap)
{
    lie_vec3 V[3];
    lie_patch_world(path, &c->s->tri_p[3 * (size_t)tri], V);
    return lie_cull_exact(c, w, tri, V, two_sided, e, cap);
}

/* The same for an old node an update copies (its class and count are
 * what a build would give: no edit reached it). */
static double old_weight(const lie_pnode *x)
{
    return render_weight((lie_class)x->cls, x->count);
}

/* A sampled leaf, made right (§4.1.2 completing §4.1): sampling shapes
 * the tree, but what a leaf tells the renderer must hold for every
 * segment, and segments sampled say less than that.
 * - Partial: the list holds what the segments hit (and the rest of those
 *   instances in the shaft); it misses thin parts and small triangles
 *   between them, and a cluster of a shared sampling (lib/lie/sample.c)
 *   saw only its share of the segments.
 * - Visible with a list: nothing was hit in a shaft the list's triangles
 *   enter (lie_sample_pair); only an empty shaft proves visibility.
 * - Occluded: every segment was blocked, but the gaps between them may
 *   let light through; kept if the blockers prove it
 *   (lie_cull_occlusion_proven).
 * Otherwise the leaf gets the exact list of its hull: empty is visible,
 * past complex_cap complex (the renderer asks the whole scene).  Returns
 * the list's length, left in w->hits; *cls is updated. */
static size_t complete_leaf(const build_ctx *c, worker *w, uint32_t tri, lie_patch_path path, int e, int two_sided,
                            lie_class *cls, size_t n_list)
{
    if (*cls == LIE_CLASS_OCCLUDED) {
        lie_vec3 V[3];
        lie_patch_world(path, &c->s->tri_p[3 * (size_t)tri], V);
        if (lie_cull_occlusion_proven(c, w, tri, V, two_sided, e, w->hits, n_list))
            return n_list;
        w->st.unproven_occluded++;
    } else if (*cls == LIE_CLASS_VISIBLE && n_list > 0) {
        w->st.unproven_visible++;
    } else if (!(*cls == LIE_CLASS_PARTIAL && n_list <= c->p->complex_cap)) {
        return n_list;
    }
    size_t n = exact_leaf_list(c, w, tri, path, e, two_sided, c->p->complex_cap);
    *cls = n == 0 ? LIE_CLASS_VISIBLE : n > c->p->complex_cap ? LIE_CLASS_COMPLEX : LIE_CLASS_PARTIAL;
    return n;
}


/* The exact lengths of the node's and its children's lists, the triangles
 * meeting each hull (§4.1.2), counted up to 8 complex_cap: a sampled list
 * past the cap stops growing (lie_sample_pair settles it), so only these
 * can tell a shaft whose lists shrink over several levels (a floor under
 * many columns) from one whose lists never do (a patch outside a lamp's
 * shade).  The split is kept if they shrink by split_gain on average. */
static int exact_split_pays(const build_ctx *c, worker *w, uint32_t tri, lie_patch_path path, int e, int two_sided)
{
    const lie_scene *s = c->s;
    size_t limit = 8 * (size_t)c->p->complex_cap + 8, cnt[5];
    for (int k = 0; k < 5; k++) {
        lie_patch_path q = k == 0 ? path : lie_patch_child(path, k - 1);
        lie_vec3 V[3];
        lie_patch_world(q, &s->tri_p[3 * (size_t)tri], V);
        lie_cull_conservative(c, w, tri, V, two_sided, e, NULL, 0, limit, &cnt[k]);
        if (w->nomem)
            return 0;
        cnt[k] = cnt[k] < limit ? cnt[k] : limit;
    }
    double mean = 0.25 * (double)(cnt[1] + cnt[2] + cnt[3] + cnt[4]);
    return mean <= (1.0 - (double)c->p->split_gain) * (double)cnt[0];
}

/* §4.1.1 with a cost test: a split is kept only if it pays.
 * - A node short enough for a list splits if its children's lists are on
 *   average shorter than its own by the share split_gain (0: every split
 *   is kept, as the paper does).  Where smaller patches keep seeing about
 *   the same blockers (a shrinking patch tends to a point, whose list is
 *   not empty), a deeper tree costs build time and cache space and saves
 *   the renderer nothing.
 * - A node too long for a list (complex as a leaf) splits if a child gets
 *   a list: part of its area leaves Embree.  If every child is too long as
 *   well, a patch larger than 1% of the largest triangle splits anyway
 *   (lists may take several levels to fall under the cap), and a smaller
 *   one splits if the exact counts shrink (exact_split_pays).
 * The decision uses only the node and its four children, all inside the
 * node's own shaft, so an update that copies an untouched node copies the
 * same decision. */
#define LIE_COMPLEX_KEEP_SPLITTING 1e-2f
static int split_pays(const build_ctx *c, worker *w, uint32_t tri, lie_patch_path path, int e, int two_sided,
                      lie_class cls, size_t n_list, const double child_w[4])
{
    if (c->p->split_gain <= 0.0f)
        return 1;
    double cap = (double)c->p->complex_cap, parent = render_weight(cls, n_list);
    int all_long = 1;
    for (int k = 0; k < 4; k++)
        all_long &= child_w[k] > cap;
    if (parent > cap && !all_long)
        return 1;
    /* A complex patch costs an Embree ray per light sample on every pixel
     * it covers: a large one keeps splitting, as the paper's rule does,
     * whatever one level shows (LIE_COMPLEX_KEEP_SPLITTING of the largest
     * triangle; a relative size, so updates keep it, lib/update). */
    float area = c->s->tri_area[tri] / (float)(1u << (2 * (path.depth < 15 ? path.depth : 15)));
    if (parent > cap && area > LIE_COMPLEX_KEEP_SPLITTING * c->s->max_tri_area)
        return 1;
    if (parent > cap && c->p->mode == LIE_BLOCKERS_SAMPLED)
        return exact_split_pays(c, w, tri, path, e, two_sided);
    double mean = 0.25 * (child_w[0] + child_w[1] + child_w[2] + child_w[3]);
    return mean <= (1.0 - (double)c->p->split_gain) * parent;
}

/* §4.1.1 ahead of the tree: whether unit (tri, e) will be complex.  Its
 * smallest patches (the first at each corner and at the centre that
 * lie_subdiv_may_split stops) are the smallest leaves the tree can have
 * there, and a leaf's shaft holds theirs: if each of them sees more than
 * complex_cap triangles (lie_cull_exact), the leaves at those four points
 * are complex however the tree grows, and where an emitter is large
 * beside the patch (a corridor's light strips) the rest are too.  A unit
 * named so is one complex leaf: Embree answers it as it would answer its
 * leaves, so the image is the same wherever the prediction errs; only the
 * lists it would have had are lost (lie-build --stats shows both counts).
 * The probes lie inside the root's shaft, so the ray segment trees flag
 * the unit whenever an edit could change the prediction (update ≡
 * rebuild).  w->hits is kept.  Only a triangle larger than
 * LIE_COMPLEX_KEEP_SPLITTING of the largest is probed: a smaller complex
 * root is settled at its first level (split_pays weighs its children's
 * exact lists), so its probes would cost as much as they save (on
 * scifi_hallway, probing every splitting root made the view build 2.6
 * times slower). */
static int predict_complex(const build_ctx *c, worker *w, uint32_t tri, int e, int two_sided, size_t n_list)
{
    static const int corner[4] = {3, 0, 1, 2}; /* the centre first: a corner is likelier to differ */
    uint32_t *keep = malloc(sizeof *keep * (n_list + 1));
    if (!keep) {
        w->nomem = 1;
        return 0;
    }
    memcpy(keep, w->hits, sizeof *keep * n_list);
    size_t n_hits = w->n_hits;
    int complex = 1;
    for (int k = 0; k < 4 && complex; k++) {
        lie_patch_path p = lie_patch_root();
        while (lie_subdiv_may_split(c, tri, p))
            p = lie_patch_child(p, corner[k]);
        lie_vec3 V[3];
        lie_patch_world(p, &c->s->tri_p[3 * (size_t)tri], V);
        complex = lie_cull_exact(c, w, tri, V, two_sided, e, c->p->complex_cap) > c->p->complex_cap && !w->nomem;
    }
    memcpy(w->hits, keep, sizeof *keep * n_list);
    w->n_hits = n_hits;
    free(keep);
    return complex;
}

/* Whether every leaf below node idx of u is complex. */
static int all_complex(const unit_buf *u, uint32_t idx)
{
    const lie_pnode *x = &u->nodes[idx];
    if (!x->child)
        return x->cls == LIE_CLASS_COMPLEX;
    for (uint32_t k = 0; k < 4; k++)
        if (!all_complex(u, x->child + k))
            return 0;
    return 1;
}

/* Build node `idx` for patch `path` of unit (tri, e).  In an update, `old`
 * is the old env's node for the same patch (or -1): when both old and new
 * split, children whose regions no edit touched are copied.  `pre`, when
 * not NULL, is the node's classification, already made by its parent's
 * lookahead.  One piece: the classification, the lookahead that decides
 * the split and the copy of untouched children share the node's list, its
 * old twin and its children's classifications, in an order the cache's
 * bytes depend on. */
static void build_node(const build_ctx *c, worker *w, unit_buf *u, uint32_t idx, uint32_t tri,
                       lie_patch_path path, int e, int two_sided, const uint32_t *parent,
                       size_t n_parent, int64_t old, const node_class *pre)
{
    if (old >= 0 && !(c->node_flags && c->node_flags[old])) {
        copy_node(c->old, (uint32_t)old, w, u, idx); /* no edit reached this patch's shaft */
        return;
    }
    if (c->stop && *c->stop) {
        w->stopped = 1; /* interrupted: lie_subdiv_triangle drops the unit */
        return;
    }
    const lie_scene *s = c->s;
    node_class nc;
    if (pre) {
        nc = *pre;
        if (!LIE_GROW(w->hits, w->cap_hits, nc.n_list)) {
            w->nomem = 1;
            return;
        }
        if (nc.n_list)
            memcpy(w->hits, nc.list, nc.n_list * sizeof *w->hits);
        nc.list = NULL;
    } else {
        classify(c, w, tri, path, e, two_sided, parent, n_parent, old, &nc);
    }
    if (w->nomem)
        return;
    w->st.patches_per_depth[path.depth]++;
    size_t n_list = nc.n_list;
    int exact_done = 0; /* w->hits holds the leaf's exact list */
    int splits = lie_subdiv_splits(c, tri, path, e, nc.cls, w->hits, n_list);
    if (splits && path.depth == 0 && (c->p->complex_predict || c->audit_complex) &&
        c->s->tri_area[tri] > LIE_COMPLEX_KEEP_SPLITTING * c->s->max_tri_area) {
        w->root_predicted = predict_complex(c, w, tri, e, two_sided, n_list);
        if (w->nomem)
            return;
        if (w->root_predicted && c->p->complex_predict) {
            splits = 0; /* one complex leaf: its shadow rays go to Embree */
            nc.cls = LIE_CLASS_COMPLEX;
        }
    }
    if (splits && lie_subdiv_modelled(c) && !lie_subdiv_pixels_pay(c, tri, path, nc.cls, n_list, nc.quality)) {
        /* too few pixels see the patch for a split to pay: a leaf, with the
         * exact list (a sampled one may miss small blockers of a large
         * patch) where a list is cheaper than an Embree ray */
        splits = 0;
        w->st.splits_pixels++;
        size_t cap = (size_t)((double)c->p->ns_ray / (double)c->p->ns_blocker);
        if (cap > c->p->complex_cap)
            cap = c->p->complex_cap;
        if (n_list > cap) {
            nc.cls = LIE_CLASS_COMPLEX;
        } else if (c->p->mode == LIE_BLOCKERS_SAMPLED) {
            n_list = exact_leaf_list(c, w, tri, path, e, two_sided, cap);
            exact_done = 1;
            if (w->nomem)
                return;
            /* the exact list holds the sampled one, longer than
             * max_blockers; were it ever shorter, the leaf goes to Embree,
             * so that every leaf this rule made is complex or a list
             * longer than max_blockers (lie_env_add_views finds them so) */
            if (n_list > cap || n_list <= c->p->max_blockers)
                nc.cls = LIE_CLASS_COMPLEX;
        }
    }
    if (splits) {
        /* §4.1.1: a patch whose list is too long splits while it is large,
         * if the split pays (split_pays): classify the four children first */
        uint32_t *keep = malloc(sizeof *keep * (n_list ? n_list : 1));
        node_class kid[4];
        double kid_w[4], kid_ns[4];
        int n_kid = 0;
        uint32_t old_child = old >= 0 ? c->old->nodes[old].child : 0;
        if (!keep) {
            w->nomem = 1;
            return;
        }
        memcpy(keep, w->hits, sizeof *keep * n_list);
        for (; n_kid < 4; n_kid++) {
            int64_t ok = old_child ? (int64_t)old_child + n_kid : -1;
            kid[n_kid].list = NULL;
            kid[n_kid].n_list = 0;
            if (ok >= 0 && !(c->node_flags && c->node_flags[ok]) &&
                old_weight_known(c, tri, lie_patch_child(path, n_kid), &c->old->nodes[ok])) {
                kid_w[n_kid] = old_weight(&c->old->nodes[ok]);
                kid_ns[n_kid] = lie_cost_list_ns(c->p, (lie_class)c->old->nodes[ok].cls, c->old->nodes[ok].count);
                continue;
            }
            classify(c, w, tri, lie_patch_child(path, n_kid), e, two_sided, keep, n_list, ok, &kid[n_kid]);
            if (w->nomem)
                break;
            kid_w[n_kid] = render_weight(kid[n_kid].cls, kid[n_kid].n_list);
            kid_ns[n_kid] = lie_cost_list_ns(c->p, kid[n_kid].cls, kid[n_kid].n_list);
            if (kid[n_kid].n_list) {
                kid[n_kid].list = malloc(sizeof *kid[n_kid].list * kid[n_kid].n_list);
                if (!kid[n_kid].list) {
                    w->nomem = 1;
                    break;
                }
                memcpy(kid[n_kid].list, w->hits, sizeof *kid[n_kid].list * kid[n_kid].n_list);
            }
        }
        int pays = !w->nomem && split_pays(c, w, tri, path, e, two_sided, nc.cls, n_list, kid_w);
        /* A leaf instead, if the split does not pay.  A list sampled over a
         * patch this large may miss small blockers that the deeper tree
         * would have found, so such a leaf gets its exact list: every
         * triangle meeting the pair's hull (§4.1.2), less a planar
         * emitter's own triangles, which end every segment.  If that list
         * is past the cap the leaf would be complex, dearer than any split:
         * the node splits after all.  In conservative mode the list is
         * exact already. */
        size_t n_leaf = n_list;
        if (!pays && !w->nomem && c->p->mode == LIE_BLOCKERS_SAMPLED && n_list <= c->p->complex_cap) {
            n_leaf = exact_leaf_list(c, w, tri, path, e, two_sided, c->p->complex_cap);
            pays = n_leaf > c->p->complex_cap;
        }
        if (pays && !w->nomem) {
            w->st.splits_kept++;
            if (lie_subdiv_modelled(c)) {
                double pixels = lie_subdiv_pixels(c, tri, path);
                double before = lie_cost_list_ns(c->p, nc.cls, n_list), after = 0.0;
                for (int k = 0; k < 4; k++)
                    after += 0.25 * kid_ns[k];
                w->st.split_saving_predicted_ns += predicted_saving_ns(c, pixels, nc.cls, n_list);
                w->st.split_saving_measured_ns += pixels * (double)c->p->light_samples * (before - after);
            }
        }
        int first = -1;
        if (pays && !w->nomem) {
            first = push_node(u, w);
            for (int k = 1; k < 4 && first >= 0; k++)
                if (push_node(u, w) < 0)
                    first = -1;
        }
        if (pays && first >= 0) {
            u->nodes[idx].child = (uint32_t)first; /* unit-local; rebased on assembly */
            u->nodes[idx].cls = LIE_CLASS_SPLIT;
            u->nodes[idx].quality = nc.quality;
            u->nodes[idx].count = (uint32_t)n_list;
            for (int k = 0; k < 4; k++) {
                int64_t ok = old_child ? (int64_t)old_child + k : -1;
                int copied = ok >= 0 && !(c->node_flags && c->node_flags[ok]);
                build_node(c, w, u, (uint32_t)first + (uint32_t)k, tri, lie_patch_child(path, k), e, two_sided,
                           keep, n_list, ok, copied ? NULL : &kid[k]);
            }
        }
        for (int k = 0; k < n_kid && k < 4; k++)
            free(kid[k].list);
        if (w->nomem || pays) {
            free(keep);
            return;
        }
        if (c->p->mode == LIE_BLOCKERS_SAMPLED && n_list <= c->p->complex_cap) {
            n_list = n_leaf; /* the exact list, in w->hits */
            exact_done = 1;
            if (!n_list)
                nc.cls = LIE_CLASS_VISIBLE;
        } else {
            if (!LIE_GROW(w->hits, w->cap_hits, n_list)) {
                free(keep);
                w->nomem = 1;
                return;
            }
            memcpy(w->hits, keep, sizeof *keep * n_list);
        }
        free(keep);
        if (w->nomem)
            return;
        w->st.splits_undone++;
    }
    if (exact_done == 0 && c->p->mode == LIE_BLOCKERS_SAMPLED) {
        n_list = complete_leaf(c, w, tri, path, e, two_sided, &nc.cls, n_list);
        if (w->nomem)
            return;
    }
    lie_pnode *nd = &u->nodes[idx];
    nd->quality = nc.quality;
    nd->count = (uint32_t)n_list;
    lie_class cls = nc.cls;
    /* A list with an alpha-masked triangle goes to Embree as well: the
     * renderer's segment test knows nothing of holes. */
    int masked = 0;
    for (size_t k = 0; cls == LIE_CLASS_PARTIAL && k < n_list && !masked; k++)
        masked = lie_scene_material(s, s->tri_material[w->hits[k]])->alpha_mask;
    int complex = cls == LIE_CLASS_PARTIAL && (n_list > c->p->complex_cap || masked);
    w->st.pairs[complex ? LIE_CLASS_COMPLEX : cls]++;
    if (complex) {
        nd->cls = LIE_CLASS_COMPLEX; /* the renderer asks the whole scene */
        return;
    }
    nd->cls = cls;
    if (cls == LIE_CLASS_PARTIAL) {
        nd->list = u->n_pool;
        push_list(u, w, w->hits, (uint32_t)n_list);
        w->st.blocker_total += n_list;
        lie_stats_hist_add(&w->st, (uint32_t)n_list);
    }
}

/* Copy node `from` of the old env (and its subtree) into node `idx` of u,
 * in the order a build would have produced it. */
static void copy_node(const lie_env *old, uint32_t from, worker *w, unit_buf *u, uint32_t idx)
{
    lie_pnode x = old->nodes[from];
    if (x.child) {
        int first = push_node(u, w);
        for (int k = 1; k < 4 && first >= 0; k++)
            if (push_node(u, w) < 0)
                first = -1;
        if (first < 0)
            return;
        u->nodes[idx] = x;
        u->nodes[idx].child = (uint32_t)first;
        for (int k = 0; k < 4; k++)
            copy_node(old, x.child + (uint32_t)k, w, u, (uint32_t)first + (uint32_t)k);
        return;
    }
    if (x.cls == LIE_CLASS_PARTIAL) {
        uint32_t list = u->n_pool;
        if (!push_list(u, w, old->pool + x.list, x.count))
            return;
        x.list = list;
    }
    u->nodes[idx] = x;
}

/* The nodes and pool entries of old node `from` and its subtree. */
void lie_subtree_size(const lie_env *old, uint32_t from, uint32_t *n_nodes, uint32_t *n_pool)
{
    const lie_pnode *x = &old->nodes[from];
    ++*n_nodes;
    if (x->child)
        for (uint32_t k = 0; k < 4; k++)
            lie_subtree_size(old, x->child + k, n_nodes, n_pool);
    else if (x->cls == LIE_CLASS_PARTIAL)
        *n_pool += x->count;
}

void lie_unit_size(const lie_env *env, uint32_t root, uint32_t *n_nodes, uint32_t *n_pool)
{
    if (!lie_pnode_lone(&env->nodes[root]))
        lie_subtree_size(env, root, n_nodes, n_pool);
}

/* The shares of triangle tri's units (lie_unit_shares) in the worker's
 * scratch, once per triangle; NULL on no memory. */
static const double *unit_shares(const build_ctx *c, worker *w, uint32_t tri)
{
    size_t ne = (size_t)c->s->n_clusters;
    if (!LIE_GROW(w->share, w->cap_share, ne + 1)) {
        w->nomem = 1;
        return NULL;
    }
    lie_unit_shares(c->s, tri, c->ray_far, w->share);
    return w->share;
}

/* How the cost model decides the units of the triangle at hand: their
 * shares (NULL: no model), or, where not even a unit with all of the
 * light could pay (lie_unit_none_pays), none_pays and no shares. */
typedef struct unit_model {
    const double *share;
    double pixels; /* per frame, the triangle's (lie_subdiv_pixels) */
    int none_pays;
} unit_model;

/* Whether the cost model leaves unit (tri, e) to Embree, counted by
 * reason: outside the views, or too little of the budget's light samples
 * to pay for its build (lie_unit_pays_pixels).  A unit its emitter cannot
 * reach is unlit and always built (it costs nothing). */
static int left_to_embree(const build_ctx *c, worker *w, uint32_t tri, int two_sided, const unit_model *m, int e)
{
    if (!lie_subdiv_seen(c, tri)) {
        w->st.units_unseen += c->pix != NULL;
        return 1;
    }
    int unpaid = 0;
    if (m->none_pays)
        unpaid = lie_cluster_can_reach(c->s, e, tri, &c->s->tri_p[3 * (size_t)tri], c->s->tri_ng[tri], two_sided);
    else if (m->share)
        unpaid = !lie_unit_pays_pixels(c->p, m->pixels, m->share[e]);
    w->st.units_unpaid += (uint64_t)unpaid;
    return unpaid;
}

/* An update's triangle whose every unit continues an old one that no edit
 * reached: it is copied at assembly, straight into the new arrays.  (The
 * cost model's decisions hold for it: lib/update/mark.c rebuilds a unit
 * whose decision an edit of the light changed.) */
static int copied_whole(const build_ctx *c, uint32_t tri, unit_buf *u)
{
    size_t ne = (size_t)c->s->n_clusters;
    uint64_t first = (uint64_t)tri * ne;
    /* (a range of some of its units is built unit by unit) */
    if (!c->old_unit || c->tri_mask || first < c->unit_lo || first + ne > c->unit_hi)
        return 0;
    for (size_t e = 0; e < ne; e++) {
        int32_t ou = lie_ctx_old_unit(c, first + e);
        if (ou < 0 || (c->node_flags && c->node_flags[c->old->root[ou]]))
            return 0;
    }
    for (size_t e = 0; e < ne; e++)
        lie_unit_size(c->old, c->old->root[lie_ctx_old_unit(c, first + e)], &u->n_nodes, &u->n_pool);
    u->copied = 1;
    return 1;
}

/* The prediction of a unit just built against what it came out as
 * (lie_build_stats.complex_predicted ...): with complex_predict, a unit
 * not named that is complex throughout is one the prediction missed. */
static void count_complex(const build_ctx *c, worker *w, const unit_buf *u, uint32_t root)
{
    if (!c->p->complex_predict && !c->audit_complex)
        return;
    int all = all_complex(u, root);
    w->st.complex_predicted += (uint64_t)w->root_predicted;
    if (c->p->complex_predict)
        w->st.complex_measured += (uint64_t)(all && !w->root_predicted);
    else
        w->st.complex_measured += (uint64_t)all;
    w->st.complex_predicted_measured += (uint64_t)(all && w->root_predicted && !c->p->complex_predict);
}

/* lie_build_stats.frame_saving_ns of the subtree of u's node idx, whose
 * patch `pixels` pixels see, each casting `rays` shadow rays to the unit's
 * cluster. */
static double leaf_saving(const build_ctx *c, const unit_buf *u, uint32_t idx, double pixels, double rays)
{
    const lie_pnode *x = &u->nodes[idx];
    if (x->child) {
        double sum = 0.0;
        for (uint32_t k = 0; k < 4; k++)
            sum += leaf_saving(c, u, x->child + k, 0.25 * pixels, rays);
        return sum;
    }
    if (x->cls == LIE_CLASS_UNLIT)
        return 0.0; /* no ray either way */
    return pixels * rays * ((double)c->p->ns_ray - lie_cost_list_ns(c->p, (lie_class)x->cls, x->count));
}

/* A whole build's prediction for the unit just built into `root`. */
static void predict_unit(const build_ctx *c, worker *w, const unit_buf *u, uint32_t root, const unit_model *m,
                         size_t e)
{
    if (c->whole_area > 0.0 && m->share && m->share[e] > 0.0 && !w->nomem)
        w->st.frame_saving_ns +=
            leaf_saving(c, u, root, m->pixels, (double)c->p->light_samples * m->share[e]);
}

/* A unit built into node `root` that came out one lone leaf gives its
 * node back: it takes the env's shared leaf (lie_pnode_lone). */
static void share_lone(unit_buf *u, worker *w, uint32_t root, size_t e)
{
    if (u->n_nodes != root + 1 || !lie_pnode_lone(&u->nodes[root]))
        return;
    u->roots[e] = u->nodes[root].cls == LIE_CLASS_UNLIT ? LIE_ROOT_LONE_UNLIT : LIE_ROOT_LONE_NONE;
    u->n_nodes = root;
    atomic_fetch_sub_explicit(w->nodes_made, 1, memory_order_relaxed);
}

void lie_subdiv_triangle(void *ctx, size_t item, int worker_id)
{
    build_ctx *c = ctx;
    worker *w = &c->workers[worker_id];
    uint32_t tri = c->tri_lo + (uint32_t)item;
    unit_buf *u = &c->out[item];
    const lie_scene *s = c->s;
    size_t ne = (size_t)s->n_clusters;
    if (copied_whole(c, tri, u)) {
        w->st.units_copied += ne;
        return;
    }
    u->roots = malloc(sizeof *u->roots * (ne + 1));
    if (!u->roots) {
        w->nomem = 1;
        return;
    }
    int two_sided = lie_pair_two_sided(s, tri);
    /* the model's shares, where it decides (views or a whole build's
     * estimate, and frames) */
    unit_model m = {NULL, 0.0, 0};
    if (lie_subdiv_modelled(c) && c->p->frames && lie_subdiv_seen(c, tri)) {
        m.pixels = lie_subdiv_pixels(c, tri, lie_patch_root());
        m.none_pays = lie_unit_none_pays(c->p, m.pixels);
        if (!m.none_pays && !(m.share = unit_shares(c, w, tri)))
            return;
    }
    for (size_t e = 0; e < ne; e++) {
        size_t unit = (size_t)tri * ne + e;
        if (unit < c->unit_lo || unit >= c->unit_hi)
            continue; /* lie_env_build_range: another part's */
        int32_t ou = lie_ctx_old_unit(c, unit);
        int64_t old = ou >= 0 ? (int64_t)c->old->root[ou] : -1;
        if (left_to_embree(c, w, tri, two_sided, &m, (int)e)) {
            u->roots[e] = LIE_ROOT_LONE_NONE; /* outside the views, or cannot pay: not built */
            w->st.pairs[LIE_CLASS_NONE]++;
            continue;
        }
        int root = push_node(u, w);
        if (root < 0)
            return;
        u->roots[e] = (uint32_t)root;
        int copy = old >= 0 && !(c->node_flags && c->node_flags[old]);
        w->st.units_copied += (uint64_t)copy;
        w->root_predicted = 0;
        if (!c->stop || copy) {
            build_node(c, w, u, (uint32_t)root, tri, lie_patch_root(), (int)e, two_sided, NULL, 0, old, NULL);
            if (!copy && !w->nomem) {
                count_complex(c, w, u, (uint32_t)root);
                predict_unit(c, w, u, (uint32_t)root, &m, e);
            }
            share_lone(u, w, (uint32_t)root, e);
            continue;
        }
        /* A build that may be interrupted: a unit the stop reaches is
         * dropped whole (nodes, lists, statistics), so what the partial env
         * holds are complete units, each exactly as an uninterrupted build
         * makes it. */
        lie_build_stats saved = w->st;
        uint32_t n_pool0 = u->n_pool;
        w->stopped = 0;
        build_node(c, w, u, (uint32_t)root, tri, lie_patch_root(), (int)e, two_sided, NULL, 0, old, NULL);
        if (!w->stopped || w->nomem) {
            if (!w->nomem) {
                count_complex(c, w, u, (uint32_t)root);
                predict_unit(c, w, u, (uint32_t)root, &m, e);
            }
            share_lone(u, w, (uint32_t)root, e);
            continue;
        }
        w->stopped = 0;
        atomic_fetch_sub_explicit(w->nodes_made, u->n_nodes - (uint32_t)root, memory_order_relaxed);
        w->st = saved;
        u->n_nodes = (uint32_t)root;
        u->n_pool = n_pool0;
        u->roots[e] = LIE_ROOT_LONE_NONE;
        w->st.pairs[LIE_CLASS_NONE]++;
        w->st.units_interrupted++;
    }
}
