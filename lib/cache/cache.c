/* SPDX-License-Identifier: Apache-2.0 */
/* Writing caches (formats/lie-cache.md): a header, a section table, the
 * sections in a fixed order, each 8-byte aligned with zero padding, and a
 * trailing XXH3-64 over everything before it.  Every byte is a function of
 * the cache's content. */
#include "cache/internal.h"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <xxhash.h>

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

enum { S_META, S_PARAMS, S_EDITS, S_EMITTERS, S_ROOTS, S_NODES, S_POOL, S_VIEWS, S_COUNT };

static const uint32_t section_ids[S_COUNT] = {
    LIE_CACHE_ID_META, LIE_CACHE_ID_PARAMS, LIE_CACHE_ID_EDITS, LIE_CACHE_ID_EMITTERS,
    LIE_CACHE_ID_ROOTS, LIE_CACHE_ID_NODES, LIE_CACHE_ID_POOL, LIE_CACHE_ID_VIEWS,
};

/* Everything a reader would reject is refused here too, so a cache that
 * encodes always decodes: the fields around the env's trees (check_head),
 * then the trees (check_cache). */
static lie_status check_head(const lie_cache *c, const char *name, lie_error *err)
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
    lie_status st = check_head(c, name, err);
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
 * the env's own layout (a build's shares its lone leaves; an older file's
 * or an edited env's may not), the same trees give the same bytes. */
typedef struct tree_writer {
    const lie_pnode *src;        /* the trees' nodes ... */
    const uint32_t *src_pool;    /* ... and lists */
    unsigned char *nodes, *pool; /* where node node_base and POOL entry pool_base go */
    uint32_t node_base, pool_base;
    uint32_t next_node, next_pool;
} tree_writer;

static void put_node(unsigned char *p, const lie_pnode *x)
{
    lie_cache_put_u32(p + 0, x->child);
    lie_cache_put_u32(p + 4, x->cls);
    lie_cache_put_u32(p + 8, x->quality);
    lie_cache_put_u32(p + 12, x->list);
    lie_cache_put_u32(p + 16, x->count);
}

