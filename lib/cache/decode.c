/* SPDX-License-Identifier: Apache-2.0 */
/* Reading caches (formats/lie-cache.md, "What a reader must reject"): first
 * the container — magic, file checksum, version, flags, the section table
 * and every section's place and checksum — then each section's counts
 * against its size, and last the structure of the patch trees.  Nothing is
 * allocated before its count has been checked against the bytes present. */
#include "cache/internal.h"

#include <limits.h>
#include <stdlib.h>

#define FAIL(...) lie_error_set(err, LIE_ERR_FORMAT, name, __VA_ARGS__)

typedef unsigned long long ull;

/* Rules 1-8: the container.  Fills out[] (up to LIE_CACHE_MAX_SECTIONS). */
static lie_status parse_container(const unsigned char *data, size_t size, const char *name, lie_cache_section *out,
                                  int *n_out, lie_error *err)
{
    *n_out = 0;
    if (size == 0)
        return FAIL("empty file, not a LIE cache");
    if (size < 8 || memcmp(data, LIE_CACHE_MAGIC, 8) != 0) {
        if (size < 8 && memcmp(data, LIE_CACHE_MAGIC, size) == 0)
            return FAIL("truncated: %zu bytes", size);
        return FAIL("not a LIE cache (bad magic)");
    }
    if (size < LIE_CACHE_HEADER_SIZE + 8)
        return FAIL("truncated: %zu bytes, shorter than a cache header", size);
    const uint64_t file_size = lie_cache_get_u64(data + 24);
    if (lie_hash_bytes(data, size - 8, 0) != lie_cache_get_u64(data + size - 8)) {
        if (file_size != size)
            return FAIL("truncated or extended: the header records %llu bytes, the file has %zu", (ull)file_size,
                        size);
        return FAIL("file checksum mismatch: the file is damaged");
    }
    const uint32_t version = lie_cache_get_u32(data + 8);
    if (version == 0)
        return FAIL("format version 0 is invalid");
    if (version > LIE_CACHE_VERSION)
        return lie_error_set(err, LIE_ERR_UNSUPPORTED, name,
                             "format version %u is newer than this reader's (%u): use a newer lie toolchain",
                             version, LIE_CACHE_VERSION);
    if (file_size != size)
        return FAIL("the header records %llu bytes, the file has %zu", (ull)file_size, size);
    const uint32_t required = lie_cache_get_u32(data + 12);
    if (required != 0)
        return lie_error_set(err, LIE_ERR_UNSUPPORTED, name, "unknown required feature flags 0x%08x", required);
    const uint32_t n = lie_cache_get_u32(data + 20);
    if (n == 0 || n > LIE_CACHE_MAX_SECTIONS)
        return FAIL("section table: %u sections (expected 1..%d)", n, LIE_CACHE_MAX_SECTIONS);
    const uint64_t end = size - 8; /* where the file checksum starts */
    uint64_t pos = LIE_CACHE_HEADER_SIZE + (uint64_t)LIE_CACHE_ENTRY_SIZE * n;
    if (pos > end)
        return FAIL("section table: %u entries do not fit in %zu bytes", n, size);

    for (uint32_t i = 0; i < n; i++) {
        const unsigned char *t = data + LIE_CACHE_HEADER_SIZE + (size_t)LIE_CACHE_ENTRY_SIZE * i;
        lie_cache_section *s = &out[i];
        s->id = lie_cache_get_u32(t);
        lie_cache_section_name(s->id, s->name);
        s->offset = lie_cache_get_u64(t + 8);
        s->size = lie_cache_get_u64(t + 16);
        if (lie_cache_get_u32(t + 4) != 0)
            return FAIL("section table entry %u (%s): reserved field not zero", i, s->name);
        for (uint32_t j = 0; j < i; j++)
            if (out[j].id == s->id)
                return FAIL("section %s appears twice", s->name);
        if (s->offset != pos)
            return FAIL("section %s: offset %llu, expected %llu", s->name, (ull)s->offset, (ull)pos);
        if (s->size > end - pos)
            return FAIL("section %s: %llu bytes at offset %llu pass the end of the sections (%llu)", s->name,
                        (ull)s->size, (ull)s->offset, (ull)end);
        const uint64_t stop = pos + s->size, next = lie_cache_align8(stop);
        if (next > end)
            return FAIL("section %s: padding passes the end of the sections (%llu)", s->name, (ull)end);
        for (uint64_t k = stop; k < next; k++)
            if (data[k] != 0)
                return FAIL("section %s: padding byte at %llu not zero", s->name, (ull)k);
        if (lie_hash_bytes(data + pos, (size_t)s->size, 0) != lie_cache_get_u64(t + 24))
            return FAIL("section %s: checksum mismatch", s->name);
        pos = next;
    }
    if (pos != end)
        return FAIL("%llu bytes between the last section and the file checksum", (ull)(end - pos));
    *n_out = (int)n;
    return LIE_OK;
}

