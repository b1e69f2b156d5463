/* SPDX-License-Identifier: Apache-2.0 */
/* Sampled blocker lists (§4.1, §4.3.2): shadow segments between a patch
 * and an emitter, in adaptive rounds (lib/lie/sample.h). */
#include "lie/sample.h"
#include "lie/cull.h"
#include "lie/subdiv.h"

#include <stdlib.h>
#include <string.h>

static double radical_inverse(uint32_t base, uint32_t i)
{
    double inv = 1.0 / base, f = inv, r = 0.0;
    while (i) {
        r += (double)(i % base) * f;
        i /= base;
        f *= inv;
    }
    return r;
}

/* Sample i's coordinate `dim` (bases 2, 3, 5, 7), from the table when it
 * holds it (the same values: the table is filled by radical_inverse). */
static const uint32_t HALTON_BASE[4] = {2, 3, 5, 7};
#define HALTON_TABLE_MAX 4096u

static double halton(const build_ctx *c, int dim, uint32_t i)
{
    return i < c->n_halton ? c->halton[(size_t)dim * c->n_halton + i] : radical_inverse(HALTON_BASE[dim], i);
}

static float frac_shift(double x, float shift)
{
    double v = x + shift;
    v -= floor(v);
    return (float)(v < 1.0 ? v : 0.0);
}

lie_status lie_sample_tables(build_ctx *c)
{
    c->n_halton = c->p->max_samples < HALTON_TABLE_MAX ? c->p->max_samples : HALTON_TABLE_MAX;
    c->halton = malloc(sizeof *c->halton * 4 * (size_t)c->n_halton + 1);
    for (int d = 0; c->halton && d < 4; d++)
        for (uint32_t i = 0; i < c->n_halton; i++)
            c->halton[(size_t)d * c->n_halton + i] = radical_inverse(HALTON_BASE[d], i);
    return c->halton ? LIE_OK : LIE_ERR_NOMEM;
}

/* ---- sampled blocker lists (§4.1, §4.3.2) ------------------------------ */

/* The pair's sampling: segment i runs from a patch point (Halton bases 2,
 * 3) to an emitter point (bases 5, 7), each shifted by a hash of the patch
 * and the emitter.
 *
 * Shared across the clusters of one emitter (lie_cluster): the segments
 * are the whole emitter's, and cluster e keeps those that end on one of
 * its triangles.  So the clusters of an emitter together cast about the
 * segments one unsplit emitter would, not one emitter's each, and every
 * kept segment lies inside cluster e's own (narrower) hull, so what the
 * unit finds depends on its own shaft only: units stay independent, and
 * an update recomputes exactly the units a rebuild would change (§5).
 * The density of segments per unit of shaft is the unsplit emitter's.
 * An emitter of one cluster keeps every segment, as before clusters. */
typedef struct pair_sampler {
    const build_ctx *c;
    uint32_t tri;
    const lie_vec3 *V;
    int two_sided, e;
    int em;       /* the emitter of cluster e, whose points the segments aim at */
    int shared;   /* the emitter has several clusters: keep cluster e's segments */
    float sp1, sp2, se1, se2;
} pair_sampler;

/* Segment i, if it counts (it leaves the patch's lit side and, for a
 * one-sided emitter, reaches its front); ex[] gets the triangles it must
 * not report (the patch's own and the emitter point's), *n_ex their count. */
