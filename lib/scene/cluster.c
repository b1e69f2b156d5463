/* Clusters of emitter triangles (lie_cluster, lib/scene/scene.h): a
 * visibility-only partition of a large emitter, so that the hull of each
 * pair lie-build classifies spans a part of the emitter rather than all of
 * it (a light strip down a corridor, a neon sign over a street).
 *
 * Split in space, as a bounding volume hierarchy is built: the cluster of
 * largest extent is cut at the median of its triangles' centroids along
 * its longest axis, while it is larger than a quarter of the emitter's
 * extent, holds at least 2 LIE_CLUSTER_MIN_TRIS triangles, and the emitter
 * has fewer than LIE_CLUSTER_MAX clusters.  A function of the emitter's own
 * triangles alone (so an edit elsewhere never changes it), and
 * deterministic: ties are broken by triangle index. */
#include "scene/internal.h"

#include <stdlib.h>
#include <string.h>

/* Split while a cluster's extent passes this share of the emitter's. */
#define CLUSTER_EXTENT_SHARE 0.25f

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

static int u32_cmp(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

static lie_vec3 centroid(const lie_scene *s, uint32_t t)
{
    const lie_vec3 *P = &s->tri_p[3 * (size_t)t];
    return lie_v3_scale(lie_v3_add(P[0], lie_v3_add(P[1], P[2])), 1.0f / 3.0f);
}

static lie_box3 vertex_box(const lie_scene *s, const uint32_t *tris, uint32_t n)
{
    lie_box3 b = lie_box3_empty();
    for (uint32_t k = 0; k < n; k++)
        for (int j = 0; j < 3; j++)
            lie_box3_grow(&b, s->tri_p[3 * (size_t)tris[k] + (size_t)j]);
    return b;
}

static float box_diag(lie_box3 b) { return lie_box3_is_empty(&b) ? 0.0f : lie_v3_len(lie_v3_sub(b.hi, b.lo)); }

typedef struct part {
    uint32_t lo, n; /* tris[lo .. lo + n) */
    float diag;
} part;

/* Partition tris[0..n) (one emitter's) in place into parts; returns how
 * many.  kx: scratch of n entries. */
static int split_emitter(const lie_scene *s, uint32_t *tris, uint32_t n, keyed *kx, part *parts)
{
    int np = 1;
    parts[0].lo = 0;
    parts[0].n = n;
    parts[0].diag = box_diag(vertex_box(s, tris, n));
    const float limit = CLUSTER_EXTENT_SHARE * parts[0].diag;
    while (np < LIE_CLUSTER_MAX) {
        int best = -1;
        for (int i = 0; i < np; i++)
            if (parts[i].n >= 2 * LIE_CLUSTER_MIN_TRIS && parts[i].diag > limit &&
                (best < 0 || parts[i].diag > parts[best].diag))
                best = i;
        if (best < 0)
            break;
        part *p = &parts[best];
        lie_box3 cb = lie_box3_empty();
        for (uint32_t k = 0; k < p->n; k++)
            lie_box3_grow(&cb, centroid(s, tris[p->lo + k]));
        lie_vec3 ext = lie_v3_sub(cb.hi, cb.lo);
        int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : ext.y >= ext.z ? 1 : 2;
        if (!(ext.x > 0.0f || ext.y > 0.0f || ext.z > 0.0f))
            break; /* every centroid in one point: nothing to cut */
        for (uint32_t k = 0; k < p->n; k++) {
            lie_vec3 c = centroid(s, tris[p->lo + k]);
            kx[k].key = axis == 0 ? c.x : axis == 1 ? c.y : c.z;
            kx[k].tri = tris[p->lo + k];
        }
        qsort(kx, p->n, sizeof *kx, keyed_cmp);
        for (uint32_t k = 0; k < p->n; k++)
            tris[p->lo + k] = kx[k].tri;
        uint32_t half = p->n / 2;
        part a = {p->lo, half, 0.0f}, b = {p->lo + half, p->n - half, 0.0f};
        a.diag = box_diag(vertex_box(s, tris + a.lo, a.n));
        b.diag = box_diag(vertex_box(s, tris + b.lo, b.n));
        parts[best] = a;
        parts[np++] = b;
    }
    /* canonical: each part's triangles ascending, parts by their first */
    for (int i = 0; i < np; i++)
        qsort(tris + parts[i].lo, parts[i].n, sizeof *tris, u32_cmp);
    for (int i = 1; i < np; i++)
        for (int j = i; j > 0 && tris[parts[j].lo] < tris[parts[j - 1].lo]; j--) {
            part t = parts[j];
            parts[j] = parts[j - 1];
            parts[j - 1] = t;
        }
    return np;
}

lie_status lie_scene_cluster(lie_scene *s)
{
    size_t n_area_tris = 0;
    for (int e = 0; e < s->n_emitters; e++)
        if (s->emitters[e].type == LIE_EMITTER_AREA)
            n_area_tris += s->emitters[e].n_tris;
    s->clusters = calloc((size_t)s->n_emitters * LIE_CLUSTER_MAX + 1, sizeof *s->clusters);
    s->cluster_tris = malloc(sizeof *s->cluster_tris * (n_area_tris + 1));
    s->cluster_cdf = malloc(sizeof *s->cluster_cdf * (n_area_tris + 1));
    s->tri_cluster = malloc(sizeof *s->tri_cluster * ((size_t)s->n_tris + 1));
    keyed *kx = malloc(sizeof *kx * (n_area_tris + 1));
    uint32_t *scratch = malloc(sizeof *scratch * (n_area_tris + 1));
    part parts[LIE_CLUSTER_MAX];
    if (!s->clusters || !s->cluster_tris || !s->cluster_cdf || !s->tri_cluster || !kx || !scratch) {
        free(kx);
        free(scratch);
        return LIE_ERR_NOMEM;
    }
    for (uint32_t t = 0; t < s->n_tris; t++)
        s->tri_cluster[t] = -1;
    int nc = 0;
    uint32_t at = 0;
    for (int e = 0; e < s->n_emitters; e++) {
        lie_emitter *em = &s->emitters[e];
        em->first_cluster = nc;
        if (em->type != LIE_EMITTER_AREA) {
            s->clusters[nc].emitter = e;
            s->clusters[nc].first = at;
            nc++;
            em->n_clusters = 1;
            continue;
        }
        for (uint32_t k = 0; k < em->n_tris; k++)
            scratch[k] = em->first_tri + k;
        int np = split_emitter(s, scratch, em->n_tris, kx, parts);
        for (int i = 0; i < np; i++) {
            lie_cluster *cl = &s->clusters[nc];
            cl->emitter = e;
            cl->first = at;
            cl->n_tris = parts[i].n;
            double acc = 0.0;
            for (uint32_t k = 0; k < parts[i].n; k++) {
                uint32_t g = scratch[parts[i].lo + k];
                s->cluster_tris[at + k] = g;
                acc += s->tri_area[g];
                s->cluster_cdf[at + k] = (float)acc;
                s->tri_cluster[g] = nc;
            }
            cl->area = (float)acc;
            lie_scene_hull_of(s, s->cluster_tris + at, 0, cl->n_tris, cl->hull, &cl->n_hull);
            at += parts[i].n;
            nc++;
        }
        em->n_clusters = np;
    }
    s->n_clusters = nc;
    free(kx);
    free(scratch);
    return LIE_OK;
}

uint32_t lie_scene_cluster_digest(const lie_scene *s, int e)
{
    const lie_emitter *em = &s->emitters[e];
    if (em->n_clusters <= 1)
        return 0;
    uint64_t h = lie_hash_u64x4(0x636c7573746572ull /* "cluster" */, (uint64_t)em->n_clusters, 0, 0);
    for (int c = em->first_cluster; c < em->first_cluster + em->n_clusters; c++) {
        const lie_cluster *cl = &s->clusters[c];
        for (uint32_t k = 0; k < cl->n_tris; k++)
            h = lie_hash_u64x4(h, (uint64_t)(c - em->first_cluster), s->cluster_tris[cl->first + k], 0);
    }
    return (uint32_t)(h ^ (h >> 32)) | 1u; /* never 0: that is one cluster's */
}

/* ---- the emitter interface's geometry, of one cluster ------------------- */

static int whole(const lie_scene *s, int c) { return s->emitters[s->clusters[c].emitter].n_clusters == 1; }

int lie_cluster_hull_cap(const lie_scene *s, int c)
{
    const lie_cluster *cl = &s->clusters[c];
    if (whole(s, c))
        return lie_emitter_hull_cap(&s->emitters[cl->emitter]);
    return cl->n_hull ? cl->n_hull : 3 * (int)cl->n_tris;
}

int lie_cluster_hull_points(const lie_scene *s, int c, const lie_vec3 V[3], float far, lie_vec3 *out)
{
    const lie_cluster *cl = &s->clusters[c];
    if (whole(s, c))
        return lie_emitter_hull_points(s, cl->emitter, V, far, out);
    if (cl->n_hull) {
        memcpy(out, cl->hull, sizeof(lie_vec3) * (size_t)cl->n_hull);
        return cl->n_hull;
    }
    for (uint32_t k = 0; k < cl->n_tris; k++)
        memcpy(out + 3 * k, &s->tri_p[3 * (size_t)s->cluster_tris[cl->first + k]], sizeof(lie_vec3) * 3);
    return 3 * (int)cl->n_tris;
}

const lie_vec3 *lie_cluster_facing(const lie_scene *s, int c)
{
    const lie_cluster *cl = &s->clusters[c];
    if (whole(s, c))
        return lie_emitter_facing(s, cl->emitter);
    return &s->tri_ng[s->cluster_tris[cl->first]]; /* any axis serves the separating-axis test */
}

uint32_t lie_cluster_target(const lie_scene *s, int c, float u1, float u2, lie_vec3 p, float far, lie_vec3 *q,
                            lie_vec3 *n, int *one_sided)
{
    const lie_cluster *cl = &s->clusters[c];
    if (whole(s, c))
        return lie_emitter_target(s, cl->emitter, u1, u2, p, far, q, n, one_sided);
    float b1, b2;
    *one_sided = !s->emitters[cl->emitter].double_sided;
    return lie_scene_point_on(s, s->cluster_tris + cl->first, 0, cl->n_tris, s->cluster_cdf + cl->first, cl->area,
                              u1, u2, q, n, &b1, &b2);
}

int lie_cluster_can_reach(const lie_scene *s, int c, uint32_t tri, const lie_vec3 V[3], lie_vec3 ng, int two_sided)
{
    const lie_cluster *cl = &s->clusters[c];
    if (whole(s, c))
        return lie_emitter_can_reach(s, cl->emitter, tri, V, ng, two_sided);
    const lie_emitter *em = &s->emitters[cl->emitter];
    return !lie_emitter_owns(em, tri) &&
           lie_scene_area_may_reach(s, em, s->cluster_tris + cl->first, 0, cl->n_tris, V, ng, two_sided);
}
