/* SPDX-License-Identifier: Apache-2.0 */
/* Applying edit operations to a scene's document.  Geometry changes edit
 * node transforms (in world space, about the node's own origin); material
 * changes give the node's subtree its own copies of meshes and materials,
 * so other instances sharing them are untouched; removal keeps triangle
 * slots; additions append new roots, so their triangles come last.
 * Size: just past the size CONTRIBUTING.md asks: every operation's effect,
 * and the copies (materials, meshes, lights) some need, in one place. */
#include "edit/edit.h"

#include <stdlib.h>
#include <string.h>

lie_status lie_edit_find_node(const lie_scene *s, const char *name, int *node, const char *file, int line, int col,
                              lie_error *err)
{
    if (name[0] == '#') {
        char *end;
        long i = strtol(name + 1, &end, 10);
        if (name[1] && !*end && i >= 0 && i < s->n_nodes) {
            *node = (int)i;
            return LIE_OK;
        }
        return lie_error_set_at(err, LIE_ERR_NOT_FOUND, file, line, col, "node '%s': the scene has nodes #0..#%d",
                                name, s->n_nodes - 1);
    }
    int found = -1, count = 0;
    for (int i = 0; i < s->n_nodes; i++)
        if (s->nodes[i].name && strcmp(s->nodes[i].name, name) == 0) {
            if (found < 0)
                found = i;
            count++;
        }
    if (count == 0)
        return lie_error_set_at(err, LIE_ERR_NOT_FOUND, file, line, col, "node '%s': no node has this name", name);
    if (count > 1)
        return lie_error_set_at(err, LIE_ERR_NOT_FOUND, file, line, col,
                                "node '%s': %d nodes have this name; use '#%d' or another index", name, count,
                                found);
    *node = found;
    return LIE_OK;
}

static lie_mat4 parent_world(const lie_scene *s, int node)
{
    int p = s->nodes[node].parent;
    return p >= 0 ? lie_node_world_matrix(s, p) : lie_mat4_identity();
}

/* Set the node's local transform so its world transform becomes W. */
static int set_world(lie_scene *s, int node, const lie_mat4 *W)
{
    lie_mat4 P = parent_world(s, node), Pi;
    if (!lie_mat4_inverse(&P, &Pi))
        return 0;
    s->nodes[node].local = lie_mat4_mul(&Pi, W);
    return 1;
}

static int push_int(int **arr, int *n, int v)
{
    for (int i = 0; i < *n; i++)
        if ((*arr)[i] == v)
            return 1;
    int *na = realloc(*arr, sizeof **arr * ((size_t)*n + 1));
    if (!na)
        return 0;
    na[(*n)++] = v;
    *arr = na;
    return 1;
}

/* The node and every descendant. */
static int collect_subtree(const lie_scene *s, int node, int **out, int *n)
{
    if (!push_int(out, n, node))
        return 0;
    for (int i = *n - 1; i < *n; i++) {
        const lie_node *nd = &s->nodes[(*out)[i]];
        for (int c = 0; c < nd->n_children; c++)
            if (nd->children[c] >= 0 && nd->children[c] < s->n_nodes && !push_int(out, n, nd->children[c]))
                return 0;
    }
    return 1;
}

void lie_edit_effect_free(lie_edit_effect *fx)
{
    if (!fx)
        return;
    free(fx->nodes);
    memset(fx, 0, sizeof *fx);
}

static void *dup_mem(const void *p, size_t n)
{
    if (!p)
        return NULL;
    void *d = malloc(n ? n : 1);
    if (d)
        memcpy(d, p, n);
    return d;
}

/* Give `node` its own copy of its mesh and of its primitives' materials;
 * returns 0 when out of memory. */
