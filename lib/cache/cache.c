/* SPDX-License-Identifier: Apache-2.0 */
/* Writing caches (formats/lie-cache.md): a header, a section table, the
 * sections in a fixed order, each 8-byte aligned with zero padding, and a
 * trailing XXH3-64 over everything before it.  Every byte is a function of
 * the cache's content. */
#include "cache/internal.h"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>

int lie_cache_rules_old(const lie_cache *c) { return c->version != 0 && c->version < LIE_CACHE_RULES_VERSION; }

void lie_cache_destroy(lie_cache *c)
{
    if (!c)
        return;
    free(c->scene_path);
    free(c->emitters);
    for (int i = 0; c->edits && i < c->n_edits; i++) {
        free(c->edits[i].name);
        free(c->edits[i].text);
    }
    free(c->edits);
    free(c->views.cams);
    lie_env_destroy(c->env);
    free(c);
}

void lie_cache_section_name(uint32_t id, char name[16])
{
    static const struct {
        uint32_t id;
        const char *name;
    } known[] = {
        {LIE_CACHE_ID_META, "META"},         {LIE_CACHE_ID_PARAMS, "PARAMS"}, {LIE_CACHE_ID_EDITS, "EDITS"},
        {LIE_CACHE_ID_EMITTERS, "EMITTERS"}, {LIE_CACHE_ID_ROOTS, "ROOTS"},   {LIE_CACHE_ID_NODES, "NODES"},
        {LIE_CACHE_ID_POOL, "POOL"},         {LIE_CACHE_ID_RST, "RST"},       {LIE_CACHE_ID_VIEWS, "VIEWS"},
    };
    for (size_t i = 0; i < sizeof known / sizeof known[0]; i++) {
        if (known[i].id == id) {
            snprintf(name, 16, "%s", known[i].name);
            return;
        }
    }
    unsigned char b[4] = {(unsigned char)id, (unsigned char)(id >> 8), (unsigned char)(id >> 16),
                          (unsigned char)(id >> 24)};
    int printable = 1;
    for (int k = 0; k < 4; k++)
        printable &= b[k] >= 0x21 && b[k] <= 0x7e;
    if (printable)
        snprintf(name, 16, "%c%c%c%c", b[0], b[1], b[2], b[3]);
    else
        snprintf(name, 16, "0x%08x", id);
}

/* ---- encoding ------------------------------------------------------------ */

const uint32_t lie_cache_section_ids[S_COUNT] = {
    LIE_CACHE_ID_META, LIE_CACHE_ID_PARAMS, LIE_CACHE_ID_EDITS, LIE_CACHE_ID_EMITTERS,
    LIE_CACHE_ID_ROOTS, LIE_CACHE_ID_NODES, LIE_CACHE_ID_POOL, LIE_CACHE_ID_VIEWS,
};


/* Everything a reader would reject is refused here too, so a cache that
 * encodes always decodes: the fields around the env's trees (check_head),
 * then the trees (check_cache). */
lie_status lie_cache_check_head(const lie_cache *c, const char *name, lie_error *err)
{
    if (!c || !c->env)
        return lie_error_set(err, LIE_ERR_ARG, name, "refusing to write a cache without an env");
    const lie_env *env = c->env;
    if (!c->scene_path)
        return lie_error_set(err, LIE_ERR_ARG, name, "refusing to write a cache without a scene path");
    if (strlen(c->scene_path) > UINT32_MAX)
        return lie_error_set(err, LIE_ERR_ARG, name, "scene path too long");
    if (c->n_emitters < 0 || c->n_edits < 0 || (c->n_emitters > 0 && !c->emitters) ||
        (c->n_edits > 0 && !c->edits))
        return lie_error_set(err, LIE_ERR_ARG, name, "refusing to write a cache with bad emitter or edit arrays");
    uint64_t n_clusters = 0;
    for (int e = 0; e < c->n_emitters; e++)
        n_clusters += c->emitters[e].n_clusters;
    if (c->n_tris != env->n_tris || n_clusters != (uint64_t)env->n_clusters)
        return lie_error_set(err, LIE_ERR_ARG, name,
                             "refusing to write a cache whose env has %u triangles and %d clusters, not %u and %llu",
                             env->n_tris, env->n_clusters, c->n_tris, (unsigned long long)n_clusters);
    if (env->scene_hash != c->state_hash)
        return lie_error_set(err, LIE_ERR_ARG, name,
                             "refusing to write a cache whose env was built for scene state %016llx, not %016llx",
                             (unsigned long long)env->scene_hash, (unsigned long long)c->state_hash);
    lie_error perr;
    if (lie_build_params_check(&env->params, &perr) != LIE_OK)
        return lie_error_set(err, LIE_ERR_ARG, name, "refusing to write a cache with bad parameters: %s", perr.msg);
    for (int e = 0; e < c->n_emitters; e++) {
        const char *why = lie_cache_check_emitter(&c->emitters[e], c->n_tris);
        if (why)
            return lie_error_set(err, LIE_ERR_ARG, name, "refusing to write a cache: emitter %d: %s", e, why);
    }
    for (int i = 0; i < c->n_edits; i++) {
        const lie_cache_edit *ed = &c->edits[i];
        if (!ed->name || strlen(ed->name) > UINT32_MAX || ed->size > UINT32_MAX || (ed->size && !ed->text))
            return lie_error_set(err, LIE_ERR_ARG, name, "refusing to write a cache: edit %d is malformed", i);
    }
    const char *vwhy = lie_cache_check_views(&c->views);
    if (vwhy)
        return lie_error_set(err, LIE_ERR_ARG, name, "refusing to write a cache: views: %s", vwhy);
    return LIE_OK;
}

