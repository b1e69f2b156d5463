/* SPDX-License-Identifier: Apache-2.0 */
/* Light groups (sampler.h): the budgeted samplers choose among groups of
 * an emitter's triangles, not among whole emitters.
 *
 * Why: a strip of a thousand triangles down a corridor, sampled by area as
 * one light, sends most of a point's samples to the far end, where they
 * add almost nothing, and the few that land near the point carry all of
 * its light: the estimate's variance is that of the 1 / r^2 over the
 * whole strip.  pbrt-v4's BVHLightSampler and Cycles' light tree (Conty
 * Estevez and Kulla 2018) make every emissive triangle a light, so that
 * the tree's importance (distance, orientation) chooses the near ones.
 * Here an emitter of more than GROUP_SPLIT_TRIS triangles is cut in space, as a
 * bounding volume hierarchy is built (the median of the centroids along
 * the longest axis), into groups of at most GROUP_TRIS; each group is a
 * light of the sampler, with its own box, normal cone and power, and its
 * samples are drawn over its own triangles by their light (the emissive
 * texture's, lib/shade/texlight.h), or for an emitter of one radiance by
 * the solid angle they subtend (Arvo 1995).  For a Lambert receiver and an
 * emitter of one radiance, a group's closed form (lie_triangle_unshadowed)
 * times its samples' visible share is the estimate (lib/shade/pair.c's
 * ratio estimator): the samples then estimate visibility alone.
 *
 * A group is a part of its emitter: the emitter's LIE class holds for it
 * (a part of a visible emitter is visible, of an occluded one occluded, and
 * a partial pair's blocker list holds every blocker of a part).  The
 * emitter's polylight describes the whole, so a part's pair takes its own
 * triangles' closed form instead, and no exact shadow or bitmask. */
#include "shade/sampler.h"
#include "shade/spherical.h"
#include "shade/texlight.h"

#include <stdlib.h>
#include <string.h>

/* Triangles per group at most: 1, as pbrt-v4.  Groups of 8 lost on
 * scifi_hallway (docs/measurements.md, "Light groups"): a group's triangle
 * is chosen by its light alone, so a point beside one small triangle of
 * the group sees it rarely and then as a firefly; alone, the tree's
 * importance (distance, orientation) chooses it. */
#define GROUP_TRIS 1
/* An emitter of at most this many triangles stays one light: its closed
 * form (lib/shade/polylight.h, a few dozen edges) makes its unshadowed
 * light exact, where groups would add the noise of choosing among them.
 * Measured (docs/measurements.md, "Light groups"): at 16, ccity_buildings'
 * windows and signs split and lost (p99 0.87 against 0.77 whole, same
 * time); at 64 and 256 both it and scifi_hallway (strips of 320 and 1,250
 * triangles) keep the better of the two. */
#define GROUP_SPLIT_TRIS 64

typedef struct keyed {
    float key;
    uint32_t tri;
} keyed;

static int keyed_cmp(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return x->tri < y->tri ? -1 : x->tri > y->tri;
}

typedef struct builder {
    const lie_scene *s;
    lie_light_groups *G;
    keyed *k;        /* scratch */
    int cap;         /* groups allocated */
    uint32_t n_slots;
} builder;

static float centroid_axis(const lie_scene *s, uint32_t t, int a)
{
    const lie_vec3 *P = &s->tri_p[3 * (size_t)t];
    float v0 = a == 0 ? P[0].x : a == 1 ? P[0].y : P[0].z;
    float v1 = a == 0 ? P[1].x : a == 1 ? P[1].y : P[1].z;
    float v2 = a == 0 ? P[2].x : a == 1 ? P[2].y : P[2].z;
    return (v0 + v1 + v2) / 3.0f;
}

static int push_group(builder *b, int e, uint32_t first, uint32_t n)
{
    lie_light_groups *G = b->G;
    if (G->n == b->cap) {
        int cap = b->cap ? 2 * b->cap : 64;
        lie_light_group *g = realloc(G->g, sizeof *g * (size_t)cap);
        if (!g)
            return 0;
        G->g = g;
        b->cap = cap;
    }
    lie_light_group *g = &G->g[G->n++];
    memset(g, 0, sizeof *g);
    g->emitter = e;
    g->first = first;
    g->n = n;
    return 1;
}

