/* SPDX-License-Identifier: Apache-2.0 */
/* The scene: loading (through the glTF importer), flattening the node
 * hierarchy into world-space triangles, emitters and cameras, and the
 * content hash that caches refer to.
 * Size: one job, the world made from the document: loading, flattening and
 * hashing share the fill context and the per-triangle arrays. */
#include "scene/internal.h"

#include <stdlib.h>
#include <string.h>

#define LIE_XF_ID_PARAM {0.0f, 0.0f, 0.0f, 1.0f, 1.0f}
#define LIE_XF_ID {1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f}
static const lie_material default_material = {
    /* glTF 2.0 §3.9.6: the default material is white, metallic 1, roughness 1. */
    .name = NULL,
    .base_color = {1.0f, 1.0f, 1.0f, 1.0f},
    .base_color_tex = -1,
    .metallic = 1.0f,
    .roughness = 1.0f,
    .mr_tex = -1,
    .emissive_tex = -1,
    .alpha_cutoff = 0.5f,
    .tex_param = {LIE_XF_ID_PARAM, LIE_XF_ID_PARAM, LIE_XF_ID_PARAM, LIE_XF_ID_PARAM, LIE_XF_ID_PARAM},
    .tex_xf = {LIE_XF_ID, LIE_XF_ID, LIE_XF_ID, LIE_XF_ID, LIE_XF_ID},
    .normal_tex = -1,
    .normal_scale = 1.0f,
    .transmission_tex = -1,
};

lie_scene_options lie_scene_options_default(void)
{
    lie_scene_options o;
    memset(&o, 0, sizeof o);
    o.max_triangles = LIE_SCENE_MAX_TRIANGLES_DEFAULT;
    return o;
}

const lie_material *lie_scene_material(const lie_scene *s, int32_t index)
{
    return index >= 0 && index < s->n_materials ? &s->materials[index] : &default_material;
}

static void free_world(lie_scene *s)
{
    LIE_FREE(s->instances);
    s->n_instances = 0;
    LIE_FREE(s->tri_p);
    LIE_FREE(s->tri_n);
    LIE_FREE(s->tri_uv);
    LIE_FREE(s->tri_uv1);
    LIE_FREE(s->tri_color);
    LIE_FREE(s->tri_tan);
    LIE_FREE(s->tri_ng);
    LIE_FREE(s->tri_area);
    LIE_FREE(s->tri_material);
    LIE_FREE(s->tri_instance);
    LIE_FREE(s->tri_removed);
    LIE_FREE(s->tri_emitter);
    LIE_FREE(s->clusters);
    LIE_FREE(s->cluster_tris);
    LIE_FREE(s->cluster_cdf);
    LIE_FREE(s->tri_cluster);
    s->n_clusters = 0;
    for (int i = 0; i < s->n_emitters; i++)
        free(s->emitters[i].tri_cdf);
    LIE_FREE(s->emitters);
    s->n_emitters = 0;
    for (int i = 0; i < s->n_cameras; i++)
        free(s->cameras[i].name);
    LIE_FREE(s->cameras);
    s->n_cameras = 0;
    s->n_tris = 0;
}

void lie_scene_destroy(lie_scene *s)
{
    if (!s)
        return;
    free_world(s);
    for (int i = 0; i < s->n_nodes; i++) {
        free(s->nodes[i].name);
        free(s->nodes[i].children);
        free(s->nodes[i].weights);
    }
    for (int i = 0; i < s->n_skins; i++) {
        free(s->skins[i].name);
        free(s->skins[i].joints);
        free(s->skins[i].inverse_bind);
    }
    free(s->skins);
    for (int i = 0; i < s->n_animations; i++) {
        lie_animation *a = &s->animations[i];
        for (int k = 0; k < a->n_samplers; k++) {
            free(a->samplers[k].times);
            free(a->samplers[k].values);
        }
        free(a->samplers);
        free(a->channels);
        free(a->name);
    }
    free(s->animations);
    free(s->nodes);
    free(s->roots);
    for (int i = 0; i < s->n_meshes; i++) {
        lie_mesh *m = &s->meshes[i];
        for (int p = 0; p < m->n_prims; p++)
            lie_primitive_free(&m->prims[p]);
        free(m->prims);
        free(m->name);
    }
    free(s->meshes);
    for (int i = 0; i < s->n_materials; i++)
        free(s->materials[i].name);
    free(s->materials);
    for (int i = 0; i < s->n_textures; i++)
        lie_texture_free(&s->textures[i]);
    free(s->textures);
    for (int i = 0; i < s->n_images; i++) {
        free(s->images[i].bytes);
        free(s->images[i].mime);
        free(s->images[i].name);
    }
    free(s->images);
    for (int i = 0; i < s->n_not_read; i++)
        free(s->not_read[i]);
    free(s->not_read);
    for (int i = 0; i < s->n_camera_defs; i++)
        free(s->camera_defs[i].name);
    free(s->camera_defs);
    for (int i = 0; i < s->n_light_defs; i++)
        free(s->light_defs[i].name);
    free(s->light_defs);
    free(s->path);
    free(s);
}