static lie_status check_cache(const lie_cache *c, const char *name, lie_error *err)
{
    lie_status st = lie_cache_check_head(c, name, err);
    if (st != LIE_OK)
        return st;
    const lie_env *env = c->env;
    if (!env->root || !env->nodes || (env->n_pool && !env->pool))
        return lie_error_set(err, LIE_ERR_ARG, name, "refusing to write a cache: env arrays missing");
    return lie_cache_check_env(env, LIE_ERR_ARG, name, "refusing to write an invalid env: ", err);
}

/* The file's trees (formats/lie-cache.md, Canonical order): a unit that is
 * one lone leaf is a tag in ROOTS; every other unit's nodes follow in unit
 * order, each tree depth first, a split node's four children appended when
 * it is visited, lists in the order their leaves are visited.  Whatever
 * the env's own lie_cache_layout (a build's shares its lone leaves; an older file's
 * or an edited env's may not), the same trees give the same bytes. */

static void put_node(unsigned char *p, const lie_pnode *x)
{
    lie_cache_put_u32(p + 0, x->child);
    lie_cache_put_u32(p + 4, x->cls);
    lie_cache_put_u32(p + 8, x->quality);
    lie_cache_put_u32(p + 12, x->list);
    lie_cache_put_u32(p + 16, x->count);
}

void lie_cache_write_tree(lie_cache_tree_writer *w, uint32_t from, uint32_t idx)
{
    lie_pnode x = w->src[from];
    unsigned char *at = w->nodes + (size_t)LIE_CACHE_NODE_SIZE * (idx - w->node_base);
    if (x.child) {
        uint32_t first = w->next_node, oc = x.child;
        w->next_node += 4;
        x.child = first;
        put_node(at, &x);
        for (uint32_t k = 0; k < 4; k++)
            lie_cache_write_tree(w, oc + k, first + k);
        return;
    }
    if (x.cls == LIE_CLASS_PARTIAL) {
        for (uint32_t k = 0; k < x.count; k++)
            lie_cache_put_u32(w->pool + 4 * ((size_t)(w->next_pool - w->pool_base) + k), w->src_pool[x.list + k]);
        x.list = w->next_pool;
        w->next_pool += x.count;
    }
    put_node(at, &x);
}

void lie_cache_tree_size(const lie_pnode *nodes, uint32_t from, uint64_t *n_nodes, uint64_t *n_pool)
{
    const lie_pnode *x = &nodes[from];
    ++*n_nodes;
    if (x->child)
        for (uint32_t k = 0; k < 4; k++)
            lie_cache_tree_size(nodes, x->child + k, n_nodes, n_pool);
    else if (x->cls == LIE_CLASS_PARTIAL)
        *n_pool += x->count;
}

/* The ROOTS entry of a lone unit, or 0 (no tag is 0). */
uint32_t lie_cache_lone_tag(const lie_pnode *nodes, uint32_t root)
{
    const lie_pnode *x = &nodes[root];
    if (!lie_pnode_lone(x))
        return 0;
    return x->cls == LIE_CLASS_UNLIT ? LIE_CACHE_ROOT_LONE_UNLIT : LIE_CACHE_ROOT_LONE_NONE;
}