lie_status lie_cache_sections(const unsigned char *data, size_t size, const char *name, lie_cache_section *out,
                              int *n, lie_error *err)
{
    return parse_container(data, size, name, out, n, err);
}

static const lie_cache_section *find(const lie_cache_section *s, int n, uint32_t id)
{
    for (int i = 0; i < n; i++)
        if (s[i].id == id)
            return &s[i];
    return NULL;
}

/* Counts from META that the other sections are checked against. */
typedef struct meta_counts {
    uint32_t n_tris, n_emitters, n_nodes, n_pool;
    uint64_t n_units, n_clusters;
} meta_counts;

static lie_status parse_meta(const unsigned char *p, uint64_t size, const char *name, lie_cache *c, meta_counts *m,
                             lie_error *err)
{
    if (size < LIE_CACHE_META_FIXED)
        return FAIL("section META: %llu bytes, shorter than its %u-byte header", (ull)size, LIE_CACHE_META_FIXED);
    const uint32_t path_len = lie_cache_get_u32(p + 40);
    if (size != LIE_CACHE_META_FIXED + (uint64_t)path_len)
        return FAIL("section META: %llu bytes do not hold a %u-byte scene path", (ull)size, path_len);
    if (lie_cache_get_u32(p + 44) != 0)
        return FAIL("section META: reserved field not zero");
    const unsigned char *path = p + LIE_CACHE_META_FIXED;
    if (memchr(path, 0, path_len))
        return FAIL("section META: the scene path holds a zero byte");
    m->n_tris = lie_cache_get_u32(p + 16);
    m->n_emitters = lie_cache_get_u32(p + 20);
    m->n_units = lie_cache_get_u64(p + 24);
    m->n_nodes = lie_cache_get_u32(p + 32);
    m->n_pool = lie_cache_get_u32(p + 36);
    if (m->n_emitters > INT_MAX)
        return FAIL("section META: %u emitters is beyond %d", m->n_emitters, INT_MAX);
    c->scene_hash = lie_cache_get_u64(p);
    c->state_hash = lie_cache_get_u64(p + 8);
    c->n_tris = m->n_tris;
    c->n_emitters = (int)m->n_emitters;
    c->scene_path = malloc((size_t)path_len + 1);
    if (!c->scene_path)
        return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
    memcpy(c->scene_path, path, path_len);
    c->scene_path[path_len] = 0;
    return LIE_OK;
}

static lie_status parse_params(const unsigned char *p, uint64_t size, uint32_t version, const char *name,
                               lie_build_params *bp, lie_error *err)
{
    const uint32_t want = version == 1   ? LIE_CACHE_PARAMS_SIZE_V1
                          : version == 2 ? LIE_CACHE_PARAMS_SIZE_V2
                          : version <= 5 ? LIE_CACHE_PARAMS_SIZE_V5
                          : version == 6 ? LIE_CACHE_PARAMS_SIZE_V6
                                         : LIE_CACHE_PARAMS_SIZE;
    if (size != want)
        return FAIL("section PARAMS: %llu bytes, expected %u", (ull)size, want);
    memset(bp, 0, sizeof *bp);
    bp->samples = lie_cache_get_u32(p);
    bp->max_samples = lie_cache_get_u32(p + 4);
    bp->max_blockers = lie_cache_get_u32(p + 8);
    bp->complex_cap = lie_cache_get_u32(p + 12);
    bp->min_patch = lie_cache_bits_f32(lie_cache_get_u32(p + 16));
    uint32_t mode = lie_cache_get_u32(p + 20);
    if (mode > LIE_BLOCKERS_CONSERVATIVE)
        return FAIL("section PARAMS: blocker mode %u is unknown", mode);
    bp->mode = (lie_blocker_mode)mode;
    /* version 1 caches were built splitting wherever a list was too long */
    bp->split_gain = version == 1 ? 0.0f : lie_cache_bits_f32(lie_cache_get_u32(p + 24));
    bp->threads = 0;
    /* the cost model came with version 3; it decides nothing in a cache
     * without views, and older caches have none */
    lie_build_params d = lie_build_params_default();
    bp->frames = version >= 3 ? lie_cache_get_u32(p + 28) : d.frames;
    bp->light_samples = version >= 3 ? lie_cache_get_u32(p + 32) : d.light_samples;
    bp->ns_segment = version >= 3 ? lie_cache_bits_f32(lie_cache_get_u32(p + 36)) : d.ns_segment;
    bp->ns_blocker = version >= 3 ? lie_cache_bits_f32(lie_cache_get_u32(p + 40)) : d.ns_blocker;
    bp->ns_ray = version >= 3 ? lie_cache_bits_f32(lie_cache_get_u32(p + 44)) : d.ns_ray;
    /* older caches predicted nothing: every unit was built */
    bp->complex_predict = version >= 6 ? lie_cache_get_u32(p + 48) : 0u;
    /* older whole builds had no model: every unit was built */
    bp->whole_pixels = version >= 7 ? lie_cache_get_u32(p + 52) : 0u;
    lie_error perr;
    if (lie_build_params_check(bp, &perr) != LIE_OK)
        return FAIL("section PARAMS: %s", perr.msg);
    return LIE_OK;
}