static int own_materials(lie_scene *s, int node)
{
    lie_node *nd = &s->nodes[node];
    if (nd->mesh < 0 || nd->mesh >= s->n_meshes)
        return 1;
    const lie_mesh *src = &s->meshes[nd->mesh];
    int np = src->n_prims;
    lie_primitive *prims = calloc((size_t)np + 1, sizeof *prims);
    if (!prims)
        return 0;
    for (int i = 0; i < np; i++) {
        const lie_primitive *q = &src->prims[i];
        int copied = lie_primitive_copy(q, &prims[i]);
        lie_material m = q->material >= 0 && q->material < s->n_materials ? s->materials[q->material]
                                                                           : lie_material_default();
        int mi = copied ? lie_scene_add_material(s, &m) : -1;
        prims[i].material = mi;
        if (mi < 0) {
            for (int k = 0; k < i + copied; k++)
                lie_primitive_free(&prims[k]);
            free(prims);
            return 0;
        }
    }
    lie_mesh *nm = realloc(s->meshes, sizeof *nm * ((size_t)s->n_meshes + 1));
    if (!nm) {
        for (int k = 0; k < np; k++)
            lie_primitive_free(&prims[k]);
        free(prims);
        return 0;
    }
    s->meshes = nm;
    lie_mesh *m = &s->meshes[s->n_meshes];
    m->name = s->meshes[nd->mesh].name ? strdup(s->meshes[nd->mesh].name) : NULL;
    m->prims = prims;
    m->n_prims = np;
    nd->mesh = s->n_meshes++;
    return 1;
}

/* Copy node `src_node` of scene `src` (with its subtree, meshes, materials,
 * textures and punctual lights) into `s` as a new root called `as`. */
static lie_status add_from(lie_scene *s, const lie_scene *src, int src_node, const char *as, const lie_mat4 *root_local,
                           int *new_root, lie_error *err, const char *file, int line, int col)
{
    int *sub = NULL, nsub = 0;
    if (!collect_subtree(src, src_node, &sub, &nsub))
        return lie_error_set(err, LIE_ERR_NOMEM, file, "out of memory");
    int tex_base = s->n_textures, mat_base = s->n_materials;
    /* textures and materials: copied whole (the few unused ones cost little) */
    if (src->n_textures) {
        lie_texture *nt = realloc(s->textures, sizeof *nt * ((size_t)s->n_textures + (size_t)src->n_textures));
        if (!nt) {
            free(sub);
            return lie_error_set(err, LIE_ERR_NOMEM, file, "out of memory");
        }
        s->textures = nt;
        for (int i = 0; i < src->n_textures; i++) {
            lie_texture t = src->textures[i];
            t.image = -1; /* its file's image stays with its file: written as decoded */
            /* as floats: written back as PNG codes (lib/export) from them */
            size_t n = (size_t)t.width * (size_t)t.height;
            if (t.rgba || !lie_texture_has_texels(&t)) {
                t.rgba = dup_mem(t.rgba, sizeof(float) * 4 * n);
            } else {
                t.rgba = malloc(sizeof(float) * 4 * n);
                for (size_t k = 0; t.rgba && k < n; k++)
                    lie_texture_texel(&src->textures[i], k, t.rgba + 4 * k);
            }
            t.codes = NULL;
            t.code_value[0] = t.code_value[1] = NULL;
            if (!t.rgba) {
                free(sub);
                return lie_error_set(err, LIE_ERR_NOMEM, file, "out of memory");
            }
            s->textures[s->n_textures++] = t;
        }
    }
    for (int i = 0; i < src->n_materials; i++) {
        lie_material m = src->materials[i];
        if (m.base_color_tex >= 0)
            m.base_color_tex += tex_base;
        if (m.mr_tex >= 0)
            m.mr_tex += tex_base;
        if (m.emissive_tex >= 0)
            m.emissive_tex += tex_base;
        if (m.normal_tex >= 0)
            m.normal_tex += tex_base;
        if (m.transmission_tex >= 0)
            m.transmission_tex += tex_base;
        if (lie_scene_add_material(s, &m) < 0) {
            free(sub);
            return lie_error_set(err, LIE_ERR_NOMEM, file, "out of memory");
        }
    }
    int node_base = s->n_nodes;
    lie_status st = LIE_OK;
    for (int k = 0; k < nsub && st == LIE_OK; k++) {
        const lie_node *sn = &src->nodes[sub[k]];
        int mesh = -1, light = -1;
        if (sn->mesh >= 0 && sn->mesh < src->n_meshes) {
            const lie_mesh *m = &src->meshes[sn->mesh];
            for (int pi = 0; pi < m->n_prims && st == LIE_OK; pi++) {
                const lie_primitive *q = &m->prims[pi];
                int mat = q->material >= 0 ? q->material + mat_base : -1;
                int mi;
                if (pi == 0) {
                    mi = lie_scene_add_mesh(s, m->name, q->pos, q->nrm, q->uv, q->n_verts, q->idx, q->n_tris, mat);
                    mesh = mi;
                    if (mi >= 0 && q->color) {
                        lie_primitive *dp = &s->meshes[mi].prims[0];
                        dp->color = dup_mem(q->color, sizeof(float) * 4 * q->n_verts);
                        if (!dp->color)
                            mi = -1;
                    }
                    if (mi >= 0 && q->uv1) {
                        lie_primitive *dp = &s->meshes[mi].prims[0];
                        dp->uv1 = dup_mem(q->uv1, sizeof(float) * 2 * q->n_verts);
                        if (!dp->uv1)
                            mi = -1;
                    }
                    if (mi >= 0 && q->tan) {
                        lie_primitive *dp = &s->meshes[mi].prims[0];
                        dp->tan = dup_mem(q->tan, sizeof(float) * 4 * q->n_verts);
                        if (!dp->tan)
                            mi = -1;
                    }
                } else {
                    /* further primitives join the same mesh */
                    lie_mesh *dst = &s->meshes[mesh];
                    lie_primitive *np = realloc(dst->prims, sizeof *np * ((size_t)dst->n_prims + 1));
                    mi = -1;
                    if (np) {
                        dst->prims = np;
                        lie_primitive c;
                        if (lie_primitive_copy(q, &c)) {
                            c.material = mat;
                            dst->prims[dst->n_prims++] = c;
                            mi = mesh;
                        }
                    }
                }
                if (mi < 0)
                    st = lie_error_set(err, LIE_ERR_NOMEM, file, "out of memory");
            }
        }
        if (st == LIE_OK && sn->light >= 0 && sn->light < src->n_light_defs)
            light = lie_scene_add_light_def(s, &src->light_defs[sn->light]);
        /* parent: the copy of the source parent, or a new root */
        int parent = -1;
        if (k > 0)
            for (int j = 0; j < k; j++)
                if (sub[j] == sn->parent)
                    parent = node_base + j;
        const lie_mat4 *local = k == 0 ? root_local : &sn->local;
        const char *name = k == 0 ? as : sn->name;
        if (st == LIE_OK && lie_scene_add_node(s, name, parent, local, mesh, -1, light) < 0)
            st = lie_error_set(err, LIE_ERR_NOMEM, file, "out of memory");
    }
    free(sub);
    (void)line;
    (void)col;
    *new_root = node_base;
    return st;
}