static void write_tree(tree_writer *w, uint32_t from, uint32_t idx)
{
    lie_pnode x = w->src[from];
    unsigned char *at = w->nodes + (size_t)LIE_CACHE_NODE_SIZE * (idx - w->node_base);
    if (x.child) {
        uint32_t first = w->next_node, oc = x.child;
        w->next_node += 4;
        x.child = first;
        put_node(at, &x);
        for (uint32_t k = 0; k < 4; k++)
            write_tree(w, oc + k, first + k);
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

static void tree_size(const lie_pnode *nodes, uint32_t from, uint64_t *n_nodes, uint64_t *n_pool)
{
    const lie_pnode *x = &nodes[from];
    ++*n_nodes;
    if (x->child)
        for (uint32_t k = 0; k < 4; k++)
            tree_size(nodes, x->child + k, n_nodes, n_pool);
    else if (x->cls == LIE_CLASS_PARTIAL)
        *n_pool += x->count;
}

/* The ROOTS entry of a lone unit, or 0 (no tag is 0). */
static uint32_t lone_tag(const lie_pnode *nodes, uint32_t root)
{
    const lie_pnode *x = &nodes[root];
    if (!lie_pnode_lone(x))
        return 0;
    return x->cls == LIE_CLASS_UNLIT ? LIE_CACHE_ROOT_LONE_UNLIT : LIE_CACHE_ROOT_LONE_NONE;
}

/* Where each section goes (formats/lie-cache.md, Layout), for trees of
 * file_nodes nodes and file_pool list entries. */
typedef struct layout {
    uint64_t sz[S_COUNT], off[S_COUNT], total;
    int n_sections;
} layout;

static void lay_out(const lie_cache *c, uint64_t file_nodes, uint64_t file_pool, layout *L)
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
    /* VIEWS only in a cache built for views: others keep their layout */
    L->n_sections = c->views.n_cams ? S_COUNT : S_VIEWS;
    uint64_t pos = LIE_CACHE_HEADER_SIZE + LIE_CACHE_ENTRY_SIZE * (uint64_t)L->n_sections;
    for (int k = 0; k < L->n_sections; k++) {
        L->off[k] = pos;
        pos = lie_cache_align8(pos + L->sz[k]);
    }
    L->total = pos + 8;
}

/* The header, and the section table with the sections' checksums, at buf. */
static void put_header(unsigned char *buf, const layout *L, int partial, const uint64_t hash[S_COUNT])
{
    memcpy(buf, LIE_CACHE_MAGIC, 8);
    lie_cache_put_u32(buf + 8, LIE_CACHE_VERSION);
    lie_cache_put_u32(buf + 12, 0); /* required flags */
    lie_cache_put_u32(buf + 16, partial ? LIE_CACHE_OPT_PARTIAL : 0u); /* optional flags */
    lie_cache_put_u32(buf + 20, (uint32_t)L->n_sections);
    lie_cache_put_u64(buf + 24, L->total);
    for (int k = 0; k < L->n_sections; k++) {
        unsigned char *t = buf + LIE_CACHE_HEADER_SIZE + LIE_CACHE_ENTRY_SIZE * (size_t)k;
        lie_cache_put_u32(t + 0, section_ids[k]);
        lie_cache_put_u32(t + 4, 0);
        lie_cache_put_u64(t + 8, L->off[k]);
        lie_cache_put_u64(t + 16, L->sz[k]);
        lie_cache_put_u64(t + 24, hash[k]);
    }
}

/* The sections other than ROOTS, NODES and POOL, each at buf + L->off[k]
 * (buf: the whole file, or the part before ROOTS with VIEWS at `views`). */
static void put_small(unsigned char *buf, unsigned char *views, const lie_cache *c, const layout *L,
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
        if (!lone_tag(env->nodes, env->root[u]))
            tree_size(env->nodes, env->root[u], &file_nodes, &file_pool);
    if (file_nodes >= 0xFFFFFFF0u || file_pool >= 0xFFFFFFF0u)
        return lie_error_set(err, LIE_ERR_LIMIT, name, "the patch trees hold too many nodes for one cache");
    layout L;
    lay_out(c, file_nodes, file_pool, &L);
    if (L.total > SIZE_MAX / 2)
        return lie_error_set(err, LIE_ERR_LIMIT, name, "a %llu-byte cache is beyond this machine",
                             (unsigned long long)L.total);
    unsigned char *buf = calloc(1, (size_t)L.total);
    if (!buf)
        return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory for a %llu-byte cache",
                             (unsigned long long)L.total);
    put_small(buf, buf + L.off[S_VIEWS], c, &L, file_nodes, file_pool);

    /* ROOTS, NODES, POOL */
    unsigned char *p = buf + L.off[S_ROOTS];
    tree_writer tw = {env->nodes, env->pool, buf + L.off[S_NODES], buf + L.off[S_POOL], 0, 0, 0, 0};
    for (uint64_t u = 0; u < n_units; u++, p += 4) {
        uint32_t tag = lone_tag(env->nodes, env->root[u]);
        if (tag) {
            lie_cache_put_u32(p, tag);
            continue;
        }
        uint32_t idx = tw.next_node++;
        lie_cache_put_u32(p, idx);
        write_tree(&tw, env->root[u], idx);
    }

    /* section table, then the file checksum over everything before it */
    uint64_t hash[S_COUNT];
    for (int k = 0; k < L.n_sections; k++)
        hash[k] = lie_hash_bytes(buf + L.off[k], (size_t)L.sz[k], 0);
    put_header(buf, &L, env->partial, hash);
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

/* ---- streaming: units written as they are built --------------------------
 *
 * A build that writes its units in unit order holds only the ROOTS entries
 * (4 bytes a unit) and one unit at a time: each unit's tree is laid out
 * canonically (write_tree, as encode does) and appended to two spill files
 * (NODES and POOL), their checksums kept running.  Closing writes the file
 * in order through the atomic writer, the spills copied in, the file
 * checksum running over every byte: the bytes lie_cache_write gives the
 * same cache. */
struct lie_cache_stream {
    lie_cache head;            /* the cache's fields; head.env holds no trees */
    lie_env env;               /* its parameters and counts */
    char *name;                /* the output, for messages */
    unsigned char *roots;      /* ROOTS, as written */
    uint64_t n_units, next_unit;
    uint32_t next_node, next_pool;
    FILE *nodes, *pool;        /* the spills */
    XXH3_state_t *h_nodes, *h_pool;
    unsigned char *scratch;    /* one unit's nodes, then its lists */
    size_t cap_scratch;
    lie_status failed;
};

void lie_cache_stream_abort(lie_cache_stream *s)
{
    if (!s)
        return;
    if (s->nodes)
        fclose(s->nodes);
    if (s->pool)
        fclose(s->pool);
    XXH3_freeState(s->h_nodes);
    XXH3_freeState(s->h_pool);
    free(s->roots);
    free(s->scratch);
    free(s->name);
    free(s);
}

lie_status lie_cache_stream_open(const char *path, const lie_cache *c, lie_cache_stream **out, lie_error *err)
{
    *out = NULL;
    lie_status st = c && c->env ? check_head(c, path, err)
                                : lie_error_set(err, LIE_ERR_ARG, path, "refusing to write a cache without an env");
    if (st != LIE_OK)
        return st;
    const uint64_t n_units = (uint64_t)c->env->n_tris * (uint64_t)c->env->n_clusters;
    if (n_units > SIZE_MAX / 8)
        return lie_error_set(err, LIE_ERR_LIMIT, path, "%llu units are beyond this machine",
                             (unsigned long long)n_units);
    lie_cache_stream *s = calloc(1, sizeof *s);
    if (s) {
        s->head = *c;
        s->env = *c->env;
        s->env.root = NULL;
        s->env.nodes = NULL;
        s->env.pool = NULL;
        s->head.env = &s->env;
        s->n_units = n_units;
        s->name = strdup(path ? path : "-");
        s->roots = malloc((size_t)(4 * n_units) + 1);
        s->h_nodes = XXH3_createState();
        s->h_pool = XXH3_createState();
    }
    if (!s || !s->name || !s->roots || !s->h_nodes || !s->h_pool) {
        lie_cache_stream_abort(s);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    XXH3_64bits_reset(s->h_nodes);
    XXH3_64bits_reset(s->h_pool);
    /* unlinked temporaries: nothing is left behind, whatever happens */
    s->nodes = tmpfile();
    s->pool = tmpfile();
    if (!s->nodes || !s->pool) {
        int e = errno;
        lie_cache_stream_abort(s);
        return lie_error_set(err, LIE_ERR_IO, path, "cannot create a temporary file: %s", strerror(e ? e : EIO));
    }
    *out = s;
    return LIE_OK;
}

lie_status lie_cache_stream_unit(lie_cache_stream *s, const lie_pnode *nodes, const uint32_t *pool, uint32_t root,
                                 lie_error *err)
{
    if (s->failed)
        return s->failed;
    if (s->next_unit >= s->n_units)
        return s->failed = lie_error_set(err, LIE_ERR_ARG, s->name, "more units than the scene has");
    unsigned char *r = s->roots + 4 * s->next_unit++;
    uint32_t tag = root >= LIE_CACHE_ROOT_LONE_NONE ? root : lone_tag(nodes, root);
    if (tag) {
        lie_cache_put_u32(r, tag);
        return LIE_OK;
    }
    uint64_t n = 0, np = 0;
    tree_size(nodes, root, &n, &np);
    if ((uint64_t)s->next_node + n >= 0xFFFFFFF0u || (uint64_t)s->next_pool + np >= 0xFFFFFFF0u)
        return s->failed = lie_error_set(err, LIE_ERR_LIMIT, s->name, "the patch trees hold too many nodes for one cache");
    size_t need = (size_t)(LIE_CACHE_NODE_SIZE * n + 4 * np);
    if (!LIE_GROW(s->scratch, s->cap_scratch, need + 1))
        return s->failed = lie_error_set(err, LIE_ERR_NOMEM, s->name, "out of memory");
    unsigned char *nb = s->scratch, *pb = s->scratch + LIE_CACHE_NODE_SIZE * n;
    tree_writer tw = {nodes, pool, nb, pb, s->next_node, s->next_pool, s->next_node, s->next_pool};
    uint32_t idx = tw.next_node++;
    lie_cache_put_u32(r, idx);
    write_tree(&tw, root, idx);
    size_t bn = (size_t)(LIE_CACHE_NODE_SIZE * n), bp = (size_t)(4 * np);
    if (fwrite(nb, 1, bn, s->nodes) != bn || (bp && fwrite(pb, 1, bp, s->pool) != bp)) {
        int e = errno;
        return s->failed = lie_error_set(err, LIE_ERR_IO, s->name, "write failed: %s", strerror(e ? e : EIO));
    }
    XXH3_64bits_update(s->h_nodes, nb, bn);
    XXH3_64bits_update(s->h_pool, pb, bp);
    s->next_node = tw.next_node;
    s->next_pool = tw.next_pool;
    return LIE_OK;
}

uint64_t lie_cache_stream_nodes(const lie_cache_stream *s) { return s->next_node; }
uint64_t lie_cache_stream_pool(const lie_cache_stream *s) { return s->next_pool; }

/* n bytes to the file and to its checksum */
static int put_bytes(FILE *fp, XXH3_state_t *h, const void *p, size_t n)
{
    XXH3_64bits_update(h, p, n);
    return fwrite(p, 1, n, fp) == n;
}

/* Zero bytes from `at` up to `to`. */
static int put_zeros(FILE *fp, XXH3_state_t *h, uint64_t at, uint64_t to)
{
    static const unsigned char zero[8];
    return to <= at || put_bytes(fp, h, zero, (size_t)(to - at));
}

/* A spill, from its start, to the file. */
static int put_spill(FILE *fp, XXH3_state_t *h, FILE *spill, uint64_t n, unsigned char *buf, size_t cap)
{
    if (fflush(spill) != 0 || fseek(spill, 0, SEEK_SET) != 0)
        return 0;
    while (n > 0) {
        size_t k = n < cap ? (size_t)n : cap;
        if (fread(buf, 1, k, spill) != k || !put_bytes(fp, h, buf, k))
            return 0;
        n -= k;
    }
    return 1;
}

lie_status lie_cache_stream_close(lie_cache_stream *s, int partial, size_t *bytes, lie_error *err)
{
    if (bytes)
        *bytes = 0;
    lie_status st = s->failed;
    if (st == LIE_OK && s->next_unit != s->n_units)
        st = lie_error_set(err, LIE_ERR_ARG, s->name, "%llu of %llu units written", (unsigned long long)s->next_unit,
                           (unsigned long long)s->n_units);
    layout L;
    lay_out(&s->head, s->next_node, s->next_pool, &L);
    /* everything before ROOTS, and VIEWS, in memory: a few kilobytes and
     * the edit log */
    unsigned char *small = st == LIE_OK ? calloc(1, (size_t)L.off[S_ROOTS] + 1) : NULL;
    unsigned char *views = st == LIE_OK ? calloc(1, (size_t)L.sz[S_VIEWS] + 1) : NULL;
    const size_t cap = (size_t)1 << 20;
    unsigned char *buf = st == LIE_OK ? malloc(cap) : NULL;
    XXH3_state_t *h = st == LIE_OK ? XXH3_createState() : NULL;
    if (st == LIE_OK && (!small || !views || !buf || !h))
        st = lie_error_set(err, LIE_ERR_NOMEM, s->name, "out of memory");
    lie_atomic_file af;
    if (st == LIE_OK)
        st = lie_atomic_open(&af, s->name, err);
    if (st == LIE_OK) {
        s->env.partial = partial;
        put_small(small, views, &s->head, &L, s->next_node, s->next_pool);
        uint64_t hash[S_COUNT];
        for (int k = 0; k < S_ROOTS; k++)
            hash[k] = lie_hash_bytes(small + L.off[k], (size_t)L.sz[k], 0);
        hash[S_ROOTS] = lie_hash_bytes(s->roots, (size_t)L.sz[S_ROOTS], 0);
        hash[S_NODES] = XXH3_64bits_digest(s->h_nodes);
        hash[S_POOL] = XXH3_64bits_digest(s->h_pool);
        hash[S_VIEWS] = lie_hash_bytes(views, (size_t)L.sz[S_VIEWS], 0);
        put_header(small, &L, partial, hash);
        XXH3_64bits_reset(h);
        FILE *fp = af.fp;
        int ok = put_bytes(fp, h, small, (size_t)L.off[S_ROOTS]) &&
                 put_bytes(fp, h, s->roots, (size_t)L.sz[S_ROOTS]) &&
                 put_zeros(fp, h, L.off[S_ROOTS] + L.sz[S_ROOTS], L.off[S_NODES]) &&
                 put_spill(fp, h, s->nodes, L.sz[S_NODES], buf, cap) &&
                 put_zeros(fp, h, L.off[S_NODES] + L.sz[S_NODES], L.off[S_POOL]) &&
                 put_spill(fp, h, s->pool, L.sz[S_POOL], buf, cap);
        uint64_t end = L.off[S_POOL] + L.sz[S_POOL];
        if (ok && L.n_sections > S_VIEWS) {
            ok = put_zeros(fp, h, end, L.off[S_VIEWS]) && put_bytes(fp, h, views, (size_t)L.sz[S_VIEWS]);
            end = L.off[S_VIEWS] + L.sz[S_VIEWS];
        }
        ok = ok && put_zeros(fp, h, end, L.total - 8);
        unsigned char sum[8];
        lie_cache_put_u64(sum, XXH3_64bits_digest(h));
        ok = ok && fwrite(sum, 1, 8, fp) == 8;
        if (!ok) {
            int e = errno;
            lie_atomic_abort(&af);
            st = lie_error_set(err, LIE_ERR_IO, s->name, "write failed: %s", strerror(e ? e : EIO));
        } else {
            st = lie_atomic_commit(&af, err);
        }
    }
    if (st == LIE_OK && bytes)
        *bytes = (size_t)L.total;
    free(small);
    free(views);
    free(buf);
    XXH3_freeState(h);
    lie_cache_stream_abort(s);
    return st;
}