static lie_status parse_views(const unsigned char *p, uint64_t size, const char *name, lie_cache *c, lie_error *err)
{
    if (size < LIE_CACHE_VIEWS_FIXED)
        return FAIL("section VIEWS: %llu bytes, too short", (ull)size);
    uint32_t n = lie_cache_get_u32(p + 12);
    if (n == 0 || n > (size - LIE_CACHE_VIEWS_FIXED) / LIE_CACHE_VIEW_SIZE ||
        size != LIE_CACHE_VIEWS_FIXED + (uint64_t)LIE_CACHE_VIEW_SIZE * n)
        return FAIL("section VIEWS: %u views do not fill %llu bytes", n, (ull)size);
    uint32_t w = lie_cache_get_u32(p), h = lie_cache_get_u32(p + 4), d = lie_cache_get_u32(p + 8);
    if (w < 1 || w > LIE_CACHE_VIEW_MAX || h < 1 || h > LIE_CACHE_VIEW_MAX || d > 64)
        return FAIL("section VIEWS: image %ux%u or mirror depth %u out of range", w, h, d);
    lie_cache_views v = {calloc(n, sizeof *v.cams), (int)n, (int)w, (int)h, (int)d};
    if (!v.cams)
        return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
    const unsigned char *q = p + LIE_CACHE_VIEWS_FIXED;
    for (uint32_t i = 0; i < n; i++) {
        float f[12];
        for (int k = 0; k < 12; k++, q += 4)
            f[k] = lie_cache_bits_f32(lie_cache_get_u32(q));
        lie_camera *cam = &v.cams[i];
        cam->eye = (lie_vec3){f[0], f[1], f[2]};
        cam->forward = (lie_vec3){f[3], f[4], f[5]};
        cam->up = (lie_vec3){f[6], f[7], f[8]};
        cam->yfov = f[9];
        cam->aspect = f[10];
        cam->ymag = f[11];
    }
    const char *why = lie_cache_check_views(&v);
    if (why) {
        free(v.cams);
        return FAIL("section VIEWS: %s", why);
    }
    c->views = v;
    return LIE_OK;
}

static lie_status parse_edits(const unsigned char *p, uint64_t size, const char *name, lie_cache *c, lie_error *err)
{
    if (size < 4)
        return FAIL("section EDITS: %llu bytes, too short for its count", (ull)size);
    const uint32_t n = lie_cache_get_u32(p);
    if (n > (size - 4) / 8 || n > INT_MAX)
        return FAIL("section EDITS: %u edits cannot fit in %llu bytes", n, (ull)size);
    c->edits = calloc((size_t)n + 1, sizeof *c->edits);
    if (!c->edits)
        return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
    uint64_t pos = 4;
    for (uint32_t i = 0; i < n; i++) {
        if (size - pos < 8)
            return FAIL("section EDITS: edit %u: truncated", i);
        const uint32_t nl = lie_cache_get_u32(p + pos), tl = lie_cache_get_u32(p + pos + 4);
        pos += 8;
        if ((uint64_t)nl + tl > size - pos)
            return FAIL("section EDITS: edit %u: %u + %u bytes pass the end of the section", i, nl, tl);
        if (memchr(p + pos, 0, nl))
            return FAIL("section EDITS: edit %u: the name holds a zero byte", i);
        lie_cache_edit *ed = &c->edits[i];
        ed->name = malloc((size_t)nl + 1);
        ed->text = malloc((size_t)tl + 1);
        c->n_edits = (int)i + 1;
        if (!ed->name || !ed->text)
            return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
        memcpy(ed->name, p + pos, nl);
        ed->name[nl] = 0;
        memcpy(ed->text, p + pos + nl, tl);
        ed->text[tl] = 0;
        ed->size = tl;
        pos += (uint64_t)nl + tl;
    }
    if (pos != size)
        return FAIL("section EDITS: %llu bytes after the last edit", (ull)(size - pos));
    return LIE_OK;
}

