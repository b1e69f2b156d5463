/* SPDX-License-Identifier: Apache-2.0 */
/* Building a scene's document in memory: for tests, and for edits that
 * add objects. */
#include "scene/scene.h"

#include <stdlib.h>
#include <string.h>

lie_scene *lie_scene_new(const char *path)
{
    lie_scene *s = calloc(1, sizeof *s);
    if (!s)
        return NULL;
    s->path = strdup(path ? path : "");
    if (!s->path) {
        free(s);
        return NULL;
    }
    return s;
}

lie_material lie_material_default(void)
{
    lie_material m;
    memset(&m, 0, sizeof m);
    for (int k = 0; k < 4; k++)
        m.base_color[k] = 1.0f;
    m.metallic = 1.0f;
    m.roughness = 1.0f;
    m.base_color_tex = m.mr_tex = m.emissive_tex = m.normal_tex = m.transmission_tex = -1;
    m.normal_scale = 1.0f;
    m.alpha_cutoff = 0.5f;
    lie_material_tex_xf_identity(&m);
    return m;
}

void lie_material_tex_xf_identity(lie_material *m)
{
    for (int k = 0; k < LIE_TEX_SLOTS; k++) {
        const float id[5] = {0.0f, 0.0f, 0.0f, 1.0f, 1.0f};
        memcpy(m->tex_param[k], id, sizeof id);
    }
    lie_material_tex_xf_update(m);
}

/* KHR_texture_transform: uv' = T(offset) R(rotation) S(scale) uv, with
 * R = [cos sin; -sin cos] (a positive rotation turns the texture
 * counter-clockwise in uv space). */
void lie_material_tex_xf_update(lie_material *m)
{
    for (int k = 0; k < LIE_TEX_SLOTS; k++) {
        const float *p = m->tex_param[k];
        double c = cos((double)p[2]), s = sin((double)p[2]);
        float *x = m->tex_xf[k];
        x[0] = (float)(c * p[3]);
        x[1] = (float)(s * p[4]);
        x[2] = p[0];
        x[3] = (float)(-s * p[3]);
        x[4] = (float)(c * p[4]);
        x[5] = p[1];
    }
}

int lie_material_tex_xf_is_identity(const lie_material *m, int k)
{
    const float *p = m->tex_param[k];
    return p[0] == 0.0f && p[1] == 0.0f && p[2] == 0.0f && p[3] == 1.0f && p[4] == 1.0f;
}

/* Grow an array of `size`-byte elements by one; returns the new slot. */
static void *grow(void **arr, int *n, size_t size)
{
    void *na = realloc(*arr, size * ((size_t)*n + 1));
    if (!na)
        return NULL;
    *arr = na;
    void *slot = (char *)na + size * (size_t)*n;
    memset(slot, 0, size);
    (*n)++;
    return slot;
}

static char *dup_or_null(const char *s) { return s ? strdup(s) : NULL; }

int lie_scene_add_material(lie_scene *s, const lie_material *m)
{
    lie_material *slot = grow((void **)&s->materials, &s->n_materials, sizeof *slot);
    if (!slot)
        return -1;
    *slot = *m;
    slot->name = dup_or_null(m->name);
    return s->n_materials - 1;
}

static void *dup_array(const void *src, size_t bytes)
{
    if (!src)
        return NULL;
    void *d = malloc(bytes ? bytes : 1);
    if (d)
        memcpy(d, src, bytes);
    return d;
}

void lie_primitive_free(lie_primitive *p)
{
    free(p->pos);
    free(p->nrm);
    free(p->uv);
    free(p->uv1);
    free(p->color);
    free(p->tan);
    free(p->idx);
    free(p->base_pos);
    free(p->base_nrm);
    free(p->tpos);
    free(p->tnrm);
    free(p->joints);
    free(p->weights);
}

int lie_primitive_copy(const lie_primitive *src, lie_primitive *out)
{
    lie_primitive p = *src;
    p.pos = dup_array(src->pos, sizeof(float) * 3 * src->n_verts);
    p.nrm = dup_array(src->nrm, sizeof(float) * 3 * src->n_verts);
    p.uv = dup_array(src->uv, sizeof(float) * 2 * src->n_verts);
    p.uv1 = dup_array(src->uv1, sizeof(float) * 2 * src->n_verts);
    p.color = dup_array(src->color, sizeof(float) * 4 * src->n_verts);
    p.tan = dup_array(src->tan, sizeof(float) * 4 * src->n_verts);
    p.idx = dup_array(src->idx, sizeof(uint32_t) * 3 * src->n_tris);
    size_t tn = sizeof(float) * 3 * src->n_verts * (size_t)src->n_targets;
    p.base_pos = dup_array(src->base_pos, sizeof(float) * 3 * src->n_verts);
    p.base_nrm = dup_array(src->base_nrm, sizeof(float) * 3 * src->n_verts);
    p.tpos = dup_array(src->tpos, tn);
    p.tnrm = dup_array(src->tnrm, tn);
    p.joints = dup_array(src->joints, sizeof(uint16_t) * 4 * src->n_verts);
    p.weights = dup_array(src->weights, sizeof(float) * 4 * src->n_verts);
    if ((src->pos && !p.pos) || (src->nrm && !p.nrm) || (src->uv && !p.uv) || (src->uv1 && !p.uv1) ||
        (src->color && !p.color) || (src->tan && !p.tan) || (src->idx && !p.idx) || (src->base_pos && !p.base_pos) ||
        (src->base_nrm && !p.base_nrm) || (src->tpos && !p.tpos) || (src->tnrm && !p.tnrm) ||
        (src->joints && !p.joints) || (src->weights && !p.weights)) {
        lie_primitive_free(&p);
        return 0;
    }
    *out = p;
    return 1;
}