static int is_joint(const lie_scene *s, int node)
{
    for (int k = 0; k < s->n_skins; k++)
        for (int j = 0; j < s->skins[k].n_joints; j++)
            if (s->skins[k].joints[j] == node)
                return 1;
    return 0;
}

int lie_edit_transform_matters(const lie_scene *s, int node)
{
    int *sub = NULL, nsub = 0, any = 0;
    if (!collect_subtree(s, node, &sub, &nsub)) {
        free(sub);
        return 1; /* out of memory: let the edit go ahead */
    }
    for (int k = 0; k < nsub && !any; k++) {
        const lie_node *nd = &s->nodes[sub[k]];
        /* a skinned mesh follows its joints, not its node (glTF 2.0 §3.7.3.3) */
        any = (nd->mesh >= 0 && nd->skin < 0) || nd->light >= 0 || nd->camera >= 0 || is_joint(s, sub[k]);
    }
    free(sub);
    return any;
}

/* Push every live node whose skin has a joint among sub[0..nsub). */
static int push_skinned(const lie_scene *s, const int *sub, int nsub, lie_edit_effect *fx)
{
    for (int i = 0; i < s->n_nodes; i++) {
        const lie_node *nd = &s->nodes[i];
        if (nd->skin < 0 || nd->skin >= s->n_skins || nd->mesh < 0)
            continue;
        const lie_skin *sk = &s->skins[nd->skin];
        int hit = 0;
        for (int j = 0; j < sk->n_joints && !hit; j++)
            for (int k = 0; k < nsub && !hit; k++)
                hit = sk->joints[j] == sub[k];
        if (hit && !push_int(&fx->nodes, &fx->n_nodes, i))
            return 0;
    }
    return 1;
}

