/* Convex solids among the scene's instances: a shadow segment that starts
 * and ends outside a closed convex mesh and crosses it enters through a face
 * that faces its start, so the faces turned away from a shading point that
 * sees one of the solid's front faces are redundant blockers (lie_vis.c). */
#include "shade/internal.h"

#include <stdlib.h>
#include <string.h>

/* Instances larger than this are not examined (the convexity test is
 * quadratic in their size). */
#define SOLID_MAX_TRIS 4096

typedef struct edge {
    float a[3], b[3]; /* endpoints, lower first (bitwise) */
    int dir;          /* +1 stored as a->b, -1 as b->a */
} edge;

static int cmp_pt(const float *p, const float *q) { return memcmp(p, q, 3 * sizeof(float)); }

static int cmp_edge(const void *x, const void *y)
{
    const edge *e = x, *f = y;
    int c = cmp_pt(e->a, f->a);
    return c ? c : cmp_pt(e->b, f->b);
}

/* Every edge used once in each direction: closed and consistently wound
 * (positions compared bit for bit, so a T-junction or a crack fails). */
static int closed(const lie_vec3 *P, uint32_t n_tris)
{
    size_t ne = 3 * (size_t)n_tris;
    edge *E = malloc(sizeof *E * ne);
    if (!E)
        return 0;
    for (size_t i = 0; i < ne; i++) {
        const lie_vec3 *p = &P[i], *q = &P[i % 3 == 2 ? i - 2 : i + 1];
        float u[3] = {p->x, p->y, p->z}, w[3] = {q->x, q->y, q->z};
        int c = cmp_pt(u, w);
        memcpy(E[i].a, c < 0 ? u : w, sizeof u);
        memcpy(E[i].b, c < 0 ? w : u, sizeof u);
        E[i].dir = c < 0 ? 1 : -1;
        if (c == 0) { /* a degenerate edge */
            free(E);
            return 0;
        }
    }
    qsort(E, ne, sizeof *E, cmp_edge);
    int ok = 1;
    for (size_t i = 0; i < ne && ok;) {
        size_t j = i;
        int sum = 0;
        while (j < ne && cmp_edge(&E[i], &E[j]) == 0)
            sum += E[j++].dir;
        ok = sum == 0;
        i = j;
    }
    free(E);
    return ok;
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

static int convex_solid(const lie_scene *s, const lie_instance *in)
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
    /* convex, normals outward: every vertex on or behind every face plane */
    const lie_vec3 *P = &s->tri_p[3 * (size_t)first];
    for (uint32_t t = first; t < first + n; t++) {
        lie_vec3 nrm = s->tri_ng[t];
        float d = lie_v3_dot(nrm, s->tri_p[3 * (size_t)t]);
        for (size_t k = 0; k < 3 * (size_t)n; k++)
            if (lie_v3_dot(nrm, P[k]) - d > tol)
                return 0;
    }
    if (!closed(P, n))
        return 0;
    /* every light outside it, so the segments end outside */
    for (int e = 0; e < s->n_emitters; e++) {
        const lie_emitter *em = &s->emitters[e];
        if (em->type == LIE_EMITTER_DIRECTIONAL)
            continue; /* its segments end far away */
        if (em->type == LIE_EMITTER_POINT) {
            if (!outside(s, first, n, &em->position, 1, tol))
                return 0;
            continue;
        }
        const lie_vec3 *pts = em->n_hull ? em->hull : &s->tri_p[3 * (size_t)em->first_tri];
        size_t np = em->n_hull ? (size_t)em->n_hull : 3 * (size_t)em->n_tris;
        if (!outside(s, first, n, pts, np, tol))
            return 0;
    }
    return 1;
}

int32_t *lie_convex_solids(const lie_scene *s)
{
    int32_t *id = malloc(sizeof *id * ((size_t)s->n_tris + 1));
    if (!id)
        return NULL;
    for (uint32_t t = 0; t < s->n_tris; t++)
        id[t] = -1;
    for (int i = 0; i < s->n_instances; i++) {
        const lie_instance *in = &s->instances[i];
        if (in->first_tri + (uint64_t)in->n_tris <= s->n_tris && convex_solid(s, in))
            for (uint32_t t = in->first_tri; t < in->first_tri + in->n_tris; t++)
                id[t] = i;
    }
    return id;
}