static int pair_segment(const pair_sampler *ps, uint32_t i, lie_vec3 *org, lie_vec3 *dir, float *tnear, float *tfar,
                        uint32_t ex[2], int *n_ex)
{
    const build_ctx *c = ps->c;
    const lie_scene *s = c->s;
    const lie_vec3 *V = ps->V;
    float b1, b2;
    lie_sample_triangle(frac_shift(halton(c, 0, i), ps->sp1), frac_shift(halton(c, 1, i), ps->sp2), &b1, &b2);
    float b0 = 1.0f - b1 - b2;
    lie_vec3 p = lie_v3_add(lie_v3_add(lie_v3_scale(V[0], b0), lie_v3_scale(V[1], b1)), lie_v3_scale(V[2], b2));
    lie_vec3 q, ne;
    int one_sided;
    const float u1 = frac_shift(halton(c, 2, i), ps->se1), u2 = frac_shift(halton(c, 3, i), ps->se2);
    uint32_t target;
    if (ps->shared) {
        target = lie_emitter_target(s, ps->em, u1, u2, p, c->ray_far, &q, &ne, &one_sided);
        if (target >= s->n_tris || s->tri_cluster[target] != ps->e)
            return 0; /* another cluster's segment */
    } else {
        target = lie_cluster_target(s, ps->e, u1, u2, p, c->ray_far, &q, &ne, &one_sided);
    }
    lie_vec3 d = lie_v3_sub(q, p);
    lie_vec3 ng = s->tri_ng[ps->tri];
    float cg = lie_v3_dot(ng, d);
    if (!(cg > 0.0f) && !(ps->two_sided && cg < 0.0f))
        return 0;
    if (one_sided && !(lie_v3_dot(ne, d) < 0.0f))
        return 0;
    lie_vec3 side = cg > 0.0f ? ng : lie_v3_scale(ng, -1.0f);
    if (!lie_shadow_segment(p, side, q, org, dir, tnear, tfar))
        return 0;
    ex[0] = ps->tri;
    ex[1] = target;
    *n_ex = target == LIE_NO_HIT ? 1 : 2;
    return 1;
}

/* Segments of a pair's first round after which, none blocked, its shaft is
 * asked whether any triangle enters it (lie_sample_pair). */
#define SHAFT_PROBE 16u
/* Segments traced as one packet (lie_rt_all_hits8); SHAFT_PROBE is a
 * multiple of it. */
#define SEGMENT_PACKET 8u

/* A cluster of a shared sampling keeps only its share of the segments;
 * before it is called occluded it probes as many of its own as an unsplit
 * emitter would (max_samples), over at most this many times the indices. */
#define SHARED_PROBE_SPAN 64u

/* After the first round found every segment blocked: are all the segments
 * up to max_samples blocked too (shared: done of the cluster's so far)?
 * Any-hit queries, stopping at the first segment that is not. */
static int all_blocked_to_max(const pair_sampler *ps, uint32_t from, uint64_t done, worker *w)
{
    const build_ctx *c = ps->c;
    const uint64_t end = ps->shared ? (uint64_t)c->p->max_samples * SHARED_PROBE_SPAN : c->p->max_samples;
    uint64_t kept = done; /* shared: the cluster's segments so far */
    for (uint64_t i = from; i < end && (!ps->shared || kept < c->p->max_samples); i++) {
        lie_vec3 org, dir;
        float tnear, tfar;
        uint32_t ex[2];
        int n_ex;
        if (!pair_segment(ps, (uint32_t)i, &org, &dir, &tnear, &tfar, ex, &n_ex))
            continue;
        kept++;
        w->st.segments++;
        if (!lie_rt_any_hit(c->rt, org, dir, tnear, tfar, ex, n_ex))
            return 0;
    }
    return 1;
}

/* Classify one patch–emitter pair by sampling segments.  Leaves the sorted
 * unique blocker list in w->hits[0..*n_list).
 *
 * Rounds of segments, doubling while a round finds a blocker the earlier
 * ones missed (§4.3.2), up to max_samples.  Sampling stops early when the
 * outcome can no longer change; only the informational quality and count
 * of such nodes then differ from sampling on (formats/lie-cache.md):
 * - the first round blocked every segment: any-hit queries for the rest
 *   either find them all blocked (occluded, quality = max_samples) or
 *   meet a free one, and the rounds go on as if the probe had not been;
 * - the pair is partial (some segment blocked, some not) and its list is
 *   already past complex_cap: such a list is never stored (the node splits
 *   or is complex), so it is not expanded to whole instances.  Where the
 *   emitter has more than complex_cap triangles and the patch may split,
 *   sampling goes on: the emitter's own triangles decide the split.
 * One piece: the rounds, the probe and these stops share the pair's
 * segments, counters and list, in the order the list's bytes depend on. */