lie_status lie_scene_load(const char *path, const lie_scene_options *opt, lie_scene **out,
                          lie_error *err)
{
    *out = NULL;
    lie_scene_options def = lie_scene_options_default();
    if (!opt)
        opt = &def;
    lie_scene *s = calloc(1, sizeof *s);
    if (!s)
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    s->path = strdup(path);
    if (!s->path) {
        free(s);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    s->cluster_max = opt->emitter_clusters;
    if (s->cluster_max < 0 || s->cluster_max > LIE_CLUSTER_MAX) {
        lie_scene_destroy(s);
        return lie_error_set(err, LIE_ERR_ARG, path, "emitter clusters %d: expected 0 to %d", opt->emitter_clusters,
                             LIE_CLUSTER_MAX);
    }
    lie_status st = lie_gltf_import(s, path, opt, err);
    if (st == LIE_OK)
        st = lie_scene_flatten(s, err);
    if (st != LIE_OK) {
        lie_scene_destroy(s);
        return st;
    }
    *out = s;
    return LIE_OK;
}

/* ---- flattening ------------------------------------------------------- */

typedef struct visit {
    int node;
    int dead;
    lie_mat4 world;
} visit;

/* Depth-first pre-order over the default scene's roots; calls back per node
 * with its world matrix and whether it (or an ancestor) was removed.  The
 * importer has rejected cycles. */
typedef void (*visit_fn)(lie_scene *s, int node, const lie_mat4 *world, int dead, void *ctx);

static lie_status walk(lie_scene *s, visit_fn fn, void *ctx)
{
    size_t cap = (size_t)s->n_nodes + 1, n = 0;
    visit *stack = malloc(cap * sizeof *stack);
    if (!stack)
        return LIE_ERR_NOMEM;
    for (int r = 0; r < s->n_roots; r++) {
        int nd = s->roots[r];
        if (nd < 0 || nd >= s->n_nodes)
            continue;
        stack[n].node = nd;
        stack[n].dead = s->nodes[nd].removed != 0;
        stack[n].world = s->nodes[nd].local;
        n++;
        while (n > 0) {
            visit v = stack[--n];
            const lie_node *node = &s->nodes[v.node];
            fn(s, v.node, &v.world, v.dead, ctx);
            for (int c = node->n_children - 1; c >= 0; c--) {
                int ch = node->children[c];
                if (ch < 0 || ch >= s->n_nodes)
                    continue;
                if (n == cap) {
                    visit *ns = realloc(stack, 2 * cap * sizeof *stack);
                    if (!ns) {
                        free(stack);
                        return LIE_ERR_NOMEM;
                    }
                    stack = ns;
                    cap *= 2;
                }
                stack[n].node = ch;
                stack[n].dead = v.dead || s->nodes[ch].removed != 0;
                stack[n].world = lie_mat4_mul(&v.world, &s->nodes[ch].local);
                n++;
            }
        }
    }
    free(stack);
    return LIE_OK;
}

typedef struct count_ctx {
    uint64_t tris;
    int instances, lights, cameras;
} count_ctx;

static void count_node(lie_scene *s, int nd, const lie_mat4 *world, int dead, void *p)
{
    count_ctx *c = p;
    const lie_node *node = &s->nodes[nd];
    if (node->mesh >= 0 && node->mesh < s->n_meshes) {
        const lie_mesh *m = &s->meshes[node->mesh];
        for (int i = 0; i < m->n_prims; i++) {
            if (m->prims[i].n_tris == 0)
                continue;
            c->tris += m->prims[i].n_tris;
            c->instances++;
        }
    }
    if (node->light >= 0 && node->light < s->n_light_defs)
        c->lights++;
    if (node->camera >= 0 && node->camera < s->n_camera_defs)
        c->cameras++;
}

static int material_emits(const lie_material *m)
{
    return m->emissive[0] > 0.0f || m->emissive[1] > 0.0f || m->emissive[2] > 0.0f;
}

typedef struct fill_ctx {
    uint32_t tri;
    lie_status status;
    lie_mat4 *node_world;  /* every node's world transform, for skins; NULL without skins */
} fill_ctx;

/* Every node's world transform (parents' chains; the importer refused cycles). */
static lie_mat4 *node_worlds(const lie_scene *s)
{
    lie_mat4 *w = malloc(sizeof *w * ((size_t)s->n_nodes + 1));
    uint8_t *done = calloc((size_t)s->n_nodes + 1, 1);
    int *chain = malloc(sizeof *chain * ((size_t)s->n_nodes + 1));
    if (!w || !done || !chain) {
        free(w);
        free(done);
        free(chain);
        return NULL;
    }
    for (int i = 0; i < s->n_nodes; i++) {
        int n = 0;
        for (int k = i; k >= 0 && !done[k] && n < s->n_nodes; k = s->nodes[k].parent)
            chain[n++] = k;
        while (n > 0) {
            int k = chain[--n], p = s->nodes[k].parent;
            w[k] = p >= 0 && done[p] ? lie_mat4_mul(&w[p], &s->nodes[k].local) : s->nodes[k].local;
            done[k] = 1;
        }
    }
    free(done);
    free(chain);
    return w;
}

/* glTF 2.0 §3.7.3.3: a skinned vertex is sum_k weight_k * (world of joint_k)
 * * (inverse bind matrix of joint_k) applied to its position; the skinned
 * node's own transform is not used.  World positions and (unnormalised)
 * normals of every vertex (and tangents, of `tan` when not NULL), and per
 * vertex whether its matrix mirrors. */
static int skin_vertices(const lie_scene *s, const lie_skin *sk, const lie_primitive *pr, const lie_mat4 *node_world,
                         const float *tan, lie_vec3 *wp, lie_vec3 *wn, lie_vec3 *wt, uint8_t *mirror)
{
    lie_mat4 *J = malloc(sizeof *J * (size_t)sk->n_joints);
    if (!J)
        return 0;
    for (int j = 0; j < sk->n_joints; j++)
        J[j] = lie_mat4_mul(&node_world[sk->joints[j]], &sk->inverse_bind[j]);
    for (uint32_t v = 0; v < pr->n_verts; v++) {
        lie_mat4 M;
        memset(&M, 0, sizeof M);
        for (int k = 0; k < 4; k++) {
            double wk = pr->weights[4 * (size_t)v + (size_t)k];
            int j = pr->joints[4 * (size_t)v + (size_t)k];
            if (wk == 0.0 || j >= sk->n_joints)
                continue;
            for (int c = 0; c < 16; c++)
                M.m[c] += wk * J[j].m[c];
        }
        const float *q = &pr->pos[3 * (size_t)v];
        wp[v] = lie_mat4_point(&M, lie_v3(q[0], q[1], q[2]));
        mirror[v] = lie_mat4_det3(&M) < 0.0;
        if (pr->nrm) {
            const float *nq = &pr->nrm[3 * (size_t)v];
            wn[v] = lie_mat4_normal(&M, lie_v3(nq[0], nq[1], nq[2]));
        }
        if (tan) /* a tangent lies in the surface: it moves as positions do */
            wt[v] = lie_mat4_vector(&M, lie_v3(tan[4 * (size_t)v], tan[4 * (size_t)v + 1], tan[4 * (size_t)v + 2]));
    }
    free(J);
    return 1;
}

/* Flatten node nd (world: its world transform; dead: removed, itself or an
 * ancestor) into the world arrays at fill_ctx's cursor.  One piece: every
 * per-triangle array (positions, normals, texture coordinates, colours,
 * materials, removal) is written in one pass over the node's primitives, so
 * that each triangle's slot is the same in all of them. */
static void fill_node(lie_scene *s, int nd, const lie_mat4 *world, int dead, void *p)
{
    fill_ctx *f = p;
    const lie_node *node = &s->nodes[nd];
    if (node->mesh >= 0 && node->mesh < s->n_meshes) {
        const lie_mesh *m = &s->meshes[node->mesh];
        /* glTF §3.7.4: a negative determinant flips the winding; we swap two
         * vertices so every world triangle is counter-clockwise seen from its
         * front. */
        int mirror = lie_mat4_det3(world) < 0.0;
        const lie_skin *sk = node->skin >= 0 && node->skin < s->n_skins && f->node_world ? &s->skins[node->skin] : NULL;
        for (int pi = 0; pi < m->n_prims; pi++) {
            const lie_primitive *pr = &m->prims[pi];
            if (pr->n_tris == 0)
                continue;
            /* Tangents where the material has a normal map: the file's, else
             * made from the normal map's texture coordinates. */
            const lie_material *pmat = lie_scene_material(s, pr->material);
            const float *tan = NULL;
            float *made = NULL;
            if (s->tri_tan && pmat->normal_tex >= 0 && !dead) {
                tan = pr->tan;
                if (!tan) {
                    made = malloc(sizeof(float) * 4 * ((size_t)pr->n_verts + 1));
                    if (!made || !lie_primitive_tangents(pr, pmat->tex_set[LIE_TEX_NORMAL], made)) {
                        free(made);
                        f->status = LIE_ERR_NOMEM;
                        return;
                    }
                    tan = made;
                }
            }
            lie_vec3 *sk_p = NULL, *sk_n = NULL, *sk_t = NULL;
            uint8_t *sk_m = NULL;
            if (sk && pr->joints && !dead) {
                sk_p = malloc(sizeof *sk_p * ((size_t)pr->n_verts + 1));
                sk_n = malloc(sizeof *sk_n * ((size_t)pr->n_verts + 1));
                sk_t = malloc(sizeof *sk_t * ((size_t)pr->n_verts + 1));
                sk_m = malloc((size_t)pr->n_verts + 1);
                if (!sk_p || !sk_n || !sk_t || !sk_m ||
                    !skin_vertices(s, sk, pr, f->node_world, tan, sk_p, sk_n, sk_t, sk_m)) {
                    free(sk_p);
                    free(sk_n);
                    free(sk_t);
                    free(sk_m);
                    free(made);
                    f->status = LIE_ERR_NOMEM;
                    return;
                }
            }
            lie_instance *in = &s->instances[s->n_instances];
            in->node = nd;
            in->mesh = node->mesh;
            in->prim = pi;
            in->material = pr->material;
            in->first_tri = f->tri;
            in->n_tris = pr->n_tris;
            in->world = sk_p ? lie_mat4_identity() : *world;
            uint32_t inst = (uint32_t)s->n_instances++;
            for (uint32_t t = 0; t < pr->n_tris; t++) {
                uint32_t g = f->tri++;
                uint32_t v[3] = {pr->idx[3 * t], pr->idx[3 * t + 1], pr->idx[3 * t + 2]};
                if (sk_p ? sk_m[v[0]] : mirror) {
                    uint32_t x = v[1];
                    v[1] = v[2];
                    v[2] = x;
                }
                lie_vec3 *P = &s->tri_p[3 * (size_t)g];
                s->tri_removed[g] = (uint8_t)dead;
                for (int k = 0; k < 3; k++) {
                    const float *q = &pr->pos[3 * (size_t)v[k]];
                    /* a removed node's slots: empty triangles at the origin */
                    P[k] = dead   ? lie_v3(0.0f, 0.0f, 0.0f)
                           : sk_p ? sk_p[v[k]]
                                  : lie_mat4_point(world, lie_v3(q[0], q[1], q[2]));
                }
                lie_vec3 c = lie_v3_cross(lie_v3_sub(P[1], P[0]), lie_v3_sub(P[2], P[0]));
                float len = lie_v3_len(c);
                s->tri_area[g] = 0.5f * len;
                if (len > 0.0f && isfinite(len)) {
                    s->tri_ng[g] = lie_v3_scale(c, 1.0f / len);
                } else {
                    s->tri_ng[g] = lie_v3(0.0f, 0.0f, 1.0f);
                    s->tri_area[g] = 0.0f;
                    s->stats.degenerate_tris += (uint32_t)!dead;
                }
                for (int k = 0; k < 3; k++) {
                    lie_vec3 n = s->tri_ng[g];
                    if (pr->nrm) {
                        const float *q = &pr->nrm[3 * (size_t)v[k]];
                        lie_vec3 w = lie_v3_norm(sk_p ? sk_n[v[k]] : lie_mat4_normal(world, lie_v3(q[0], q[1], q[2])));
                        if (lie_v3_dot(w, w) > 0.5f)
                            n = w;
                    }
                    s->tri_n[3 * (size_t)g + k] = n;
                    float *uv = &s->tri_uv[6 * (size_t)g + 2 * k];
                    if (pr->uv) {
                        uv[0] = pr->uv[2 * (size_t)v[k]];
                        uv[1] = pr->uv[2 * (size_t)v[k] + 1];
                    } else {
                        uv[0] = uv[1] = 0.0f;
                    }
                    if (s->tri_uv1) {
                        float *uv1 = &s->tri_uv1[6 * (size_t)g + 2 * k];
                        uv1[0] = pr->uv1 ? pr->uv1[2 * (size_t)v[k]] : uv[0];
                        uv1[1] = pr->uv1 ? pr->uv1[2 * (size_t)v[k] + 1] : uv[1];
                    }
                    if (s->tri_color) {
                        float *col = &s->tri_color[12 * (size_t)g + 4 * k];
                        for (int q = 0; q < 4; q++)
                            col[q] = pr->color ? pr->color[4 * (size_t)v[k] + (size_t)q] : 1.0f;
                    }
                    if (s->tri_tan) {
                        /* The tangent moves with the surface (the model
                         * matrix, not the normal's); a mirroring transform
                         * turns the frame's handedness around. */
                        float *tt = &s->tri_tan[12 * (size_t)g + 4 * k];
                        memset(tt, 0, sizeof(float) * 4);
                        if (tan) {
                            const float *q = &tan[4 * (size_t)v[k]];
                            lie_vec3 w = lie_v3_norm(sk_t ? sk_t[v[k]] : lie_mat4_vector(world, lie_v3(q[0], q[1], q[2])));
                            int flip = sk_p ? sk_m[v[k]] : mirror;
                            tt[0] = w.x;
                            tt[1] = w.y;
                            tt[2] = w.z;
                            tt[3] = (q[3] < 0.0f) != flip ? -1.0f : 1.0f;
                        }
                    }
                }
                s->tri_material[g] = pr->material;
                s->tri_instance[g] = inst;
                s->tri_emitter[g] = -1;
            }
            free(sk_p);
            free(sk_n);
            free(sk_t);
            free(sk_m);
            free(made);
            const lie_material *mat = lie_scene_material(s, pr->material);
            if (!dead && material_emits(mat)) {
                lie_emitter *e = &s->emitters[s->n_emitters];
                memset(e, 0, sizeof *e);
                e->type = LIE_EMITTER_AREA;
                e->node = nd;
                e->instance = (int)inst;
                e->first_tri = in->first_tri;
                e->n_tris = in->n_tris;
                e->tri_cdf = malloc(sizeof(float) * in->n_tris);
                if (!e->tri_cdf) {
                    f->status = LIE_ERR_NOMEM;
                    return;
                }
                double acc = 0.0;
                for (uint32_t t = 0; t < in->n_tris; t++) {
                    acc += s->tri_area[in->first_tri + t];
                    e->tri_cdf[t] = (float)acc;
                }
                e->area = (float)acc;
                memcpy(e->radiance, mat->emissive, sizeof e->radiance);
                e->double_sided = mat->double_sided;
                lie_scene_emitter_shape(s, e);
                e->cos_inner = e->cos_outer = -2.0f;
                if (e->area > 0.0f) {
                    for (uint32_t t = 0; t < in->n_tris; t++)
                        s->tri_emitter[in->first_tri + t] = s->n_emitters;
                    s->n_emitters++;
                } else {
                    free(e->tri_cdf); /* an emitter of zero area emits nothing */
                    e->tri_cdf = NULL;
                }
            }
        }
    }
    if (dead)
        return;
    if (node->light >= 0 && node->light < s->n_light_defs) {
        const lie_light_def *l = &s->light_defs[node->light];
        lie_emitter *e = &s->emitters[s->n_emitters++];
        memset(e, 0, sizeof *e);
        e->type = l->type == LIE_LIGHT_DIRECTIONAL ? LIE_EMITTER_DIRECTIONAL : LIE_EMITTER_POINT;
        e->node = nd;
        e->instance = -1;
        e->position = lie_mat4_point(world, lie_v3(0.0f, 0.0f, 0.0f));
        /* KHR_lights_punctual: spot and directional lights point down local -Z. */
        e->direction = lie_v3_norm(lie_mat4_vector(world, lie_v3(0.0f, 0.0f, -1.0f)));
        for (int k = 0; k < 3; k++)
            e->intensity[k] = l->color[k] * l->intensity;
        e->range = l->range;
        if (l->type == LIE_LIGHT_SPOT) {
            e->cos_inner = cosf(l->inner_cone);
            e->cos_outer = cosf(l->outer_cone);
        } else {
            e->cos_inner = e->cos_outer = -2.0f;
        }
    }
    if (node->camera >= 0 && node->camera < s->n_camera_defs) {
        const lie_camera_def *cd = &s->camera_defs[node->camera];
        lie_camera *c = &s->cameras[s->n_cameras];
        const char *name = node->name ? node->name : cd->name;
        c->name = name ? strdup(name) : NULL;
        c->eye = lie_mat4_point(world, lie_v3(0.0f, 0.0f, 0.0f));
        c->forward = lie_v3_norm(lie_mat4_vector(world, lie_v3(0.0f, 0.0f, -1.0f)));
        lie_vec3 up = lie_mat4_vector(world, lie_v3(0.0f, 1.0f, 0.0f));
        up = lie_v3_sub(up, lie_v3_scale(c->forward, lie_v3_dot(up, c->forward)));
        c->up = lie_v3_norm(up);
        c->yfov = cd->yfov;
        c->aspect = cd->aspect;
        c->ymag = cd->ymag > 0.0f ? cd->ymag : 0.0f;
        if ((cd->yfov > 0.0f || c->ymag > 0.0f) && lie_v3_dot(c->forward, c->forward) > 0.5f &&
            lie_v3_dot(c->up, c->up) > 0.5f)
            s->n_cameras++;
        else
            free(c->name); /* a degenerate transform: no usable camera */
    }
}

static void hash_world(lie_scene *s, lie_hasher *h)
{
    uint64_t n = s->n_tris;
    lie_hasher_update(h, "lie-scene-1", 11);
    lie_hasher_update(h, &n, sizeof n);
    lie_hasher_update(h, s->tri_p, sizeof(lie_vec3) * 3 * n);
    lie_hasher_update(h, s->tri_n, sizeof(lie_vec3) * 3 * n);
    lie_hasher_update(h, s->tri_uv, sizeof(float) * 6 * n);
    if (s->tri_color) { /* only when there are vertex colours: other scenes keep their hashes */
        lie_hasher_update(h, "COLOR_0", 7);
        lie_hasher_update(h, s->tri_color, sizeof(float) * 12 * n);
    }
    if (s->tri_tan) { /* likewise tangents, made for normal maps */
        lie_hasher_update(h, "TANGENT", 7);
        lie_hasher_update(h, s->tri_tan, sizeof(float) * 12 * n);
    }
    if (s->tri_uv1) { /* likewise a second texture coordinate set */
        lie_hasher_update(h, "TEXCOORD_1", 10);
        lie_hasher_update(h, s->tri_uv1, sizeof(float) * 6 * n);
    }
    lie_hasher_update(h, s->tri_material, sizeof(int32_t) * n);
    lie_hasher_update(h, s->tri_removed, n);
    int32_t nm = s->n_materials, nt = s->n_textures, ne = s->n_emitters;
    lie_hasher_update(h, &nm, sizeof nm);
    for (int i = 0; i < s->n_materials; i++) {
        const lie_material *m = &s->materials[i];
        float f[10] = {m->base_color[0], m->base_color[1], m->base_color[2], m->base_color[3],
                       m->metallic,      m->roughness,     m->emissive[0],   m->emissive[1],
                       m->emissive[2],   (float)m->double_sided};
        int32_t t[3] = {m->base_color_tex, m->mr_tex, m->emissive_tex};
        lie_hasher_update(h, f, sizeof f);
        lie_hasher_update(h, t, sizeof t);
        if (m->alpha_mask) { /* only masked materials: other scenes keep their hashes */
            float a[2] = {1.0f, m->alpha_cutoff};
            lie_hasher_update(h, a, sizeof a);
        }
        for (int k = 0; k < 3; k++) /* texture transforms, when there are any */
            if (!lie_material_tex_xf_is_identity(m, k)) {
                int32_t slot = k;
                lie_hasher_update(h, &slot, sizeof slot);
                lie_hasher_update(h, m->tex_param[k], sizeof m->tex_param[k]);
            }
        for (int k = 0; k < 3; k++) /* slots reading TEXCOORD_1 */
            if (m->tex_set[k]) {
                int32_t d[2] = {k + 16, m->tex_set[k]};
                lie_hasher_update(h, d, sizeof d);
            }
        /* The normal map and transmission only where a material has them:
         * other scenes keep their hashes. */
        if (m->normal_tex >= 0) {
            int32_t d[3] = {32, m->normal_tex, m->tex_set[LIE_TEX_NORMAL]};
            lie_hasher_update(h, d, sizeof d);
            lie_hasher_update(h, &m->normal_scale, sizeof m->normal_scale);
            lie_hasher_update(h, m->tex_param[LIE_TEX_NORMAL], sizeof m->tex_param[LIE_TEX_NORMAL]);
        }
        if (m->transmission > 0.0f) {
            int32_t d[3] = {33, m->transmission_tex, m->tex_set[LIE_TEX_TRANSMISSION]};
            lie_hasher_update(h, d, sizeof d);
            lie_hasher_update(h, &m->transmission, sizeof m->transmission);
            lie_hasher_update(h, m->tex_param[LIE_TEX_TRANSMISSION], sizeof m->tex_param[LIE_TEX_TRANSMISSION]);
        }
    }
    lie_hasher_update(h, &nt, sizeof nt);
    for (int i = 0; i < s->n_textures; i++) {
        const lie_texture *t = &s->textures[i];
        int32_t d[4] = {t->width, t->height, (int32_t)t->wrap_s, (int32_t)t->wrap_t};
        lie_hasher_update(h, d, sizeof d);
        size_t texels = (size_t)t->width * (size_t)t->height;
        if (t->rgba || !lie_texture_has_texels(t)) {
            lie_hasher_update(h, t->rgba, sizeof(float) * 4 * texels);
            continue;
        }
        /* the same bytes as the floats would be, a run of texels at a
         * time (the digest does not depend on how the input is cut) */
        float run[4 * 1024];
        for (size_t i0 = 0; i0 < texels; i0 += 1024) {
            size_t k = texels - i0 < 1024 ? texels - i0 : 1024;
            lie_texture_texels(t, i0, k, run);
            lie_hasher_update(h, run, sizeof(float) * 4 * k);
        }
    }
    lie_hasher_update(h, &ne, sizeof ne);
    for (int i = 0; i < s->n_emitters; i++) {
        const lie_emitter *e = &s->emitters[i];
        int32_t d[4] = {(int32_t)e->type, (int32_t)e->first_tri, (int32_t)e->n_tris, e->double_sided};
        float f[15] = {e->radiance[0],  e->radiance[1],  e->radiance[2], e->position.x, e->position.y,
                       e->position.z,   e->direction.x,  e->direction.y, e->direction.z, e->intensity[0],
                       e->intensity[1], e->intensity[2], e->cos_inner,   e->cos_outer,  e->range};
        lie_hasher_update(h, d, sizeof d);
        lie_hasher_update(h, f, sizeof f);
    }
}

/* The world within the coordinate range (core.h, LIE_COORD_MAX): vertices
 * and lights, and the cameras' eyes within LIE_CAMERA_COORD_MAX.  A node a
 * file or an edit sends past it is refused here, where every load, edit and
 * animation frame passes, rather than left for Embree to abort on. */
static lie_status check_range(const lie_scene *s, lie_error *err)
{
    const char *path = s->path ? s->path : "";
    for (size_t i = 0; i < 3 * (size_t)s->n_tris; i++)
        if (!s->tri_removed[i / 3] && !lie_v3_within(s->tri_p[i], LIE_COORD_MAX)) {
            int nd = s->instances[s->tri_instance[i / 3]].node;
            lie_vec3 p = s->tri_p[i];
            return lie_error_set(err, LIE_ERR_LIMIT, path,
                                 "node '%s': a vertex at (%g, %g, %g), outside the coordinate range +-%g",
                                 s->nodes[nd].name ? s->nodes[nd].name : "", (double)p.x, (double)p.y, (double)p.z,
                                 (double)LIE_COORD_MAX);
        }
    for (int i = 0; i < s->n_emitters; i++) {
        const lie_emitter *e = &s->emitters[i];
        if (e->type == LIE_EMITTER_POINT && !lie_v3_within(e->position, LIE_COORD_MAX))
            return lie_error_set(err, LIE_ERR_LIMIT, path, "node '%s': a light outside the coordinate range +-%g",
                                 s->nodes[e->node].name ? s->nodes[e->node].name : "", (double)LIE_COORD_MAX);
    }
    for (int i = 0; i < s->n_cameras; i++)
        if (!lie_v3_within(s->cameras[i].eye, LIE_CAMERA_COORD_MAX))
            return lie_error_set(err, LIE_ERR_LIMIT, path, "camera '%s': outside the coordinate range +-%g",
                                 s->cameras[i].name ? s->cameras[i].name : "", (double)LIE_CAMERA_COORD_MAX);
    return LIE_OK;
}

lie_status lie_scene_flatten(lie_scene *s, lie_error *err)
{
    const char *path = s->path ? s->path : "";
    free_world(s);
    s->stats.degenerate_tris = 0;
    count_ctx c = {0, 0, 0, 0};
    if (walk(s, count_node, &c) != LIE_OK)
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    if (c.tris > 0xFFFFFFF0u)
        return lie_error_set(err, LIE_ERR_LIMIT, path, "%llu triangles: more than this build supports",
                             (unsigned long long)c.tris);
    size_t n = (size_t)c.tris;
    s->instances = calloc((size_t)c.instances + 1, sizeof *s->instances);
    s->tri_p = malloc(sizeof(lie_vec3) * 3 * n + 1);
    s->tri_n = malloc(sizeof(lie_vec3) * 3 * n + 1);
    s->tri_uv = malloc(sizeof(float) * 6 * n + 1);
    s->tri_ng = malloc(sizeof(lie_vec3) * n + 1);
    s->tri_area = malloc(sizeof(float) * n + 1);
    s->tri_material = malloc(sizeof(int32_t) * n + 1);
    s->tri_instance = malloc(sizeof(uint32_t) * n + 1);
    s->tri_removed = malloc(n + 1);
    s->tri_emitter = malloc(sizeof(int32_t) * n + 1);
    int any_color = 0, any_uv1 = 0; /* vertex colours, a second set: memory only where a file has them */
    for (int i = 0; i < s->n_meshes; i++)
        for (int p = 0; p < s->meshes[i].n_prims; p++) {
            any_color |= s->meshes[i].prims[p].color != NULL;
            any_uv1 |= s->meshes[i].prims[p].uv1 != NULL;
        }
    s->tri_color = any_color ? malloc(sizeof(float) * 12 * n + 1) : NULL;
    s->tri_uv1 = any_uv1 ? malloc(sizeof(float) * 6 * n + 1) : NULL;
    int any_normal_map = 0; /* tangents likewise: only for normal maps */
    for (int i = 0; i < s->n_materials; i++)
        any_normal_map |= s->materials[i].normal_tex >= 0;
    s->tri_tan = any_normal_map ? malloc(sizeof(float) * 12 * n + 1) : NULL;
    s->emitters = calloc((size_t)c.instances + (size_t)c.lights + 1, sizeof *s->emitters);
    s->cameras = calloc((size_t)c.cameras + 1, sizeof *s->cameras);
    if (!s->instances || !s->tri_p || !s->tri_n || !s->tri_uv || !s->tri_ng || !s->tri_area ||
        !s->tri_material || !s->tri_instance || !s->tri_removed || !s->tri_emitter || !s->emitters ||
        !s->cameras || (any_color && !s->tri_color) || (any_uv1 && !s->tri_uv1) ||
        (any_normal_map && !s->tri_tan)) {
        free_world(s);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory for %zu triangles", n);
    }
    s->n_tris = (uint32_t)n;
    fill_ctx f = {0, LIE_OK, NULL};
    if (s->n_skins > 0 && !(f.node_world = node_worlds(s))) {
        free_world(s);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    lie_status wst = walk(s, fill_node, &f);
    free(f.node_world);
    if (wst != LIE_OK || f.status != LIE_OK) {
        free_world(s);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    s->bounds = lie_box3_empty();
    s->max_tri_area = 0.0f;
    for (size_t i = 0; i < 3 * n; i++)
        if (!s->tri_removed[i / 3])
            lie_box3_grow(&s->bounds, s->tri_p[i]);
    for (size_t i = 0; i < n; i++)
        s->max_tri_area = fmaxf(s->max_tri_area, s->tri_area[i]);
    lie_status rst = check_range(s, err);
    if (rst != LIE_OK) {
        free_world(s);
        return rst;
    }
    if (lie_scene_cluster(s) != LIE_OK) {
        free_world(s);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    lie_hasher *h = lie_hasher_create(0);
    if (!h) {
        free_world(s);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    hash_world(s, h);
    s->hash = lie_hasher_digest(h);
    lie_hasher_destroy(h);
    return LIE_OK;
}

/* ---- cameras ---------------------------------------------------------- */

lie_camera lie_scene_default_camera(const lie_scene *s)
{
    lie_camera c;
    memset(&c, 0, sizeof c);
    c.yfov = 45.0f * (float)M_PI / 180.0f;
    c.aspect = 0.0f;
    lie_vec3 lo = s->bounds.lo, hi = s->bounds.hi;
    if (lie_box3_is_empty(&s->bounds))
        lo = hi = lie_v3(0.0f, 0.0f, 0.0f);
    lie_vec3 centre = lie_v3_scale(lie_v3_add(lo, hi), 0.5f);
    float radius = 0.5f * lie_v3_len(lie_v3_sub(hi, lo));
    if (!(radius > 0.0f))
        radius = 1.0f;
    /* From the +z side, raised 30 degrees, far enough that the bounding
     * sphere fits the vertical field of view. */
    lie_vec3 dir = lie_v3_norm(lie_v3(0.0f, 0.5f, 0.8660254f));
    float dist = radius / sinf(0.5f * c.yfov);
    c.eye = lie_v3_add(centre, lie_v3_scale(dir, dist));
    c.forward = lie_v3_scale(dir, -1.0f);
    lie_vec3 up = lie_v3(0.0f, 1.0f, 0.0f);
    c.up = lie_v3_norm(lie_v3_sub(up, lie_v3_scale(c.forward, lie_v3_dot(up, c.forward))));
    return c;
}

lie_status lie_scene_camera(const lie_scene *s, const char *spec, lie_camera *out, lie_error *err)
{
    const char *path = s->path ? s->path : "";
    if (!spec || !*spec) {
        *out = s->n_cameras > 0 ? s->cameras[0] : lie_scene_default_camera(s);
        return LIE_OK;
    }
    const char *num = spec[0] == '#' ? spec + 1 : spec;
    char *end = NULL;
    long idx = strtol(num, &end, 10);
    if (*num && end && *end == '\0') {
        if (idx < 0 || idx >= s->n_cameras)
            return lie_error_set(err, LIE_ERR_NOT_FOUND, path, "camera %ld: the scene has %d camera%s", idx,
                                 s->n_cameras, s->n_cameras == 1 ? "" : "s");
        *out = s->cameras[idx];
        return LIE_OK;
    }
    for (int i = 0; i < s->n_cameras; i++)
        if (s->cameras[i].name && strcmp(s->cameras[i].name, spec) == 0) {
            *out = s->cameras[i];
            return LIE_OK;
        }
    /* Also by the glTF camera object's name. */
    for (int i = 0; i < s->n_nodes; i++) {
        const lie_node *nd = &s->nodes[i];
        if (nd->camera >= 0 && nd->camera < s->n_camera_defs && s->camera_defs[nd->camera].name &&
            strcmp(s->camera_defs[nd->camera].name, spec) == 0 && nd->name) {
            for (int k = 0; k < s->n_cameras; k++)
                if (s->cameras[k].name && strcmp(s->cameras[k].name, nd->name) == 0) {
                    *out = s->cameras[k];
                    return LIE_OK;
                }
        }
    }
    return lie_error_set(err, LIE_ERR_NOT_FOUND, path, "no camera named '%s'", spec);
}
