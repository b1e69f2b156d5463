/* SPDX-License-Identifier: Apache-2.0 */
/* The inverse of an edit: the operations restoring what it is about to
 * change, in absolute values, so that their order does not matter:
 *   - move, rotate, scale, set-transform: the node's local transform
 *     (set-transform, once per node);
 *   - set-material, set-emission: per mesh node of the subtree, each
 *     primitive's own material (`primitive: K`): colour, metallic,
 *     roughness and emission (set-material, then set-emission); a base
 *     colour texture that set-material dropped stays dropped;
 *   - remove: restore; restore: remove;
 *   - set-weights: the node's weights; set-light: the light's fields.
 * Nodes are named '#index', which names them alone whatever their names.
 * add has no inverse in formats/edit.md (no operation takes an added
 * object out again). */
#include "edit/internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* in[i] = 1 for node and its descendants (by the parent links) */
static void mark_subtree(const lie_scene *s, int node, uint8_t *in)
{
    memset(in, 0, (size_t)s->n_nodes);
    for (int i = 0; i < s->n_nodes; i++)
        for (int a = i, guard = 0; a >= 0 && guard <= s->n_nodes; a = s->nodes[a].parent, guard++)
            if (a == node) {
                in[i] = 1;
                break;
            }
}

typedef struct inverse_state {
    const lie_scene *s;
    lie_edit *out;
    uint8_t *done_tf, *done_mat, *in;
} inverse_state;

static lie_status push(inverse_state *v, lie_edit_op op, lie_error *err)
{
    return lie_edit_append(v->out, &op, err);
}

/* every primitive's material of every mesh node in node's subtree, as it is */
static lie_status restore_materials(inverse_state *v, int node, lie_error *err)
{
    const lie_scene *s = v->s;
    mark_subtree(s, node, v->in);
    lie_status st = LIE_OK;
    for (int n = 0; st == LIE_OK && n < s->n_nodes; n++) {
        if (!v->in[n] || v->done_mat[n] || s->nodes[n].mesh < 0 || s->meshes[s->nodes[n].mesh].n_prims == 0)
            continue;
        v->done_mat[n] = 1;
        char ref[24];
        snprintf(ref, sizeof ref, "#%d", n);
        const lie_mesh *mesh = &s->meshes[s->nodes[n].mesh];
        for (int pi = 0; st == LIE_OK && pi < mesh->n_prims; pi++) {
            const lie_material *m = lie_scene_material(s, mesh->prims[pi].material);
            float peak = fmaxf(m->emissive[0], fmaxf(m->emissive[1], m->emissive[2]));
            lie_edit_op mat = lie_edit_op_set_material(
                ref, LIE_EDIT_HAS_BASE_COLOR | LIE_EDIT_HAS_METALLIC | LIE_EDIT_HAS_ROUGHNESS, m->base_color,
                m->metallic, m->roughness);
            mat.primitive = pi;
            mat.has |= LIE_EDIT_HAS_PRIMITIVE;
            st = push(v, mat, err);
            float colour[3] = {0.0f, 0.0f, 0.0f};
            if (peak > 0.0f)
                for (int c = 0; c < 3; c++)
                    colour[c] = m->emissive[c] / peak;
            lie_edit_op em =
                lie_edit_op_set_emission(ref, LIE_EDIT_HAS_EMISSIVE | (peak > 0.0f ? LIE_EDIT_HAS_STRENGTH : 0), colour, peak);
            em.primitive = pi;
            em.has |= LIE_EDIT_HAS_PRIMITIVE;
            if (st == LIE_OK)
                st = push(v, em, err);
        }
    }
    return st;
}

static lie_status restore_light(inverse_state *v, int node, const char *ref, lie_error *err)
{
    const lie_scene *s = v->s;
    int l = s->nodes[node].light;
    if (l < 0 || l >= s->n_light_defs)
        return LIE_OK; /* the edit itself will fail */
    const lie_light_def *d = &s->light_defs[l];
    unsigned has = LIE_EDIT_HAS_COLOR | LIE_EDIT_HAS_INTENSITY | LIE_EDIT_HAS_RANGE;
    float inner = (float)(d->inner_cone * 180.0 / M_PI), outer = (float)(d->outer_cone * 180.0 / M_PI);
    if (d->type == LIE_LIGHT_SPOT)
        has |= LIE_EDIT_HAS_INNER | LIE_EDIT_HAS_OUTER;
    return push(v, lie_edit_op_set_light(ref, has, d->color, d->intensity, d->range, inner, outer), err);
}

static lie_status inverse_op(inverse_state *v, const lie_edit *e, const lie_edit_op *op, lie_error *err)
{
    const lie_scene *s = v->s;
    int node;
    lie_error miss;
    if (lie_edit_find_node(s, op->node, &node, e->name, op->line, op->col, &miss) != LIE_OK)
        return LIE_OK; /* the edit itself fails on it */
    char ref[24];
    snprintf(ref, sizeof ref, "#%d", node);
    switch (op->kind) {
    case LIE_EDIT_REMOVE:
        return push(v, lie_edit_op_restore(ref), err);
    case LIE_EDIT_RESTORE:
        return push(v, lie_edit_op_remove(ref), err);
    case LIE_EDIT_SET_MATERIAL:
    case LIE_EDIT_SET_EMISSION:
        return restore_materials(v, node, err);
    case LIE_EDIT_SET_WEIGHTS:
        if (s->nodes[node].n_weights <= 0)
            return LIE_OK; /* the edit itself fails on a mesh without targets */
        return push(v, lie_edit_op_set_weights(ref, s->nodes[node].weights, s->nodes[node].n_weights), err);
    case LIE_EDIT_SET_LIGHT:
        return restore_light(v, node, ref, err);
    default:
        if (v->done_tf[node])
            return LIE_OK;
        v->done_tf[node] = 1;
        return push(v, lie_edit_op_set_transform(ref, s->nodes[node].local.m), err);
    }
}

lie_status lie_edit_inverse(const lie_scene *s, const lie_edit *e, lie_edit **out, lie_error *err)
{
    *out = NULL;
    for (int i = 0; i < e->n_ops; i++)
        if (e->ops[i].kind == LIE_EDIT_ADD)
            return lie_error_set_at(err, LIE_ERR_UNSUPPORTED, e->name, e->ops[i].line, e->ops[i].col,
                                    "add has no inverse (formats/edit.md has no edit that takes an object out again)");
    inverse_state v = {s, lie_edit_create(e->name), calloc((size_t)s->n_nodes + 1, 1),
                       calloc((size_t)s->n_nodes + 1, 1), calloc((size_t)s->n_nodes + 1, 1)};
    lie_status st = v.out && v.done_tf && v.done_mat && v.in ? LIE_OK
                                                             : lie_error_set(err, LIE_ERR_NOMEM, e->name, "out of memory");
    for (int i = 0; st == LIE_OK && i < e->n_ops; i++)
        st = inverse_op(&v, e, &e->ops[i], err);
    free(v.done_tf);
    free(v.done_mat);
    free(v.in);
    if (st != LIE_OK) {
        lie_edit_destroy(v.out);
        return st;
    }
    *out = v.out;
    return LIE_OK;
}