lie_class lie_sample_pair(const build_ctx *c, worker *w, uint32_t tri, lie_patch_path path, const lie_vec3 V[3],
                          int two_sided, int e, uint32_t *quality, size_t *n_list)
{
    const lie_scene *s = c->s;
    const int em_index = s->clusters[e].emitter;
    const lie_emitter *em = &s->emitters[em_index];
    const int shared = em->n_clusters > 1;
    /* The shifts hash the patch alone, so that every emitter, and every
     * cluster of one, sees the same pattern from it.  Not the emitter's
     * index: emitters are numbered in the scene's walk order, so one that
     * appears or goes (a set-emission) renumbers those after it, and a
     * unit's segments would change with no change to its patch or emitter
     * (update = rebuild; formats/lie-cache.md, version 5).  The patterns of
     * different emitters from one patch are alike, but their segments end
     * on different emitters and meet different blockers. */
    uint64_t h = lie_hash_u64x4(tri, path.digits, (uint64_t)path.depth, 0);
    uint64_t h2 = lie_hash_u64x4(h, 0x656d6974ull, 0, 0);
    const pair_sampler ps = {c,
                             tri,
                             V,
                             two_sided,
                             e,
                             em_index,
                             shared,
                             lie_hash_to_unit(h),
                             lie_hash_to_unit(h << 24),
                             lie_hash_to_unit(h2),
                             lie_hash_to_unit(h2 << 24)};
    const int can_split = lie_subdiv_may_split(c, tri, path);
    /* The list length past which this node's class is settled, once partial:
     * past complex_cap the list is never stored (a node that splits keeps only
     * its count; one that does not, or whose split is undone because it does
     * not shorten the lists, is complex).  Below it the list is sampled in
     * full, since lie_subdiv may keep any node as a leaf.  A node that may
     * split towards an emitter of more than complex_cap triangles is never
     * settled early: its own triangles decide whether it splits. */
    const size_t settled = can_split && em->n_tris > c->p->complex_cap ? SIZE_MAX : c->p->complex_cap;
    uint32_t total = 0, round_n = c->p->samples;
    uint64_t valid = 0, blocked = 0;
    size_t known = 0; /* distinct blockers after the previous round */
    int forced = 0;
    size_t n_forced = 0;
    uint64_t cast = 0;
    w->n_hits = 0;
    /* hits are kept unique as they come (a segment through an occluder
     * hits it hundreds of times a pair), by stamping triangles */
    if (!w->stamp) {
        w->stamp = calloc((size_t)s->n_tris + 1, sizeof *w->stamp);
        if (!w->stamp) {
            w->nomem = 1;
            return LIE_CLASS_VISIBLE;
        }
    }
    if (++w->stamp_id == 0) {
        memset(w->stamp, 0, sizeof *w->stamp * ((size_t)s->n_tris + 1));
        w->stamp_id = 1;
    }
    const uint32_t id = w->stamp_id;
    for (;;) {
        /* segments in packets of SEGMENT_PACKET, traced together
         * (lie_rt_all_hits8): a pair's segments are coherent */
        for (uint32_t i0 = total; i0 < total + round_n; i0 += SEGMENT_PACKET) {
            /* A shaft no triangle enters is visible, proven (the test the
             * first round ends with when it finds nothing, below): when the
             * first SHAFT_PROBE segments of the pair found nothing, ask the
             * shaft before paying for the rest of the round.  With many
             * emitters most lit pairs are such. */
            if (i0 == SHAFT_PROBE && total == 0 && w->n_hits == 0 && SHAFT_PROBE < round_n) {
                if (lie_cull_shaft_empty(c, w, tri, V, two_sided, e)) {
                    w->st.segments += shared ? cast : SHAFT_PROBE;
                    *quality = round_n; /* what the whole round would have said */
                    *n_list = 0;
                    return LIE_CLASS_VISIBLE;
                }
                if (w->nomem)
                    return LIE_CLASS_VISIBLE;
            }
            uint32_t i1 = total + round_n - i0 < SEGMENT_PACKET ? total + round_n : i0 + SEGMENT_PACKET;
            lie_vec3 org[SEGMENT_PACKET], dir[SEGMENT_PACKET];
            float tnear[SEGMENT_PACKET], tfar[SEGMENT_PACKET];
            uint32_t ex[SEGMENT_PACKET][2];
            int n_ex[SEGMENT_PACKET], m = 0;
            for (uint32_t i = i0; i < i1; i++)
                m += pair_segment(&ps, i, &org[m], &dir[m], &tnear[m], &tfar[m], ex[m], &n_ex[m]);
            if (m == 0)
                continue;
            cast += (uint64_t)m;
            size_t before = w->n_hits;
            unsigned hit_mask = 0;
            if (lie_rt_all_hits8(c->rt, org, dir, tnear, tfar, (const uint32_t(*)[2])ex, n_ex, m, &w->hits,
                                 &w->n_hits, &w->cap_hits, &hit_mask) != LIE_OK) {
                w->nomem = 1;
                return LIE_CLASS_VISIBLE;
            }
            valid += (uint64_t)m;
            blocked += (uint64_t)__builtin_popcount(hit_mask);
            size_t k = before;
            for (size_t j = before; j < w->n_hits; j++) {
                uint32_t t = w->hits[j];
                if (t < s->n_tris && w->stamp[t] == id)
                    continue;
                if (t < s->n_tris)
                    w->stamp[t] = id;
                w->hits[k++] = t;
            }
            w->n_hits = k;
        }
        w->st.segments += shared ? cast : round_n; /* shared: the segments this cluster kept */
        cast = 0;
        total += round_n;
        w->n_hits = lie_sort_unique(w->hits, w->n_hits);
        int found_new = w->n_hits > known;
        known = w->n_hits;
        if (total >= c->p->max_samples)
            break;
        if (blocked > 0 && blocked < valid && w->n_hits > settled) {
            *quality = total; /* partial, and the list already decides the node */
            *n_list = w->n_hits;
            return LIE_CLASS_PARTIAL;
        }
        if (total == c->p->samples && valid > 0 && blocked == valid && all_blocked_to_max(&ps, total, valid, w)) {
            *quality = c->p->max_samples;
            *n_list = w->n_hits;
            return LIE_CLASS_OCCLUDED;
        }
        /* §4.3.2: keep doubling while a round finds a blocker the earlier
         * rounds missed */
        if (!found_new && w->n_hits > 0)
            break;
        if (!found_new && !forced) {
            /* Nothing found.  Only triangles in the shaft can block: none
             * means visible, proven; a few become the list, exact; many
             * mean sampling on to max_samples before calling it visible. */
            size_t n_shaft = lie_cull_shaft(c, w, tri, V, two_sided, e);
            if (n_shaft == 0)
                break;
            if (n_shaft <= c->p->max_blockers) {
                *quality = total;
                *n_list = n_shaft;
                if (!LIE_GROW(w->hits, w->cap_hits, n_shaft)) {
                    w->nomem = 1;
                    return LIE_CLASS_VISIBLE;
                }
                memcpy(w->hits, w->cand, n_shaft * sizeof *w->hits);
                w->n_hits = n_shaft;
                return LIE_CLASS_PARTIAL;
            }
            forced = 1;
            n_forced = n_shaft;
        }
        round_n = total;
        if (total + round_n > c->p->max_samples)
            round_n = c->p->max_samples - total;
    }
    if (shared && valid > 0 && blocked == valid && !all_blocked_to_max(&ps, total, valid, w)) {
        /* a cluster's share called it occluded, its own probes do not */
        *quality = total;
        *n_list = w->n_hits;
        return LIE_CLASS_PARTIAL;
    }
    if (forced && blocked == 0) {
        /* The segments found nothing in a shaft of many triangles.  That
         * proves nothing (thin parts, small triangles between them): the
         * pair is visible with the shaft as its list, which lie_subdiv
         * replaces at a leaf by the exact one (lib/lie/subdiv.c,
         * complete_leaf).  A cluster of a shared sampling, which saw only
         * its share of the segments, takes them as a partial list instead,
         * so that its patch splits while the list is long. */
        if (!LIE_GROW(w->hits, w->cap_hits, n_forced)) {
            w->nomem = 1;
            return LIE_CLASS_VISIBLE;
        }
        memcpy(w->hits, w->cand, n_forced * sizeof *w->hits);
        *quality = total;
        *n_list = n_forced;
        return shared ? LIE_CLASS_PARTIAL : LIE_CLASS_VISIBLE;
    }
    if (blocked > 0 && blocked < valid)
        lie_cull_expand(c, w, tri, V, two_sided, e, c->p->complex_cap);
    *quality = total;
    *n_list = w->n_hits;
    if (valid == 0 || blocked == 0)
        return LIE_CLASS_VISIBLE;
    if (blocked == valid)
        return LIE_CLASS_OCCLUDED;
    return LIE_CLASS_PARTIAL;
}