static lie_status parse_emitters(const unsigned char *p, uint64_t size, uint32_t version, const char *name,
                                 meta_counts *m, lie_cache *c, lie_error *err)
{
    const uint32_t rec = version < 4 ? LIE_CACHE_EMITTER_SIZE_V3 : LIE_CACHE_EMITTER_SIZE;
    if (size != (uint64_t)rec * m->n_emitters)
        return FAIL("section EMITTERS: %llu bytes for %u emitters, expected %llu", (ull)size, m->n_emitters,
                    (ull)rec * m->n_emitters);
    c->emitters = calloc((size_t)m->n_emitters + 1, sizeof *c->emitters);
    if (!c->emitters)
        return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
    m->n_clusters = 0;
    for (uint32_t e = 0; e < m->n_emitters; e++, p += rec) {
        lie_cache_emitter *em = &c->emitters[e];
        em->type = lie_cache_get_u32(p);
        em->node = (int32_t)lie_cache_get_u32(p + 4);
        em->first_tri = lie_cache_get_u32(p + 8);
        em->n_tris = lie_cache_get_u32(p + 12);
        em->n_clusters = version < 4 ? 1 : lie_cache_get_u32(p + 16);
        em->partition = version < 4 ? 0 : lie_cache_get_u32(p + 20);
        const char *why = lie_cache_check_emitter(em, m->n_tris);
        if (why)
            return FAIL("section EMITTERS: emitter %u: %s", e, why);
        m->n_clusters += em->n_clusters;
    }
    if (m->n_clusters > INT_MAX)
        return FAIL("section EMITTERS: %llu clusters is beyond %d", (ull)m->n_clusters, INT_MAX);
    if (m->n_units != (uint64_t)m->n_tris * m->n_clusters)
        return FAIL("section META: %llu units is not %u triangles x %llu clusters", (ull)m->n_units, m->n_tris,
                    (ull)m->n_clusters);
    return LIE_OK;
}

/* ROOTS, NODES, POOL into a new env; the structure is checked after. */
static lie_status parse_env(const unsigned char *data, uint32_t version, const lie_cache_section *roots,
                            const lie_cache_section *nodes, const lie_cache_section *pool, const char *name,
                            const meta_counts *m, lie_env *env, lie_error *err)
{
    if (roots->size % 4 != 0 || roots->size / 4 != m->n_units)
        return FAIL("section ROOTS: %llu bytes for %llu units, expected 4 per unit", (ull)roots->size,
                    (ull)m->n_units);
    if (nodes->size != (uint64_t)LIE_CACHE_NODE_SIZE * m->n_nodes)
        return FAIL("section NODES: %llu bytes for %u nodes, expected %u per node", (ull)nodes->size, m->n_nodes,
                    LIE_CACHE_NODE_SIZE);
    if (pool->size != 4 * (uint64_t)m->n_pool)
        return FAIL("section POOL: %llu bytes for %u entries, expected 4 per entry", (ull)pool->size, m->n_pool);
    /* every count is now bounded by bytes present in memory */
    const size_t n_units = (size_t)m->n_units;
    /* from version 6, a lone unit is a tag: it shares the leaf its class
     * has after the file's nodes, as a build lays an env out (lib/lie/lie.h,
     * lie_pnode_lone); before, every tag is a root beyond the nodes */
    const unsigned char *p = data + roots->offset;
    int used_unlit = 0, used_none = 0;
    for (size_t u = 0; version >= 6 && u < n_units; u++, p += 4) {
        uint32_t r = lie_cache_get_u32(p);
        used_unlit |= r == LIE_CACHE_ROOT_LONE_UNLIT;
        used_none |= r == LIE_CACHE_ROOT_LONE_NONE;
    }
    const uint32_t shared_unlit = m->n_nodes, shared_none = m->n_nodes + (uint32_t)used_unlit;
    const uint32_t n_mem = m->n_nodes + (uint32_t)used_unlit + (uint32_t)used_none;
    if (n_mem < m->n_nodes)
        return FAIL("section META: %u nodes leave no room for the shared leaves", m->n_nodes);
    env->root = malloc(sizeof *env->root * (n_units + 1));
    env->nodes = malloc(sizeof *env->nodes * ((size_t)n_mem + 1));
    env->pool = malloc(sizeof *env->pool * ((size_t)m->n_pool + 1));
    if (!env->root || !env->nodes || !env->pool)
        return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
    p = data + roots->offset;
    for (size_t u = 0; u < n_units; u++, p += 4) {
        uint32_t r = lie_cache_get_u32(p);
        if (version >= 6 && r == LIE_CACHE_ROOT_LONE_UNLIT)
            r = shared_unlit;
        else if (version >= 6 && r == LIE_CACHE_ROOT_LONE_NONE)
            r = shared_none;
        else if (r >= m->n_nodes)
            return FAIL("section ROOTS: unit %zu: root %u beyond the %u nodes", u, r, m->n_nodes);
        env->root[u] = r;
    }
    memset(env->nodes + m->n_nodes, 0, sizeof *env->nodes * (size_t)(n_mem - m->n_nodes));
    if (used_unlit)
        env->nodes[shared_unlit].cls = LIE_CLASS_UNLIT;
    if (used_none)
        env->nodes[shared_none].cls = LIE_CLASS_NONE;
    p = data + nodes->offset;
    for (uint32_t i = 0; i < m->n_nodes; i++, p += LIE_CACHE_NODE_SIZE) {
        lie_pnode *x = &env->nodes[i];
        x->child = lie_cache_get_u32(p);
        x->cls = lie_cache_get_u32(p + 4);
        x->quality = lie_cache_get_u32(p + 8);
        x->list = lie_cache_get_u32(p + 12);
        x->count = lie_cache_get_u32(p + 16);
    }
    p = data + pool->offset;
    for (uint32_t i = 0; i < m->n_pool; i++, p += 4)
        env->pool[i] = lie_cache_get_u32(p);
    env->n_tris = m->n_tris;
    env->n_clusters = (int)m->n_clusters;
    env->n_nodes = n_mem;
    env->n_pool = m->n_pool;
    return lie_cache_check_env(env, LIE_ERR_FORMAT, name, "", err);
}