/* Split tris[first, first + n) (slots of G->tris) into groups. */
static int split(builder *b, int e, uint32_t first, uint32_t n)
{
    if (n <= GROUP_TRIS)
        return push_group(b, e, first, n);
    const lie_scene *s = b->s;
    uint32_t *tris = b->G->tris + first;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            float c = centroid_axis(s, tris[i], a);
            lo[a] = fminf(lo[a], c);
            hi[a] = fmaxf(hi[a], c);
        }
    int axis = 0;
    for (int a = 1; a < 3; a++)
        if (hi[a] - lo[a] > hi[axis] - lo[axis])
            axis = a;
    for (uint32_t i = 0; i < n; i++)
        b->k[i] = (keyed){centroid_axis(s, tris[i], axis), tris[i]};
    qsort(b->k, n, sizeof *b->k, keyed_cmp);
    for (uint32_t i = 0; i < n; i++)
        tris[i] = b->k[i].tri;
    uint32_t half = n / 2;
    return split(b, e, first, half) && split(b, e, first + half, n - half);
}

/* Group g's box, cone and power: phi_e (the emitter's, as the sampler
 * weighs it) times its share of the emitter's light. */
static void group_bounds(const lie_scene *s, const lie_light_groups *G, const lie_light_group *g, double emitter_total,
                         const lie_light_bounds *eb, lie_light_bounds *b)
{
    memset(b, 0, sizeof *b);
    lie_light_bounds_tris(s, G->tris, g->first, g->n, s->emitters[g->emitter].double_sided, b);
    double share = emitter_total > 0.0 ? g->total / emitter_total : 0.0;
    b->phi = (float)((double)eb->phi * share);
    if (!isfinite(b->phi) || !(b->phi > 0.0f))
        b->phi = 0.0f;
}

lie_status lie_light_groups_create(const lie_scene *s, lie_texlight *const *tl, const lie_light_bounds *eb, int split_on,
                                   lie_light_groups **out)
{
    *out = NULL;
    lie_light_groups *G = calloc(1, sizeof *G);
    if (!G)
        return LIE_ERR_NOMEM;
    G->split = split_on;
    size_t slots = 0;
    uint32_t most = 1;
    for (int e = 0; e < s->n_emitters; e++) {
        slots += s->emitters[e].n_tris;
        if (s->emitters[e].n_tris > most)
            most = s->emitters[e].n_tris;
    }
    G->tris = malloc(sizeof *G->tris * (slots + 1));
    G->cdf = malloc(sizeof *G->cdf * (slots + 1));
    builder b = {s, G, malloc(sizeof(keyed) * most), 0, 0};
    lie_status st = G->tris && G->cdf && b.k ? LIE_OK : LIE_ERR_NOMEM;
    uint32_t used = 0;
    for (int e = 0; st == LIE_OK && e < s->n_emitters; e++) {
        const lie_emitter *em = &s->emitters[e];
        const lie_texlight *t = tl ? tl[e] : NULL;
        int first_group = G->n;
        /* a delta light, a small emitter, or one whose light no
         * distribution describes (a texture that could not be read) is
         * one group, sampled as a whole */
        int whole = !split_on || lie_emitter_is_delta(em) || em->n_tris <= GROUP_SPLIT_TRIS ||
                    (!t && !lie_emitter_uniform(s, e));
        if (whole) {
            if (!push_group(&b, e, used, 0)) {
                st = LIE_ERR_NOMEM;
                break;
            }
            G->g[G->n - 1].whole = 1;
            continue;
        }
        /* the lit triangles (a dark one has no light to sample) */
        uint32_t n = 0;
        for (uint32_t k = 0; k < em->n_tris; k++) {
            double w = t ? lie_texlight_tri_weight(t, k) : s->tri_area[em->first_tri + k];
            if (w > 0.0)
                G->tris[used + n++] = em->first_tri + k;
        }
        if (!split(&b, e, used, n)) {
            st = LIE_ERR_NOMEM;
            break;
        }
        double total = 0.0;
        for (int j = first_group; j < G->n; j++) {
            lie_light_group *g = &G->g[j];
            double acc = 0.0;
            for (uint32_t i = g->first; i < g->first + g->n; i++) {
                uint32_t k = G->tris[i] - em->first_tri;
                acc += t ? lie_texlight_tri_weight(t, k) : s->tri_area[G->tris[i]];
                G->cdf[i] = acc;
            }
            g->total = acc;
            total += acc;
        }
        for (int j = first_group; j < G->n; j++)
            G->g[j].emitter_total = total;
        used += n;
    }
    free(b.k);
    if (st == LIE_OK) {
        G->bounds = calloc((size_t)G->n + 1, sizeof *G->bounds);
        st = G->bounds ? LIE_OK : LIE_ERR_NOMEM;
    }
    for (int j = 0; st == LIE_OK && j < G->n; j++) {
        const lie_light_group *g = &G->g[j];
        if (g->whole)
            G->bounds[j] = eb[g->emitter];
        else
            group_bounds(s, G, g, g->emitter_total, &eb[g->emitter], &G->bounds[j]);
    }
    if (st != LIE_OK) {
        lie_light_groups_destroy(G);
        return st;
    }
    *out = G;
    return LIE_OK;
}