void lie_cache_lay_out(const lie_cache *c, uint64_t file_nodes, uint64_t file_pool, lie_cache_layout *L)
{
    const uint64_t n_units = (uint64_t)c->env->n_tris * (uint64_t)c->env->n_clusters;
    L->sz[S_META] = LIE_CACHE_META_FIXED + strlen(c->scene_path);
    L->sz[S_PARAMS] = LIE_CACHE_PARAMS_SIZE;
    L->sz[S_EDITS] = 4;
    for (int i = 0; i < c->n_edits; i++)
        L->sz[S_EDITS] += 8 + (uint64_t)strlen(c->edits[i].name) + c->edits[i].size;
    L->sz[S_EMITTERS] = LIE_CACHE_EMITTER_SIZE * (uint64_t)c->n_emitters;
    L->sz[S_ROOTS] = 4 * n_units;
    L->sz[S_NODES] = LIE_CACHE_NODE_SIZE * file_nodes;
    L->sz[S_POOL] = 4 * file_pool;
    L->sz[S_VIEWS] = LIE_CACHE_VIEWS_FIXED + LIE_CACHE_VIEW_SIZE * (uint64_t)c->views.n_cams;
    /* VIEWS only in a cache built for views: others keep their lie_cache_layout */
    L->n_sections = c->views.n_cams ? S_COUNT : S_VIEWS;
    uint64_t pos = LIE_CACHE_HEADER_SIZE + LIE_CACHE_ENTRY_SIZE * (uint64_t)L->n_sections;
    for (int k = 0; k < L->n_sections; k++) {
        L->off[k] = pos;
        pos = lie_cache_align8(pos + L->sz[k]);
    }
    for (int k = L->n_sections; k < S_COUNT; k++)
        L->off[k] = 0; /* absent: no offset to compute from */
    L->total = pos + 8;
}

/* The header, and the section table with the sections' checksums, at buf. */
void lie_cache_put_header(unsigned char *buf, const lie_cache_layout *L, int partial, const uint64_t hash[S_COUNT])
{
    memcpy(buf, LIE_CACHE_MAGIC, 8);
    lie_cache_put_u32(buf + 8, LIE_CACHE_VERSION);
    lie_cache_put_u32(buf + 12, 0); /* required flags */
    lie_cache_put_u32(buf + 16, partial ? LIE_CACHE_OPT_PARTIAL : 0u); /* optional flags */
    lie_cache_put_u32(buf + 20, (uint32_t)L->n_sections);
    lie_cache_put_u64(buf + 24, L->total);
    for (int k = 0; k < L->n_sections; k++) {
        unsigned char *t = buf + LIE_CACHE_HEADER_SIZE + LIE_CACHE_ENTRY_SIZE * (size_t)k;
        lie_cache_put_u32(t + 0, lie_cache_section_ids[k]);
        lie_cache_put_u32(t + 4, 0);
        lie_cache_put_u64(t + 8, L->off[k]);
        lie_cache_put_u64(t + 16, L->sz[k]);
        lie_cache_put_u64(t + 24, hash[k]);
    }
}

/* The sections other than ROOTS, NODES and POOL, each at buf + L->off[k]
 * (buf: the whole file, or the part before ROOTS with VIEWS at `views`). */