/* Give `node` a mesh no other node draws (a copy when shared); 0 when out of memory. */
static int own_mesh(lie_scene *s, int node)
{
    int mi = s->nodes[node].mesh, shared = 0;
    for (int i = 0; i < s->n_nodes && !shared; i++)
        shared = i != node && s->nodes[i].mesh == mi;
    if (!shared)
        return 1;
    const lie_mesh *src = &s->meshes[mi];
    lie_primitive *prims = calloc((size_t)src->n_prims + 1, sizeof *prims);
    if (!prims)
        return 0;
    for (int i = 0; i < src->n_prims; i++)
        if (!lie_primitive_copy(&src->prims[i], &prims[i])) {
            for (int k = 0; k < i; k++)
                lie_primitive_free(&prims[k]);
            free(prims);
            return 0;
        }
    lie_mesh *nm = realloc(s->meshes, sizeof *nm * ((size_t)s->n_meshes + 1));
    if (!nm) {
        for (int k = 0; k < src->n_prims; k++)
            lie_primitive_free(&prims[k]);
        free(prims);
        return 0;
    }
    s->meshes = nm;
    lie_mesh *m = &s->meshes[s->n_meshes];
    m->name = s->meshes[mi].name ? strdup(s->meshes[mi].name) : NULL;
    m->prims = prims;
    m->n_prims = s->meshes[mi].n_prims;
    s->nodes[node].mesh = s->n_meshes++;
    return 1;
}

/* set-weights: the node's own mesh morphed with the new weights. */
static lie_status set_weights(lie_scene *s, const char *file, const lie_edit_op *op, int node, int *changed,
                              lie_error *err)
{
    lie_node *nd = &s->nodes[node];
    *changed = 0;
    if (nd->mesh < 0 || nd->n_weights == 0)
        return lie_error_set_at(err, LIE_ERR_FORMAT, file, op->line, op->col,
                                "set-weights: node '%s' has no mesh with morph targets", op->node);
    if (op->n_weights != nd->n_weights)
        return lie_error_set_at(err, LIE_ERR_FORMAT, file, op->line, op->col,
                                "set-weights.weights: %d weights, node '%s' has %d morph targets", op->n_weights,
                                op->node, nd->n_weights);
    if (memcmp(nd->weights, op->weights, sizeof(double) * (size_t)op->n_weights) == 0)
        return LIE_OK;
    if (!own_mesh(s, node))
        return lie_error_set(err, LIE_ERR_NOMEM, file, "out of memory");
    nd = &s->nodes[node];
    memcpy(nd->weights, op->weights, sizeof(double) * (size_t)op->n_weights);
    lie_mesh *m = &s->meshes[nd->mesh];
    for (int pi = 0; pi < m->n_prims; pi++)
        if (lie_primitive_morph(&m->prims[pi], nd->weights, nd->n_weights) != LIE_OK)
            return lie_error_set_at(err, LIE_ERR_FORMAT, file, op->line, op->col,
                                    "set-weights: node '%s': a morphed position is not a finite number", op->node);
    *changed = 1;
    return LIE_OK;
}

/* set-light: KHR_lights_punctual colour, intensity, range and spot cones
 * of the node's light (its own copy when other nodes share it). */
static lie_status set_light(lie_scene *s, const char *file, const lie_edit_op *op, int node, lie_error *err)
{
    lie_node *nd = &s->nodes[node];
    if (nd->light < 0 || nd->light >= s->n_light_defs)
        return lie_error_set_at(err, LIE_ERR_FORMAT, file, op->line, op->col,
                                "set-light: node '%s' has no KHR_lights_punctual light%s", op->node,
                                nd->mesh >= 0 ? " (an emissive mesh is changed by set-emission)" : "");
    lie_light_def l = s->light_defs[nd->light];
    static const char *const type_name[3] = {"point", "spot", "directional"};
    if ((op->has & (LIE_EDIT_HAS_INNER | LIE_EDIT_HAS_OUTER)) && l.type != LIE_LIGHT_SPOT)
        return lie_error_set_at(err, LIE_ERR_FORMAT, file, op->line, op->col,
                                "set-light: node '%s' holds a %s light, which has no cone", op->node,
                                type_name[l.type]);
    if ((op->has & LIE_EDIT_HAS_RANGE) && l.type == LIE_LIGHT_DIRECTIONAL)
        return lie_error_set_at(err, LIE_ERR_FORMAT, file, op->line, op->col,
                                "set-light.range: node '%s' holds a directional light, which has no range", op->node);
    if (op->has & LIE_EDIT_HAS_COLOR)
        memcpy(l.color, op->color, sizeof l.color);
    if (op->has & LIE_EDIT_HAS_INTENSITY)
        l.intensity = op->intensity;
    if (op->has & LIE_EDIT_HAS_RANGE)
        l.range = op->range;
    if (op->has & LIE_EDIT_HAS_INNER)
        l.inner_cone = (float)(op->inner_deg * M_PI / 180.0);
    if (op->has & LIE_EDIT_HAS_OUTER)
        l.outer_cone = (float)(op->outer_deg * M_PI / 180.0);
    if (l.type == LIE_LIGHT_SPOT && !(l.inner_cone >= 0.0f && l.inner_cone < l.outer_cone))
        return lie_error_set_at(err, LIE_ERR_FORMAT, file, op->line, op->col,
                                "set-light: node '%s': the inner cone must be smaller than the outer one", op->node);
    int shared = 0;
    for (int i = 0; i < s->n_nodes && !shared; i++)
        shared = i != node && s->nodes[i].light == nd->light;
    if (shared) {
        l.name = l.name ? strdup(l.name) : NULL;
        int li = lie_scene_add_light_def(s, &l);
        free(l.name);
        if (li < 0)
            return lie_error_set(err, LIE_ERR_NOMEM, file, "out of memory");
        s->nodes[node].light = li;
    } else {
        l.name = s->light_defs[nd->light].name;
        s->light_defs[nd->light] = l;
    }
    return LIE_OK;
}

