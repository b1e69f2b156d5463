/* SPDX-License-Identifier: Apache-2.0 */
/* Clusters of emitter triangles (lie_cluster, lib/scene/scene.h): a
 * visibility-only partition of a large emitter, so that the hull of each
 * pair lie-build classifies spans a part of the emitter rather than all of
 * it (a light strip down a corridor, a neon sign over a street).
 *
 * Split in space, as a bounding volume hierarchy is built: the cluster of
 * largest extent is cut at the median of its triangles' centroids along
 * its longest axis, while it is larger than CLUSTER_EXTENT_SHARE of the
 * scene's extent, holds at least 2 LIE_CLUSTER_MIN_TRIS triangles, and the
 * emitter has fewer than lie_scene_options.emitter_clusters clusters
 * (default CLUSTER_SPLIT_MAX).  A function of the
 * emitter's triangles and the scene's bounds, deterministic (ties are
 * broken by triangle index); lib/update compares partitions by digest and
 * rebuilds an emitter's units when its partition changed.
 *
 * An emissive texture may be black over a whole emitter (bedroom_corner's
 * second emissive mesh): wherever a lookup can land on its triangles, it
 * reads black.  Such an emitter is one dark cluster, which no pair is built
 * for and lie-render skips. */
#include "scene/internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Lit triangles (textured or not: clusters change visibility only) are
 * split while a part's extent passes this share of the scene's, into at
 * most CLUSTER_SPLIT_MAX parts, or lie_scene_options.emitter_clusters.
 * 1: no spatial split by default, as measured (docs/measurements.md,
 * "Emitters in clusters"): with the sampling shared between an emitter's
 * clusters (lib/lie/sample.c) bedroom_corner's emitter in 8 clusters still
 * builds 19x slower than whole, for a slower frame.
 * (With the split on, tests/data/gltf/light_strip.gltf's strip in 2
 * clusters updates as it rebuilds for moves, rotations and removals;
 * tests/unit/test_cluster.c checks it.) */
/* 0: only an emitter dark as a whole becomes a dark cluster.  Measured
 * (docs/measurements.md, "Emitters in clusters"), splitting the dark
 * triangles off a partly lit emitter cost more than it saved: the lit cluster's segments,
 * aimed at the lit part only, find more partial pairs than the whole
 * emitter's did, so bedroom_corner's build took 2.2x and
 * LightsPunctualLamp's 1.5x the CPU time, for no faster frame (dark samples
 * weigh 0, and full visibility casts no ray for them either). */
#define CLUSTER_DARK_SPLIT 0
#define CLUSTER_EXTENT_SHARE 0.125f
#define CLUSTER_SPLIT_MAX 1

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

/* Is emissive texture t black wherever a bilinear lookup (lie_texture_sample)
 * on triangle g of material m can read?  Every texel within one of the
 * triangle's texture-space bounding box, wrapped as the sampler wraps. */
static int tri_dark(const lie_scene *s, const lie_material *m, const lie_texture *t, uint32_t g)
{
    if (!lie_texture_has_texels(t))
        return 0;
    float u[3], v[3];
    const float B[3][2] = {{0.0f, 0.0f}, {1.0f, 0.0f}, {0.0f, 1.0f}};
    for (int k = 0; k < 3; k++)
        lie_scene_slot_uv(s, m, LIE_TEX_EMISSIVE, g, B[k][0], B[k][1], &u[k], &v[k]);
    float umin = fminf(u[0], fminf(u[1], u[2])), umax = fmaxf(u[0], fmaxf(u[1], u[2]));
    float vmin = fminf(v[0], fminf(v[1], v[2])), vmax = fmaxf(v[0], fmaxf(v[1], v[2]));
    if (!isfinite(umin) || !isfinite(umax) || !isfinite(vmin) || !isfinite(vmax) || umax - umin > 1e6f ||
        vmax - vmin > 1e6f || fabsf(umin) > 1e6f || fabsf(vmin) > 1e6f)
        return 0;
    const int w = t->width, h = t->height;
    /* texel columns and rows around the box, a texel wider each side than
     * any lookup reaches; a span past two periods covers every texel */
    double x0 = floor((double)umin * w - 0.5) - 1.0, x1 = floor((double)umax * w - 0.5) + 2.0;
    double y0 = floor((double)vmin * h - 0.5) - 1.0, y1 = floor((double)vmax * h - 0.5) + 2.0;
    if (x1 - x0 >= 2.0 * w) {
        x0 = 0.0;
        x1 = 2.0 * w - 1.0;
    }
    if (y1 - y0 >= 2.0 * h) {
        y0 = 0.0;
        y1 = 2.0 * h - 1.0;
    }
    for (double y = y0; y <= y1; y += 1.0)
        for (double x = x0; x <= x1; x += 1.0) {
            int i = lie_texture_wrap_index((long long)x, w, t->wrap_s);
            int j = lie_texture_wrap_index((long long)y, h, t->wrap_t);
            float p[4];
            lie_texture_texel(t, (size_t)j * (size_t)w + (size_t)i, p);
            if (!(p[0] <= 0.0f && p[1] <= 0.0f && p[2] <= 0.0f))
                return 0;
        }
    return 1;
}