void lie_cache_put_small(unsigned char *buf, unsigned char *views, const lie_cache *c, const lie_cache_layout *L,
                      uint64_t file_nodes, uint64_t file_pool)
{
    const lie_env *env = c->env;
    const uint64_t path_len = strlen(c->scene_path);
    unsigned char *p = buf + L->off[S_META];
    lie_cache_put_u64(p + 0, c->scene_hash);
    lie_cache_put_u64(p + 8, c->state_hash);
    lie_cache_put_u32(p + 16, env->n_tris);
    lie_cache_put_u32(p + 20, (uint32_t)c->n_emitters);
    lie_cache_put_u64(p + 24, (uint64_t)env->n_tris * (uint64_t)env->n_clusters);
    lie_cache_put_u32(p + 32, (uint32_t)file_nodes);
    lie_cache_put_u32(p + 36, (uint32_t)file_pool);
    lie_cache_put_u32(p + 40, (uint32_t)path_len);
    lie_cache_put_u32(p + 44, 0);
    memcpy(p + LIE_CACHE_META_FIXED, c->scene_path, (size_t)path_len);

    p = buf + L->off[S_PARAMS];
    lie_cache_put_u32(p + 0, env->params.samples);
    lie_cache_put_u32(p + 4, env->params.max_samples);
    lie_cache_put_u32(p + 8, env->params.max_blockers);
    lie_cache_put_u32(p + 12, env->params.complex_cap);
    lie_cache_put_u32(p + 16, lie_cache_f32_bits(env->params.min_patch));
    lie_cache_put_u32(p + 20, (uint32_t)env->params.mode);
    lie_cache_put_u32(p + 24, lie_cache_f32_bits(env->params.split_gain));
    lie_cache_put_u32(p + 28, env->params.frames);
    lie_cache_put_u32(p + 32, env->params.light_samples);
    lie_cache_put_u32(p + 36, lie_cache_f32_bits(env->params.ns_segment));
    lie_cache_put_u32(p + 40, lie_cache_f32_bits(env->params.ns_blocker));
    lie_cache_put_u32(p + 44, lie_cache_f32_bits(env->params.ns_ray));
    lie_cache_put_u32(p + 48, env->params.complex_predict);
    lie_cache_put_u32(p + 52, env->params.whole_pixels);

    p = buf + L->off[S_EDITS];
    lie_cache_put_u32(p, (uint32_t)c->n_edits);
    p += 4;
    for (int i = 0; i < c->n_edits; i++) {
        const lie_cache_edit *ed = &c->edits[i];
        size_t nl = strlen(ed->name);
        lie_cache_put_u32(p, (uint32_t)nl);
        lie_cache_put_u32(p + 4, (uint32_t)ed->size);
        memcpy(p + 8, ed->name, nl);
        if (ed->size)
            memcpy(p + 8 + nl, ed->text, ed->size);
        p += 8 + nl + ed->size;
    }

    p = buf + L->off[S_EMITTERS];
    for (int e = 0; e < c->n_emitters; e++, p += LIE_CACHE_EMITTER_SIZE) {
        const lie_cache_emitter *em = &c->emitters[e];
        lie_cache_put_u32(p + 0, em->type);
        lie_cache_put_u32(p + 4, (uint32_t)em->node);
        lie_cache_put_u32(p + 8, em->first_tri);
        lie_cache_put_u32(p + 12, em->n_tris);
        lie_cache_put_u32(p + 16, em->n_clusters);
        lie_cache_put_u32(p + 20, em->partition);
    }

    if (L->n_sections > S_VIEWS) {
        p = views;
        lie_cache_put_u32(p + 0, (uint32_t)c->views.width);
        lie_cache_put_u32(p + 4, (uint32_t)c->views.height);
        lie_cache_put_u32(p + 8, (uint32_t)c->views.max_depth);
        lie_cache_put_u32(p + 12, (uint32_t)c->views.n_cams);
        p += LIE_CACHE_VIEWS_FIXED;
        for (int i = 0; i < c->views.n_cams; i++) {
            const lie_camera *cam = &c->views.cams[i];
            const float f[12] = {cam->eye.x,     cam->eye.y,     cam->eye.z, cam->forward.x, cam->forward.y,
                                 cam->forward.z, cam->up.x,      cam->up.y,  cam->up.z,      cam->yfov,
                                 cam->aspect,    cam->ymag};
            for (int k = 0; k < 12; k++, p += 4)
                lie_cache_put_u32(p, lie_cache_f32_bits(f[k]));
        }
    }
}