int lie_edit_add_path(const lie_edit *e, const lie_edit_op *op, char *path, size_t cap)
{
    const char *slash = strrchr(e->name, '/');
    int n = op->file[0] != '/' && slash ? snprintf(path, cap, "%.*s/%s", (int)(slash - e->name), e->name, op->file)
                                        : snprintf(path, cap, "%s", op->file);
    return n >= 0 && (size_t)n < cap;
}

/* Apply one operation.  One piece: the checks every operation shares (the
 * node found, not removed, a transform that moves something), one case per
 * operation of formats/edit.md, and the effect they share (the subtree's
 * nodes for the update, `geometry` unless the case cleared it); the cases
 * that grew (set-weights, set-light, add's copy) are functions of their own. */
static lie_status apply_op(lie_scene *s, const lie_edit *e, const lie_edit_op *op, const lie_scene_options *opt,
                           lie_edit_effect *fx, lie_error *err)
{
    const char *file = e->name;
    int node = -1;
    lie_status st;
    if (op->kind != LIE_EDIT_ADD) {
        st = lie_edit_find_node(s, op->node, &node, file, op->line, op->col, err);
        if (st != LIE_OK)
            return st;
        if (s->nodes[node].removed && op->kind != LIE_EDIT_RESTORE)
            return lie_error_set_at(err, LIE_ERR_NOT_FOUND, file, op->line, op->col,
                                    "node '%s' was removed by an earlier edit", op->node);
        if (!s->nodes[node].removed && op->kind == LIE_EDIT_RESTORE)
            return lie_error_set_at(err, LIE_ERR_FORMAT, file, op->line, op->col,
                                    "restore: node '%s' was not removed", op->node);
    }
    int geometry = 1;
    if ((op->kind == LIE_EDIT_MOVE_BY || op->kind == LIE_EDIT_MOVE_TO || op->kind == LIE_EDIT_ROTATE ||
         op->kind == LIE_EDIT_SCALE || op->kind == LIE_EDIT_SET_TRANSFORM) &&
        !lie_edit_transform_matters(s, node))
        return lie_error_set_at(err, LIE_ERR_FORMAT, file, op->line, op->col,
                                "node '%s': nothing a transform moves is in its subtree (no unskinned mesh, light, "
                                "camera or skin joint)",
                                op->node);
    switch (op->kind) {
    case LIE_EDIT_MOVE_BY:
    case LIE_EDIT_MOVE_TO: {
        lie_mat4 W = lie_node_world_matrix(s, node);
        double by[3] = {op->v[0], op->v[1], op->v[2]};
        if (op->kind == LIE_EDIT_MOVE_TO)
            for (int k = 0; k < 3; k++)
                by[k] = op->v[k] - W.m[12 + k];
        lie_mat4 T = lie_mat4_translation(by[0], by[1], by[2]);
        lie_mat4 W2 = lie_mat4_mul(&T, &W);
        if (!set_world(s, node, &W2))
            return lie_error_set_at(err, LIE_ERR_FORMAT, file, op->line, op->col,
                                    "node '%s': its parent's transform is singular", op->node);
        break;
    }
    case LIE_EDIT_ROTATE: {
        lie_mat4 W = lie_node_world_matrix(s, node);
        lie_mat4 to = lie_mat4_translation(-W.m[12], -W.m[13], -W.m[14]);
        lie_mat4 back = lie_mat4_translation(W.m[12], W.m[13], W.m[14]);
        lie_mat4 R = lie_mat4_rotation(op->v, op->degrees * M_PI / 180.0);
        lie_mat4 a = lie_mat4_mul(&R, &to), b = lie_mat4_mul(&back, &a), W2 = lie_mat4_mul(&b, &W);
        if (!set_world(s, node, &W2))
            return lie_error_set_at(err, LIE_ERR_FORMAT, file, op->line, op->col,
                                    "node '%s': its parent's transform is singular", op->node);
        break;
    }
    case LIE_EDIT_SCALE: {
        lie_mat4 S = lie_mat4_identity();
        S.m[0] = op->v[0];
        S.m[5] = op->v[1];
        S.m[10] = op->v[2];
        s->nodes[node].local = lie_mat4_mul(&s->nodes[node].local, &S);
        break;
    }
    case LIE_EDIT_SET_TRANSFORM:
        /* an absolute transform equal to the node's own moves nothing (lie-animate's frames) */
        geometry = memcmp(s->nodes[node].local.m, op->matrix, sizeof op->matrix) != 0;
        memcpy(s->nodes[node].local.m, op->matrix, sizeof op->matrix);
        break;
    case LIE_EDIT_SET_WEIGHTS:
        st = set_weights(s, file, op, node, &geometry, err);
        if (st != LIE_OK)
            return st;
        break;
    case LIE_EDIT_SET_LIGHT:
        /* Blocker lists do not depend on a light's colour or intensity.  Its
         * range and outer cone decide which pairs it reaches (unlit pairs,
         * lie_emitter_can_reach), so an edit of them rebuilds its pairs. */
        geometry = (op->has & (LIE_EDIT_HAS_RANGE | LIE_EDIT_HAS_OUTER)) != 0;
        st = set_light(s, file, op, node, err);
        if (st != LIE_OK)
            return st;
        break;
    case LIE_EDIT_REMOVE:
        s->nodes[node].removed = 1;
        break;
    case LIE_EDIT_RESTORE:
        s->nodes[node].removed = 0; /* its triangles kept their slots (see remove) */
        break;
    case LIE_EDIT_ADD: {
        int dup = 0;
        for (int i = 0; i < s->n_nodes; i++)
            dup |= s->nodes[i].name && strcmp(s->nodes[i].name, op->as) == 0;
        if (dup)
            return lie_error_set_at(err, LIE_ERR_FORMAT, file, op->line, op->col,
                                    "add.as: a node named '%s' exists already", op->as);
        char path[4096];
        if (!lie_edit_add_path(e, op, path, sizeof path))
            return lie_error_set_at(err, LIE_ERR_LIMIT, file, op->line, op->col, "add.file: the path is too long");
        lie_scene *src = NULL;
        lie_error sub;
        lie_error_clear(&sub);
        if (lie_scene_load(path, opt, &src, &sub) != LIE_OK)
            return lie_error_set_at(err, sub.status, file, op->line, op->col, "add.file: %s: %s", path, sub.msg);
        int src_node;
        st = lie_edit_find_node(src, op->node, &src_node, file, op->line, op->col, err);
        if (st == LIE_OK) {
            lie_mat4 local = (op->has & LIE_EDIT_HAS_TRANSFORM) ? lie_mat4_identity() : lie_node_world_matrix(src, src_node);
            if (op->has & LIE_EDIT_HAS_TRANSFORM)
                memcpy(local.m, op->matrix, sizeof local.m);
            st = add_from(s, src, src_node, op->as, &local, &node, err, file, op->line, op->col);
        }
        lie_scene_destroy(src);
        if (st != LIE_OK)
            return st;
        break;
    }
    case LIE_EDIT_SET_MATERIAL:
    case LIE_EDIT_SET_EMISSION: {
        geometry = 0;
        int *sub = NULL, nsub = 0;
        if (!collect_subtree(s, node, &sub, &nsub))
            return lie_error_set(err, LIE_ERR_NOMEM, file, "out of memory");
        int meshes = 0;
        for (int k = 0; k < nsub; k++)
            meshes += s->nodes[sub[k]].mesh >= 0;
        if (!meshes) {
            free(sub);
            int light = s->nodes[node].light >= 0;
            return lie_error_set_at(err, LIE_ERR_FORMAT, file, op->line, op->col,
                                    "%s: node '%s' has no mesh in its subtree%s",
                                    op->kind == LIE_EDIT_SET_EMISSION ? "set-emission" : "set-material", op->node,
                                    light ? " (it holds a KHR_lights_punctual light: use set-light)" : "");
        }
        if (op->has & LIE_EDIT_HAS_PRIMITIVE) {
            /* one primitive of the node's own mesh, not its subtree */
            int own = s->nodes[node].mesh >= 0 ? s->meshes[s->nodes[node].mesh].n_prims : 0;
            if (op->primitive >= own) {
                free(sub);
                return lie_error_set_at(err, LIE_ERR_FORMAT, file, op->line, op->col,
                                        "%s: node '%s' has %d primitive%s in its own mesh, no primitive %d",
                                        op->kind == LIE_EDIT_SET_EMISSION ? "set-emission" : "set-material", op->node,
                                        own, own == 1 ? "" : "s", op->primitive);
            }
            sub[0] = node;
            nsub = 1;
        }
        for (int k = 0; k < nsub; k++) {
            int nd = sub[k];
            if (s->nodes[nd].mesh < 0)
                continue;
            if (!own_materials(s, nd)) {
                free(sub);
                return lie_error_set(err, LIE_ERR_NOMEM, file, "out of memory");
            }
            const lie_mesh *m = &s->meshes[s->nodes[nd].mesh];
            for (int pi = 0; pi < m->n_prims; pi++) {
                if ((op->has & LIE_EDIT_HAS_PRIMITIVE) && pi != op->primitive)
                    continue;
                lie_material *mat = &s->materials[m->prims[pi].material];
                if (op->has & LIE_EDIT_HAS_BASE_COLOR) {
                    memcpy(mat->base_color, op->base_color, sizeof op->base_color);
                    mat->base_color_tex = -1;
                }
                if (op->has & LIE_EDIT_HAS_METALLIC)
                    mat->metallic = op->metallic;
                if (op->has & LIE_EDIT_HAS_ROUGHNESS)
                    mat->roughness = op->roughness;
                if (op->kind == LIE_EDIT_SET_EMISSION) {
                    /* emissive colour times strength; one given alone keeps the other */
                    float peak = fmaxf(mat->emissive[0], fmaxf(mat->emissive[1], mat->emissive[2]));
                    float colour[3], strength = peak;
                    for (int c = 0; c < 3; c++)
                        colour[c] = peak > 0.0f ? mat->emissive[c] / peak : 1.0f;
                    if (op->has & LIE_EDIT_HAS_EMISSIVE) {
                        memcpy(colour, op->emissive, sizeof colour);
                        if (!(op->has & LIE_EDIT_HAS_STRENGTH))
                            strength = 1.0f;
                    }
                    if (op->has & LIE_EDIT_HAS_STRENGTH)
                        strength = op->strength;
                    for (int c = 0; c < 3; c++)
                        mat->emissive[c] = colour[c] * strength;
                    mat->emissive_tex = -1;
                }
            }
        }
        free(sub);
        break;
    }
    }
    if (geometry && fx) {
        int *sub = NULL, nsub = 0;
        int ok = collect_subtree(s, node, &sub, &nsub);
        for (int k = 0; ok && k < nsub; k++)
            ok = push_int(&fx->nodes, &fx->n_nodes, sub[k]);
        /* a joint's edit is an edit of every mesh its skin deforms */
        ok = ok && push_skinned(s, sub, nsub, fx);
        free(sub);
        if (!ok)
            return lie_error_set(err, LIE_ERR_NOMEM, file, "out of memory");
    }
    return LIE_OK;
}

lie_status lie_edit_apply(lie_scene *s, const lie_edit *e, const lie_scene_options *opt, lie_edit_effect *fx,
                          lie_error *err)
{
    for (int i = 0; i < e->n_ops; i++) {
        lie_status st = apply_op(s, e, &e->ops[i], opt, fx, err);
        if (st != LIE_OK)
            return st;
    }
    lie_status st = lie_scene_flatten(s, err);
    /* the edits made the world what it is: they are the input to blame */
    if (st != LIE_OK && err && st != LIE_ERR_NOMEM) {
        char msg[sizeof err->msg];
        snprintf(msg, sizeof msg, "%s", err->msg);
        lie_error_set(err, st, e->name, "the edited scene: %s", msg);
    }
    return st;
}
