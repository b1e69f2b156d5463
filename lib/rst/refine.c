/* Exact refinement of ray-segment-tree answers: the hull of a flagged
 * unit root's patch and emitter against the edit's boxes, then down its
 * patch tree while the hulls meet them. */
#include "rst/rst.h"

#include <stdlib.h>

typedef struct refine_ctx {
    const lie_scene *s;
    const lie_env *env;
    const lie_box3 *boxes;
    int n_boxes;
    uint8_t *flags;
    lie_vec3 *hull;
    uint64_t cleared;
} refine_ctx;

static void refine_node(refine_ctx *c, uint32_t node, uint32_t tri, lie_patch_path path, int e)
{
    if (!c->flags[node])
        return;
    lie_vec3 V[3];
    lie_patch_world(path, &c->s->tri_p[3 * (size_t)tri], V);
    int n = lie_pair_hull_points(c->s, tri, V, e, c->hull);
    int meets = 0;
    float tol = 1e-5f * fmaxf(1.0f, lie_v3_len(lie_v3_sub(c->s->bounds.hi, c->s->bounds.lo)));
    for (int b = 0; b < c->n_boxes && !meets; b++)
        meets = lie_pair_hull_meets_box(c->hull, n, c->boxes[b], tol);
    if (!meets) {
        c->flags[node] = 0; /* nor can its children's segments, all among its own */
        c->cleared++;
        return;
    }
    const lie_pnode *x = &c->env->nodes[node];
    if (x->child)
        for (uint32_t k = 0; k < 4; k++) {
            c->flags[x->child + k] = 1; /* a candidate, as its parent is */
            refine_node(c, x->child + k, tri, lie_patch_child(path, (int)k), e);
        }
}

uint64_t lie_rst_refine(const lie_scene *s, const lie_env *env, const lie_box3 *boxes, int n_boxes, uint8_t *flags)
{
    int cap = 0;
    for (int e = 0; e < s->n_clusters; e++)
        cap = cap > lie_pair_hull_cap(s, e) ? cap : lie_pair_hull_cap(s, e);
    refine_ctx c = {s, env, boxes, n_boxes, flags, malloc(sizeof(lie_vec3) * ((size_t)cap + 1)), 0};
    if (!c.hull) {
        lie_rst_spread(env, flags); /* out of memory: flag whole subtrees (still correct) */
        return 0;
    }
    for (uint32_t t = 0; t < env->n_tris; t++)
        for (int e = 0; e < env->n_clusters; e++)
            refine_node(&c, env->root[(size_t)t * (size_t)env->n_clusters + (size_t)e], t, lie_patch_root(), e);
    free(c.hull);
    return c.cleared;
}

static void spread_node(const lie_env *env, uint32_t node, uint8_t *flags)
{
    const lie_pnode *x = &env->nodes[node];
    if (!flags[node] || !x->child)
        return;
    for (uint32_t k = 0; k < 4; k++) {
        flags[x->child + k] = 1;
        spread_node(env, x->child + k, flags);
    }
}

void lie_rst_spread(const lie_env *env, uint8_t *flags)
{
    for (size_t u = 0; u < (size_t)env->n_tris * (size_t)env->n_clusters; u++)
        spread_node(env, env->root[u], flags);
}