/* `name` (the output path, or NULL) is used in messages. */
static lie_status encode(const lie_cache *c, const char *name, unsigned char **data, size_t *size, lie_error *err)
{
    *data = NULL;
    *size = 0;
    lie_status st = check_cache(c, name, err);
    if (st != LIE_OK)
        return st;
    const lie_env *env = c->env;
    const uint64_t n_units = (uint64_t)env->n_tris * (uint64_t)env->n_clusters;
    uint64_t file_nodes = 0, file_pool = 0;
    for (uint64_t u = 0; u < n_units; u++)
        if (!lie_cache_lone_tag(env->nodes, env->root[u]))
            lie_cache_tree_size(env->nodes, env->root[u], &file_nodes, &file_pool);
    if (file_nodes >= 0xFFFFFFF0u || file_pool >= 0xFFFFFFF0u)
        return lie_error_set(err, LIE_ERR_LIMIT, name, "the patch trees hold too many nodes for one cache");
    lie_cache_layout L;
    lie_cache_lay_out(c, file_nodes, file_pool, &L);
    if (L.total > SIZE_MAX / 2)
        return lie_error_set(err, LIE_ERR_LIMIT, name, "a %llu-byte cache is beyond this machine",
                             (unsigned long long)L.total);
    unsigned char *buf = calloc(1, (size_t)L.total);
    if (!buf)
        return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory for a %llu-byte cache",
                             (unsigned long long)L.total);
    lie_cache_put_small(buf, L.n_sections > S_VIEWS ? buf + L.off[S_VIEWS] : NULL, c, &L, file_nodes, file_pool);

    /* ROOTS, NODES, POOL */
    unsigned char *p = buf + L.off[S_ROOTS];
    lie_cache_tree_writer tw = {env->nodes, env->pool, buf + L.off[S_NODES], buf + L.off[S_POOL], 0, 0, 0, 0};
    for (uint64_t u = 0; u < n_units; u++, p += 4) {
        uint32_t tag = lie_cache_lone_tag(env->nodes, env->root[u]);
        if (tag) {
            lie_cache_put_u32(p, tag);
            continue;
        }
        uint32_t idx = tw.next_node++;
        lie_cache_put_u32(p, idx);
        lie_cache_write_tree(&tw, env->root[u], idx);
    }

    /* section table, then the file checksum over everything before it */
    uint64_t hash[S_COUNT];
    for (int k = 0; k < L.n_sections; k++)
        hash[k] = lie_hash_bytes(buf + L.off[k], (size_t)L.sz[k], 0);
    lie_cache_put_header(buf, &L, env->partial, hash);
    lie_cache_put_u64(buf + L.total - 8, lie_hash_bytes(buf, (size_t)L.total - 8, 0));
    *data = buf;
    *size = (size_t)L.total;
    return LIE_OK;
}

lie_status lie_cache_encode(const lie_cache *c, unsigned char **data, size_t *size, lie_error *err)
{
    return encode(c, NULL, data, size, err);
}

static lie_status write_group(const char *path, const lie_cache *c, size_t *bytes, lie_atomic_group *group,
                              lie_error *err)
{
    unsigned char *data = NULL;
    size_t size = 0;
    if (bytes)
        *bytes = 0;
    lie_status st = encode(c, path, &data, &size, err);
    if (st != LIE_OK)
        return st;
    lie_atomic_file af;
    st = lie_atomic_open_group(&af, path, group, err);
    if (st != LIE_OK) {
        free(data);
        return st;
    }
    if (fwrite(data, 1, size, af.fp) != size) {
        int e = errno;
        lie_atomic_abort(&af);
        free(data);
        return lie_error_set(err, LIE_ERR_IO, path, "write failed: %s", strerror(e ? e : EIO));
    }
    free(data);
    st = lie_atomic_commit(&af, err);
    if (st == LIE_OK && bytes)
        *bytes = size;
    return st;
}

lie_status lie_cache_write(const char *path, const lie_cache *c, size_t *bytes, lie_error *err)
{
    return write_group(path, c, bytes, NULL, err);
}

lie_status lie_cache_write_with_scene(const char *path, const lie_cache *c, const lie_scene *s,
                                      const char *scene_out, const lie_gltf_export_options *scene_opt,
                                      size_t *bytes, lie_error *err)
{
    lie_atomic_group *group = lie_atomic_group_create();
    if (!group)
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    lie_status st = scene_out ? lie_gltf_export_group(s, scene_out, scene_opt, group, err) : LIE_OK;
    if (st == LIE_OK)
        st = write_group(path, c, bytes, group, err);
    if (st == LIE_OK)
        st = lie_atomic_group_commit(group, err);
    lie_atomic_group_destroy(group);
    return st;
}

lie_status lie_cache_read(const char *path, lie_cache **out, lie_error *err)
{
    *out = NULL;
    unsigned char *data = NULL;
    size_t size = 0;
    lie_status st = lie_read_file(path, &data, &size, err);
    if (st != LIE_OK)
        return st;
    st = lie_cache_decode(data, size, path, out, err);
    free(data);
    return st;
}