lie_status lie_cache_decode(const unsigned char *data, size_t size, const char *name, lie_cache **out,
                            lie_error *err)
{
    *out = NULL;
    if (!name)
        name = "cache";
    if (!data)
        size = 0;
    static const unsigned char empty[1];
    if (size == 0)
        data = empty;
    lie_cache_section sec[LIE_CACHE_MAX_SECTIONS];
    int n = 0;
    lie_status st = parse_container(data, size, name, sec, &n, err);
    if (st != LIE_OK)
        return st;
    static const uint32_t required[] = {LIE_CACHE_ID_META,  LIE_CACHE_ID_PARAMS, LIE_CACHE_ID_EDITS,
                                        LIE_CACHE_ID_EMITTERS, LIE_CACHE_ID_ROOTS, LIE_CACHE_ID_NODES,
                                        LIE_CACHE_ID_POOL};
    const lie_cache_section *s[7];
    for (int i = 0; i < 7; i++) {
        s[i] = find(sec, n, required[i]);
        if (!s[i]) {
            char nm[16];
            lie_cache_section_name(required[i], nm);
            return FAIL("required section %s missing", nm);
        }
    }
    lie_cache *c = calloc(1, sizeof *c);
    lie_env *env = c ? calloc(1, sizeof *env) : NULL;
    if (!env) {
        free(c);
        return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
    }
    c->env = env;
    c->version = lie_cache_get_u32(data + 8);
    meta_counts m = {0, 0, 0, 0, 0, 0};
    st = parse_meta(data + s[0]->offset, s[0]->size, name, c, &m, err);
    if (st == LIE_OK)
        st = parse_params(data + s[1]->offset, s[1]->size, lie_cache_get_u32(data + 8), name, &env->params, err);
    if (st == LIE_OK)
        st = parse_edits(data + s[2]->offset, s[2]->size, name, c, err);
    if (st == LIE_OK)
        st = parse_emitters(data + s[3]->offset, s[3]->size, lie_cache_get_u32(data + 8), name, &m, c, err);
    if (st == LIE_OK)
        st = parse_env(data, c->version, s[4], s[5], s[6], name, &m, env, err);
    const lie_cache_section *sv = find(sec, n, LIE_CACHE_ID_VIEWS);
    if (st == LIE_OK && sv && lie_cache_get_u32(data + 8) >= 3)
        st = parse_views(data + sv->offset, sv->size, name, c, err);
    if (st != LIE_OK) {
        lie_cache_destroy(c);
        return st;
    }
    env->scene_hash = c->state_hash;
    env->partial = (lie_cache_get_u32(data + 16) & LIE_CACHE_OPT_PARTIAL) != 0;
    *out = c;
    return LIE_OK;
}
