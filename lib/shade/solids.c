/* SPDX-License-Identifier: Apache-2.0 */
/* Convex solids among the scene's instances: a shadow segment that starts
 * and ends outside a closed convex mesh and crosses it enters through a face
 * that faces its start, so the faces turned away from a shading point that
 * sees one of the solid's front faces are redundant blockers (lie_vis.c). */
#include "shade/internal.h"

#include <stdlib.h>
#include <string.h>

/* Instances larger than this are not examined (the convexity test takes
 * faces times distinct vertices). */
#define SOLID_MAX_TRIS 4096
#define CORNERS (3 * SOLID_MAX_TRIS)
#define SLOTS 32768 /* a power of two, at least twice CORNERS */

/* Scratch for one instance: its distinct vertices (positions compared bit
 * for bit) as three arrays, each corner's vertex id, and two open-addressing
 * tables: vertices, and undirected edges with their winding sums. */
typedef struct mesh_scratch {
    float x[CORNERS], y[CORNERS], z[CORNERS];
    uint32_t vid[CORNERS];
    uint32_t mask;          /* the tables' size in use, less one: a power of two >= 2 corners */
    uint32_t vslot[SLOTS];  /* vertex id + 1, 0 empty */
    uint64_t ekey[SLOTS];   /* lower id << 32 | higher id, 0 empty (ids differ) */
    int32_t esum[SLOTS];
} mesh_scratch;

static uint32_t bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

/* Number the distinct corner positions; returns how many. */
static uint32_t number_vertices(const lie_vec3 *P, uint32_t n, mesh_scratch *w)
{
    w->mask = 15;
    while (w->mask + 1 < 2 * n)
        w->mask = 2 * w->mask + 1;
    memset(w->vslot, 0, sizeof *w->vslot * (w->mask + 1));
    uint32_t nv = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t bx = bits(P[i].x), by = bits(P[i].y), bz = bits(P[i].z);
        uint32_t h = (uint32_t)lie_hash_u64x4(bx, by, bz, 0) & w->mask;
        for (;; h = (h + 1) & w->mask) {
            uint32_t v = w->vslot[h];
            if (v == 0) {
                w->vslot[h] = ++nv;
                w->x[nv - 1] = P[i].x;
                w->y[nv - 1] = P[i].y;
                w->z[nv - 1] = P[i].z;
                w->vid[i] = nv - 1;
                break;
            }
            if (bits(w->x[v - 1]) == bx && bits(w->y[v - 1]) == by && bits(w->z[v - 1]) == bz) {
                w->vid[i] = v - 1;
                break;
            }
        }
    }
    return nv;
}

/* Every edge used as often in one direction as in the other: closed and
 * consistently wound (by vertex ids, so a T-junction or a crack fails).
 * After number_vertices, whose table size it shares: the edges of a mesh
 * are no more than its corners. */
static int closed(uint32_t n_tris, mesh_scratch *w)
{
    memset(w->ekey, 0, sizeof *w->ekey * (w->mask + 1));
    for (uint32_t i = 0; i < 3 * n_tris; i++) {
        uint32_t a = w->vid[i], b = w->vid[i % 3 == 2 ? i - 2 : i + 1];
        if (a == b)
            return 0; /* a degenerate edge */
        uint64_t key = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        uint32_t h = (uint32_t)lie_hash_u64x4(key, 0, 0, 0) & w->mask;
        while (w->ekey[h] != 0 && w->ekey[h] != key)
            h = (h + 1) & w->mask;
        if (w->ekey[h] == 0) {
            w->ekey[h] = key;
            w->esum[h] = 0;
        }
        w->esum[h] += a < b ? 1 : -1;
    }
    for (uint32_t h = 0; h <= w->mask; h++)
        if (w->ekey[h] != 0 && w->esum[h] != 0)
            return 0;
    return 1;
}

/* max over the distinct vertices of n . p */
static float max_height(const mesh_scratch *w, uint32_t nv, lie_vec3 nrm)
{
    const float *restrict x = w->x, *restrict y = w->y, *restrict z = w->z;
    float m = -INFINITY;
#pragma omp simd reduction(max : m)
    for (uint32_t i = 0; i < nv; i++) {
        float h = nrm.x * x[i] + nrm.y * y[i] + nrm.z * z[i];
        m = h > m ? h : m;
    }
    return m;
}

/* Some face plane has every point strictly in front of it. */
static int outside(const lie_scene *s, uint32_t first, uint32_t n, const lie_vec3 *pts, size_t np, float tol)
{
    for (uint32_t t = first; t < first + n; t++) {
        lie_vec3 nrm = s->tri_ng[t];
        float d = lie_v3_dot(nrm, s->tri_p[3 * (size_t)t]);
        size_t k = 0;
        while (k < np && lie_v3_dot(nrm, pts[k]) - d > tol)
            k++;
        if (k == np)
            return 1;
    }
    return 0;
}

static int convex_solid(const lie_scene *s, const lie_instance *in, mesh_scratch *w)
{
    const uint32_t first = in->first_tri, n = in->n_tris;
    if (n < 4 || n > SOLID_MAX_TRIS)
        return 0;
    const lie_material *m = lie_scene_material(s, in->material);
    if (m->alpha_mask)
        return 0; /* holes */
    lie_box3 box = lie_box3_empty();
    for (uint32_t t = first; t < first + n; t++) {
        if (s->tri_removed[t] || !(s->tri_area[t] > 0.0f))
            return 0;
        for (int k = 0; k < 3; k++)
            lie_box3_grow(&box, s->tri_p[3 * (size_t)t + (size_t)k]);
    }
    float size = lie_v3_len(lie_v3_sub(box.hi, box.lo));
    if (!(size > 0.0f) || !isfinite(size))
        return 0;
    float tol = 1e-5f * size + 1e-6f * lie_v3_maxabs(box.hi) + 1e-6f * lie_v3_maxabs(box.lo);
    uint32_t nv = number_vertices(&s->tri_p[3 * (size_t)first], 3 * n, w);
    if (!closed(n, w))
        return 0;
    /* convex, normals outward: every vertex on or behind every face plane */
    for (uint32_t t = first; t < first + n; t++) {
        lie_vec3 nrm = s->tri_ng[t];
        float d = lie_v3_dot(nrm, s->tri_p[3 * (size_t)t]);
        if (max_height(w, nv, nrm) - d > tol)
            return 0;
    }
    /* every light outside it, so the segments end outside */
    for (int e = 0; e < s->n_emitters; e++) {
        const lie_vec3 *pts;
        int np = lie_emitter_extent(s, e, &pts);
        if (np > 0 && !outside(s, first, n, pts, (size_t)np, tol))
            return 0; /* a light at infinity (np 0): its segments end far away */
    }
    return 1;
}

int32_t *lie_solids_find(const lie_scene *s)
{
    int32_t *id = malloc(sizeof *id * ((size_t)s->n_tris + 1));
    if (!id)
        return NULL;
    for (uint32_t t = 0; t < s->n_tris; t++)
        id[t] = -1;
    mesh_scratch *w = malloc(sizeof *w);
    if (!w) {
        free(id);
        return NULL;
    }
    for (int i = 0; i < s->n_instances; i++) {
        const lie_instance *in = &s->instances[i];
        if (in->first_tri + (uint64_t)in->n_tris <= s->n_tris && convex_solid(s, in, w))
            for (uint32_t t = in->first_tri; t < in->first_tri + in->n_tris; t++)
                id[t] = i;
    }
    free(w);
    return id;
}