void lie_light_groups_destroy(lie_light_groups *G)
{
    if (!G)
        return;
    free(G->g);
    free(G->tris);
    free(G->cdf);
    free(G->bounds);
    free(G);
}

void lie_light_group_sample(const lie_scene *s, const lie_light_groups *G, int j, const lie_texlight *tl,
                            const lie_vec3 *o, float u1, float u2, lie_emitter_sample *out)
{
    const lie_light_group *g = &G->g[j];
    const lie_emitter *em = &s->emitters[g->emitter];
    /* the triangle by u1 over the group's cumulative weights */
    double x = (double)u1 * g->total;
    uint32_t lo = g->first, hi = g->first + g->n - 1;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        if (x < G->cdf[mid])
            hi = mid;
        else
            lo = mid + 1;
    }
    double below = lo > g->first ? G->cdf[lo - 1] : 0.0, w = G->cdf[lo] - below;
    float r = w > 0.0 ? (float)((x - below) / w) : 0.5f;
    r = fminf(fmaxf(r, 0.0f), LIE_BELOW_ONE);
    uint32_t t = G->tris[lo];
    if (tl) {
        lie_texlight_sample_tri(s, g->emitter, tl, t - em->first_tri, r, u2, out);
    } else {
        const lie_vec3 *P = &s->tri_p[3 * (size_t)t];
        /* near the triangle, by the solid angle it subtends from o (Arvo
         * 1995, spherical.h): the 1 / d^2 of area samples beside an
         * emitter is what makes a pixel's few samples fireflies */
        lie_sph_tri st;
        lie_sph_sample q;
        if (o && lie_sph_tri_setup(*o, P, &st) && lie_sph_tri_sample(&st, r, fminf(u2, LIE_BELOW_ONE), &q) &&
            q.inv_pdf_area > 0.0 && isfinite(q.inv_pdf_area)) {
            out->p = lie_v3((float)q.p[0], (float)q.p[1], (float)q.p[2]);
            out->n = s->tri_ng[t];
            out->tri = t;
            memcpy(out->le, em->radiance, sizeof out->le);
            out->inv_pdf = (float)q.inv_pdf_area;
            double pt = w / g->total;
            out->inv_pdf = pt > 0.0 ? (float)((double)out->inv_pdf / pt) : 0.0f;
            return;
        }
        float b1, b2;
        lie_sample_triangle(r, fminf(u2, LIE_BELOW_ONE), &b1, &b2);
        float b0 = 1.0f - b1 - b2;
        out->p = lie_v3_add(lie_v3_add(lie_v3_scale(P[0], b0), lie_v3_scale(P[1], b1)), lie_v3_scale(P[2], b2));
        out->n = s->tri_ng[t];
        out->tri = t;
        memcpy(out->le, em->radiance, sizeof out->le);
        out->inv_pdf = s->tri_area[t];
    }
    /* density: P(triangle | group) times the density on the triangle */
    double pt = w / g->total;
    out->inv_pdf = pt > 0.0 && out->inv_pdf > 0.0f ? (float)((double)out->inv_pdf / pt) : 0.0f;
}