int lie_scene_add_mesh(lie_scene *s, const char *name, const float *pos, const float *nrm,
                       const float *uv, uint32_t n_verts, const uint32_t *idx, uint32_t n_tris,
                       int material)
{
    lie_primitive p;
    memset(&p, 0, sizeof p);
    p.n_verts = n_verts;
    p.n_tris = n_tris;
    p.material = material;
    p.pos = dup_array(pos, sizeof(float) * 3 * n_verts);
    p.nrm = dup_array(nrm, sizeof(float) * 3 * n_verts);
    p.uv = dup_array(uv, sizeof(float) * 2 * n_verts);
    p.idx = dup_array(idx, sizeof(uint32_t) * 3 * n_tris);
    lie_primitive *prim = malloc(sizeof *prim);
    if (!p.pos || (nrm && !p.nrm) || (uv && !p.uv) || !p.idx || !prim) {
        lie_primitive_free(&p);
        free(prim);
        return -1;
    }
    *prim = p;
    lie_mesh *m = grow((void **)&s->meshes, &s->n_meshes, sizeof *m);
    if (!m) {
        lie_primitive_free(&p);
        free(prim);
        return -1;
    }
    m->name = dup_or_null(name);
    m->prims = prim;
    m->n_prims = 1;
    return s->n_meshes - 1;
}

int lie_scene_add_light_def(lie_scene *s, const lie_light_def *l)
{
    lie_light_def *slot = grow((void **)&s->light_defs, &s->n_light_defs, sizeof *slot);
    if (!slot)
        return -1;
    *slot = *l;
    slot->name = dup_or_null(l->name);
    return s->n_light_defs - 1;
}

int lie_scene_add_node(lie_scene *s, const char *name, int parent, const lie_mat4 *local, int mesh,
                       int camera, int light)
{
    if (parent >= s->n_nodes)
        return -1;
    int *link;
    if (parent >= 0) {
        lie_node *p = &s->nodes[parent];
        link = grow((void **)&p->children, &p->n_children, sizeof *link);
    } else {
        link = grow((void **)&s->roots, &s->n_roots, sizeof *link);
    }
    if (!link)
        return -1;
    lie_node *n = grow((void **)&s->nodes, &s->n_nodes, sizeof *n);
    if (!n) {
        if (parent >= 0)
            s->nodes[parent].n_children--;
        else
            s->n_roots--;
        return -1;
    }
    *link = s->n_nodes - 1;
    n->name = dup_or_null(name);
    n->parent = parent;
    n->local = local ? *local : lie_mat4_identity();
    n->mesh = mesh;
    n->camera = camera;
    n->light = light;
    n->removed = 0;
    n->has_trs = 0;
    n->weights = NULL;
    n->n_weights = 0;
    n->skin = -1;
    n->children = NULL;
    n->n_children = 0;
    return s->n_nodes - 1;
}

lie_status lie_primitive_morph(lie_primitive *p, const double *w, int n_w)
{
    if (p->n_targets <= 0 || !p->base_pos)
        return LIE_OK;
    size_t n = 3 * (size_t)p->n_verts;
    memcpy(p->pos, p->base_pos, sizeof(float) * n);
    if (p->nrm && p->base_nrm)
        memcpy(p->nrm, p->base_nrm, sizeof(float) * n);
    int moved = 0;
    for (int t = 0; t < p->n_targets && t < n_w; t++) {
        if (w[t] == 0.0)
            continue;
        moved = 1;
        const float *dp = p->tpos + (size_t)t * n, *dn = p->tnrm ? p->tnrm + (size_t)t * n : NULL;
        for (size_t i = 0; i < n; i++)
            p->pos[i] = (float)((double)p->pos[i] + w[t] * (double)dp[i]);
        if (p->nrm && dn)
            for (size_t i = 0; i < n; i++)
                p->nrm[i] = (float)((double)p->nrm[i] + w[t] * (double)dn[i]);
    }
    for (size_t i = 0; moved && i < n; i++)
        if (!isfinite(p->pos[i]))
            return LIE_ERR_FORMAT;
    return LIE_OK;
}