static float box_diag(lie_box3 b) { return lie_box3_is_empty(&b) ? 0.0f : lie_v3_len(lie_v3_sub(b.hi, b.lo)); }

typedef struct part {
    uint32_t lo, n; /* tris[lo .. lo + n) */
    float diag;
} part;

/* Partition tris[0..n) (one emitter's) in place into parts; returns how
 * many.  kx: scratch of n entries. */
static int split_emitter(const lie_scene *s, uint32_t *tris, uint32_t n, keyed *kx, part *parts, int kmax)
{
    int np = 1;
    parts[0].lo = 0;
    parts[0].n = n;
    parts[0].diag = box_diag(vertex_box(s, tris, n));
    const float limit = CLUSTER_EXTENT_SHARE * box_diag(s->bounds);
    while (np < kmax) {
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
        /* the dark triangles first (one cluster), then the lit ones, split */
        const lie_material *mat = lie_scene_material(s, s->tri_material[em->first_tri]);
        const lie_texture *tex =
            mat->emissive_tex >= 0 && mat->emissive_tex < s->n_textures ? &s->textures[mat->emissive_tex] : NULL;
        uint32_t n_dark = 0, n_lit = 0;
        for (uint32_t k = 0; k < em->n_tris; k++) {
            int dark = tex && tri_dark(s, mat, tex, em->first_tri + k);
            n_dark += (uint32_t)dark;
            if (!CLUSTER_DARK_SPLIT && !dark)
                break; /* one lit triangle and none is dark (below): the rest need not be read */
        }
        if (!CLUSTER_DARK_SPLIT && n_dark < em->n_tris)
            n_dark = 0; /* dark only as a whole */
        for (uint32_t k = 0, d = 0; k < em->n_tris; k++) {
            uint32_t g = em->first_tri + k;
            if (n_dark > 0 && tri_dark(s, mat, tex, g))
                scratch[d++] = g;
            else
                scratch[n_dark + n_lit++] = g;
        }
        int np = 0;
        if (n_dark > 0) {
            parts[0].lo = 0;
            parts[0].n = n_dark;
            np = 1;
        }
        if (n_lit > 0)
            np += split_emitter(s, scratch + n_dark, n_lit, kx, parts + np, s->cluster_max > 0 ? s->cluster_max : CLUSTER_SPLIT_MAX);
        for (int i = n_dark > 0; i < np; i++)
            parts[i].lo += n_dark;
        /* canonical: each part's triangles ascending; the dark part first,
         * then the lit ones by their first triangle */
        for (int i = 0; i < np; i++)
            qsort(scratch + parts[i].lo, parts[i].n, sizeof *scratch, u32_cmp);
        for (int i = (n_dark > 0) + 1; i < np; i++)
            for (int j = i; j > (n_dark > 0) && scratch[parts[j].lo] < scratch[parts[j - 1].lo]; j--) {
                part t = parts[j];
                parts[j] = parts[j - 1];
                parts[j - 1] = t;
            }
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
            cl->dark = n_dark > 0 && i == 0;
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
    if (cl->dark)
        return 0; /* no light leaves it */
    if (whole(s, c))
        return lie_emitter_can_reach(s, cl->emitter, tri, V, ng, two_sided);
    const lie_emitter *em = &s->emitters[cl->emitter];
    return !lie_emitter_owns(em, tri) &&
           lie_scene_area_may_reach(s, em, s->cluster_tris + cl->first, 0, cl->n_tris, V, ng, two_sided);
}

/* ---- unshadowed light, for the build's cost model ---------------------- */

/* The projected solid angle of triangle q (world) seen from p above the
 * plane of normal n: the triangle clipped to n . (x - p) >= 0, then
 * Lambert's edge sum (Arvo 1995, "Applications of irradiance tensors to
 * the simulation of non-Lambertian phenomena", eq. 3): half the sum over
 * the edges of the angle each subtends times the cosine between n and the
 * normal of the plane through p and the edge. */
static double projected_solid_angle(const lie_vec3 q[3], lie_vec3 p, lie_vec3 n)
{
    double v[4][3], h[3];
    int m = 0;
    for (int k = 0; k < 3; k++) {
        lie_vec3 d = lie_v3_sub(q[k], p);
        h[k] = (double)n.x * d.x + (double)n.y * d.y + (double)n.z * d.z;
    }
    /* Sutherland-Hodgman against one plane: at most four vertices */
    for (int k = 0; k < 3; k++) {
        int j = (k + 1) % 3;
        lie_vec3 a = lie_v3_sub(q[k], p), b = lie_v3_sub(q[j], p);
        if (h[k] >= 0.0) {
            v[m][0] = a.x, v[m][1] = a.y, v[m][2] = a.z;
            m++;
        }
        if ((h[k] >= 0.0) != (h[j] >= 0.0)) {
            double t = h[k] / (h[k] - h[j]);
            v[m][0] = a.x + t * (b.x - a.x), v[m][1] = a.y + t * (b.y - a.y), v[m][2] = a.z + t * (b.z - a.z);
            m++;
        }
    }
    if (m < 3)
        return 0.0;
    for (int k = 0; k < m; k++) {
        double l = sqrt(v[k][0] * v[k][0] + v[k][1] * v[k][1] + v[k][2] * v[k][2]);
        if (!(l > 0.0))
            return 0.0; /* p on the emitter: no finite estimate, and none needed (it owns no unit) */
        for (int c = 0; c < 3; c++)
            v[k][c] /= l;
    }
    double sum = 0.0;
    for (int k = 0; k < m; k++) {
        const double *a = v[k], *b = v[(k + 1) % m];
        double g[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
        double gl = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        if (!(gl > 0.0))
            continue;
        double c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        double theta = acos(c < -1.0 ? -1.0 : c > 1.0 ? 1.0 : c);
        sum += theta * (g[0] * n.x + g[1] * n.y + g[2] * n.z) / gl;
    }
    return 0.5 * fabs(sum);
}

static double luminance(const float c[3]) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

double lie_cluster_unshadowed(const lie_scene *s, int c, lie_vec3 p, lie_vec3 n, int two_sided, float far)
{
    const lie_cluster *cl = &s->clusters[c];
    const lie_emitter *em = &s->emitters[cl->emitter];
    if (cl->dark)
        return 0.0;
    if (lie_emitter_is_delta(em)) {
        lie_emitter_incident in;
        if (!lie_emitter_light_at(s, cl->emitter, p, far, &in))
            return 0.0;
        double cosv = (double)lie_v3_dot(n, in.wi);
        cosv = two_sided ? fabs(cosv) : cosv > 0.0 ? cosv : 0.0;
        return luminance(in.li) * cosv;
    }
    double omega = 0.0;
    for (uint32_t k = 0; k < cl->n_tris; k++) {
        uint32_t g = s->cluster_tris[cl->first + k];
        const lie_vec3 *q = &s->tri_p[3 * (size_t)g];
        if (!em->double_sided && lie_v3_dot(s->tri_ng[g], lie_v3_sub(p, q[0])) <= 0.0f)
            continue; /* p behind a one-sided emitter's triangle */
        omega += projected_solid_angle(q, p, n);
        if (two_sided)
            omega += projected_solid_angle(q, p, lie_v3_scale(n, -1.0f));
    }
    return luminance(em->radiance) * omega;
}

uint64_t lie_scene_light_digest(const lie_scene *s)
{
    uint64_t h = lie_hash_u64x4(0x6c69676874ull, (uint64_t)s->n_clusters, 0, 0);
    for (int c = 0; c < s->n_clusters; c++) {
        const lie_cluster *cl = &s->clusters[c];
        const lie_emitter *em = &s->emitters[cl->emitter];
        float f[20] = {em->radiance[0], em->radiance[1], em->radiance[2], em->position.x, em->position.y,
                       em->position.z, em->direction.x, em->direction.y, em->direction.z, em->intensity[0],
                       em->intensity[1], em->intensity[2], em->cos_inner, em->cos_outer, em->range,
                       (float)em->double_sided, (float)cl->dark, (float)cl->n_tris, (float)lie_emitter_is_delta(em),
                       /* its emissive texture, which the renderer's set-up reads (lib/shade/texlight.c) */
                       em->n_tris ? (float)lie_scene_material(s, s->tri_material[em->first_tri])->emissive_tex : -2.0f};
        h = lie_hash_bytes(f, sizeof f, h);
        for (uint32_t k = 0; k < cl->n_tris; k++)
            h = lie_hash_bytes(&s->tri_p[3 * (size_t)s->cluster_tris[cl->first + k]], sizeof(lie_vec3) * 3, h);
    }
    return h;
}
