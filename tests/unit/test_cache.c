/* SPDX-License-Identifier: Apache-2.0 */
/* lib/cache: round trips, byte-exact determinism, an independent encoder
 * written from formats/lie-cache.md, and rejection of every damaged,
 * truncated, misplaced, newer or structurally invalid file — without
 * crashing and without allocating what the file does not hold.
 * Size: long as the format is: one test per field and section a reader must
 * check (CONTRIBUTING.md, Tests: one file per module). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "lie.h"
#include "fixtures.h"

/* ---- fixtures ------------------------------------------------------------- */

/* A cache as lie-build makes it, from a scene. */
static lie_cache *cache_from_scene(const lie_scene *s, const char *path, lie_blocker_mode mode)
{
    lie_error err;
    lie_rt *rt = NULL;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_build_params p = lie_build_params_default();
    p.samples = 8;
    p.max_samples = 16;
    p.max_blockers = 1;
    p.min_patch = 0.01f;
    p.split_gain = 0.0f; /* every split kept: the fixtures need interior nodes */
    p.mode = mode;
    p.threads = 2;
    lie_cache *c = calloc(1, sizeof *c);
    assert_non_null(c);
    lie_build_stats st;
    assert_int_equal(lie_env_build(s, rt, &p, NULL, &c->env, &st, &err), LIE_OK);
    lie_rt_destroy(rt);
    c->scene_path = strdup(path);
    c->scene_hash = s->hash;
    assert_int_equal(lie_cache_set_state(c, s, &err), LIE_OK);
    return c;
}

static lie_cache *small_cache(void)
{
    lie_scene *s = occluder_scene();
    lie_cache *c = cache_from_scene(s, "scenes/occluder.gltf", LIE_BLOCKERS_SAMPLED);
    lie_scene_destroy(s);
    return c;
}

static lie_cache *cornell_cache(lie_blocker_mode mode)
{
    lie_scene *s = NULL;
    lie_error err;
    lie_scene_options so = lie_scene_options_default();
    assert_int_equal(lie_scene_load(TEST_SCENES "/cornell.gltf", &so, &s, &err), LIE_OK);
    lie_cache *c = cache_from_scene(s, TEST_SCENES "/cornell.gltf", mode);
    lie_scene_destroy(s);
    return c;
}

static void add_edit(lie_cache *c, const char *name, const void *text, size_t size)
{
    c->edits = realloc(c->edits, sizeof *c->edits * (size_t)(c->n_edits + 1));
    lie_cache_edit *e = &c->edits[c->n_edits++];
    e->name = strdup(name);
    e->text = malloc(size + 1);
    memcpy(e->text, text, size);
    e->size = size;
}

static void encode(const lie_cache *c, unsigned char **data, size_t *size)
{
    lie_error err;
    assert_int_equal(lie_cache_encode(c, data, size, &err), LIE_OK);
}

/* Decode must fail with `status`, one line, naming the input. */
static void expect_reject(const unsigned char *data, size_t size, lie_status status, const char *needle)
{
    lie_cache *c = (lie_cache *)1;
    lie_error err;
    memset(&err, 0, sizeof err);
    lie_status st = lie_cache_decode(data, size, "t.lie", &c, &err);
    if (st != status || (needle && !strstr(err.msg, needle)))
        print_error("expected status %d with '%s', got %d: %s\n", status, needle ? needle : "", st, err.msg);
    assert_int_equal(st, status);
    assert_null(c);
    assert_string_equal(err.file, "t.lie");
    assert_null(strchr(err.msg, '\n'));
    assert_true(err.msg[0] != 0);
    if (needle)
        assert_non_null(strstr(err.msg, needle));
}

static lie_cache *decode_ok(const unsigned char *data, size_t size)
{
    lie_cache *c = NULL;
    lie_error err;
    lie_status st = lie_cache_decode(data, size, "t.lie", &c, &err);
    if (st != LIE_OK)
        print_error("decode failed: %s\n", err.msg);
    assert_int_equal(st, LIE_OK);
    assert_non_null(c);
    return c;
}

/* ---- little-endian helpers and an independent encoder from the spec ---- */

static void put32(unsigned char *p, uint32_t v)
{
    for (int k = 0; k < 4; k++)
        p[k] = (unsigned char)(v >> (8 * k));
}
static void put64(unsigned char *p, uint64_t v)
{
    for (int k = 0; k < 8; k++)
        p[k] = (unsigned char)(v >> (8 * k));
}
static uint32_t get32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static uint64_t get64(const unsigned char *p) { return get32(p) | (uint64_t)get32(p + 4) << 32; }
static uint32_t id4(const char *s) { return get32((const unsigned char *)s); }

typedef struct sect {
    uint32_t id;
    unsigned char *data;
    size_t size;
} sect;

/* The container of formats/lie-cache.md around the given sections. */
static void assemble(const sect *s, int n, unsigned char **out, size_t *size)
{
    size_t pos = 32 + 32 * (size_t)n;
    size_t total = pos;
    for (int i = 0; i < n; i++)
        total = ((total + s[i].size) + 7) & ~(size_t)7;
    total += 8;
    unsigned char *b = calloc(1, total);
    assert_non_null(b);
    memcpy(b, "LIECACHE", 8);
    put32(b + 8, 7);
    put32(b + 20, (uint32_t)n);
    put64(b + 24, total);
    for (int i = 0; i < n; i++) {
        unsigned char *t = b + 32 + 32 * (size_t)i;
        put32(t, s[i].id);
        put64(t + 8, pos);
        put64(t + 16, s[i].size);
        if (s[i].size)
            memcpy(b + pos, s[i].data, s[i].size);
        put64(t + 24, lie_hash_bytes(b + pos, s[i].size, 0));
        pos = (pos + s[i].size + 7) & ~(size_t)7;
    }
    put64(b + total - 8, lie_hash_bytes(b, total - 8, 0));
    *out = b;
    *size = total;
}

enum { META, PARM, EDIT, EMIT, ROOT, NODE, POOL, N_SECT };

/* The trees in the file's canonical order (formats/lie-cache.md): per unit
 * its root, then depth first, a split node's children appended when it is
 * visited, lists as their leaves are visited; a lone unit is a tag in
 * ROOTS (version 6), or with `own_lone` its own node (versions 1 to 5). */
typedef struct spec_trees {
    const lie_env *env;
    uint32_t *root, n_nodes, n_pool;
    lie_pnode *nodes;
    uint32_t *pool;
} spec_trees;

static void spec_copy(spec_trees *t, uint32_t from, uint32_t idx)
{
    lie_pnode x = t->env->nodes[from];
    if (x.child) {
        uint32_t first = t->n_nodes, oc = x.child;
        t->n_nodes += 4;
        x.child = first;
        t->nodes[idx] = x;
        for (uint32_t k = 0; k < 4; k++)
            spec_copy(t, oc + k, first + k);
        return;
    }
    if (x.cls == LIE_CLASS_PARTIAL) {
        memcpy(t->pool + t->n_pool, t->env->pool + x.list, sizeof *t->pool * x.count);
        x.list = t->n_pool;
        t->n_pool += x.count;
    }
    t->nodes[idx] = x;
}

static void spec_lay_out(const lie_env *env, int own_lone, spec_trees *t)
{
    size_t units = (size_t)env->n_tris * (size_t)env->n_clusters;
    memset(t, 0, sizeof *t);
    t->env = env;
    t->root = calloc(units + 1, sizeof *t->root);
    t->nodes = calloc((size_t)env->n_nodes + units + 1, sizeof *t->nodes);
    t->pool = calloc((size_t)env->n_pool + 1, sizeof *t->pool);
    for (size_t u = 0; u < units; u++) {
        const lie_pnode *x = &env->nodes[env->root[u]];
        int lone = !x->child && (x->cls == LIE_CLASS_UNLIT || x->cls == LIE_CLASS_NONE) && !x->quality &&
                   !x->list && !x->count;
        if (lone && !own_lone) {
            t->root[u] = x->cls == LIE_CLASS_UNLIT ? 0xFFFFFFFFu : 0xFFFFFFFEu;
            continue;
        }
        t->root[u] = t->n_nodes++;
        spec_copy(t, env->root[u], t->root[u]);
    }
}

static void spec_free(spec_trees *t)
{
    free(t->root);
    free(t->nodes);
    free(t->pool);
}

/* The nodes a version 6 file holds for env. */
static uint32_t file_nodes(const lie_env *env)
{
    spec_trees t;
    spec_lay_out(env, 0, &t);
    uint32_t n = t.n_nodes;
    spec_free(&t);
    return n;
}

/* The seven sections of a cache, field by field as the spec lists them
 * (the trees as version 6 writes them, or with `own_lone` as version 5). */
enum { SPEC_V6, SPEC_V5, SPEC_RAW /* the env's arrays as they are: synthetic layouts */ };
static void spec_sections_as(const lie_cache *c, int how, sect s[N_SECT])
{
    spec_trees tr;
    memset(&tr, 0, sizeof tr);
    lie_env laid = *c->env;
    if (how != SPEC_RAW) {
        spec_lay_out(c->env, how == SPEC_V5, &tr);
        laid.root = tr.root;
        laid.nodes = tr.nodes;
        laid.pool = tr.pool;
        laid.n_nodes = tr.n_nodes;
        laid.n_pool = tr.n_pool;
    }
    const lie_env *env = &laid;
    size_t pl = strlen(c->scene_path), units = (size_t)c->n_tris * (size_t)env->n_clusters;
    s[META] = (sect){id4("META"), calloc(1, 48 + pl), 48 + pl};
    put64(s[META].data, c->scene_hash);
    put64(s[META].data + 8, c->state_hash);
    put32(s[META].data + 16, c->n_tris);
    put32(s[META].data + 20, (uint32_t)c->n_emitters);
    put64(s[META].data + 24, units);
    put32(s[META].data + 32, env->n_nodes);
    put32(s[META].data + 36, env->n_pool);
    put32(s[META].data + 40, (uint32_t)pl);
    memcpy(s[META].data + 48, c->scene_path, pl);
    s[PARM] = (sect){id4("PARM"), calloc(1, 56), 56};
    put32(s[PARM].data, env->params.samples);
    put32(s[PARM].data + 4, env->params.max_samples);
    put32(s[PARM].data + 8, env->params.max_blockers);
    put32(s[PARM].data + 12, env->params.complex_cap);
    uint32_t mp;
    memcpy(&mp, &env->params.min_patch, 4);
    put32(s[PARM].data + 16, mp);
    put32(s[PARM].data + 20, (uint32_t)env->params.mode);
    uint32_t sg;
    memcpy(&sg, &env->params.split_gain, 4);
    put32(s[PARM].data + 24, sg);
    put32(s[PARM].data + 28, env->params.frames);
    put32(s[PARM].data + 32, env->params.light_samples);
    const float *ns[3] = {&env->params.ns_segment, &env->params.ns_blocker, &env->params.ns_ray};
    for (int k = 0; k < 3; k++) {
        memcpy(&sg, ns[k], 4);
        put32(s[PARM].data + 36 + 4 * k, sg);
    }
    put32(s[PARM].data + 48, env->params.complex_predict);
    put32(s[PARM].data + 52, env->params.whole_pixels);
    size_t es = 4;
    for (int i = 0; i < c->n_edits; i++)
        es += 8 + strlen(c->edits[i].name) + c->edits[i].size;
    s[EDIT] = (sect){id4("EDIT"), calloc(1, es), es};
    put32(s[EDIT].data, (uint32_t)c->n_edits);
    unsigned char *p = s[EDIT].data + 4;
    for (int i = 0; i < c->n_edits; i++) {
        size_t nl = strlen(c->edits[i].name);
        put32(p, (uint32_t)nl);
        put32(p + 4, (uint32_t)c->edits[i].size);
        memcpy(p + 8, c->edits[i].name, nl);
        memcpy(p + 8 + nl, c->edits[i].text, c->edits[i].size);
        p += 8 + nl + c->edits[i].size;
    }
    s[EMIT] = (sect){id4("EMIT"), calloc(1, 24 * (size_t)c->n_emitters + 1), 24 * (size_t)c->n_emitters};
    for (int e = 0; e < c->n_emitters; e++) {
        put32(s[EMIT].data + 24 * e, c->emitters[e].type);
        put32(s[EMIT].data + 24 * e + 4, (uint32_t)c->emitters[e].node);
        put32(s[EMIT].data + 24 * e + 8, c->emitters[e].first_tri);
        put32(s[EMIT].data + 24 * e + 12, c->emitters[e].n_tris);
        put32(s[EMIT].data + 24 * e + 16, c->emitters[e].n_clusters);
        put32(s[EMIT].data + 24 * e + 20, c->emitters[e].partition);
    }
    s[ROOT] = (sect){id4("ROOT"), calloc(1, 4 * units + 1), 4 * units};
    for (size_t u = 0; u < units; u++)
        put32(s[ROOT].data + 4 * u, env->root[u]);
    s[NODE] = (sect){id4("NODE"), calloc(1, 20 * (size_t)env->n_nodes + 1), 20 * (size_t)env->n_nodes};
    for (uint32_t i = 0; i < env->n_nodes; i++) {
        const lie_pnode *x = &env->nodes[i];
        uint32_t f[5] = {x->child, x->cls, x->quality, x->list, x->count};
        for (int k = 0; k < 5; k++)
            put32(s[NODE].data + 20 * (size_t)i + 4 * k, f[k]);
    }
    s[POOL] = (sect){id4("POOL"), calloc(1, 4 * (size_t)env->n_pool + 1), 4 * (size_t)env->n_pool};
    for (uint32_t i = 0; i < env->n_pool; i++)
        put32(s[POOL].data + 4 * i, env->pool[i]);
    spec_free(&tr);
}

static void spec_sections(const lie_cache *c, sect s[N_SECT]) { spec_sections_as(c, SPEC_V6, s); }

static void free_sections(sect *s, int n)
{
    for (int i = 0; i < n; i++)
        free(s[i].data);
}

/* Recompute every in-range section checksum and the file checksum, so a
 * crafted change reaches the checks behind them. */
static void reseal(unsigned char *b, size_t size)
{
    uint32_t n = get32(b + 20);
    for (uint32_t i = 0; i < n && 32 + 32 * (uint64_t)(i + 1) <= size - 8; i++) {
        unsigned char *t = b + 32 + 32 * (size_t)i;
        uint64_t off = get64(t + 8), sz = get64(t + 16);
        if (off <= size && sz <= size - off)
            put64(t + 24, lie_hash_bytes(b + off, (size_t)sz, 0));
    }
    put64(b + size - 8, lie_hash_bytes(b, size - 8, 0));
}

/* Where section `id` of an encoding starts (its table entry in *entry). */
static size_t section_at(const unsigned char *b, const char *id, unsigned char **entry)
{
    uint32_t n = get32(b + 20);
    for (uint32_t i = 0; i < n; i++) {
        const unsigned char *t = b + 32 + 32 * (size_t)i;
        if (get32(t) == id4(id)) {
            if (entry)
                *entry = (unsigned char *)t;
            return (size_t)get64(t + 8);
        }
    }
    fail_msg("no section %s", id);
    return 0;
}

/* ---- round trips ---------------------------------------------------------- */

static void assert_caches_equal(const lie_cache *a, const lie_cache *b)
{
    assert_string_equal(a->scene_path, b->scene_path);
    assert_true(a->scene_hash == b->scene_hash);
    assert_true(a->state_hash == b->state_hash);
    assert_int_equal(a->n_tris, b->n_tris);
    assert_int_equal(a->n_emitters, b->n_emitters);
    for (int e = 0; e < a->n_emitters; e++) {
        assert_int_equal(a->emitters[e].type, b->emitters[e].type);
        assert_int_equal(a->emitters[e].node, b->emitters[e].node);
        assert_int_equal(a->emitters[e].first_tri, b->emitters[e].first_tri);
        assert_int_equal(a->emitters[e].n_tris, b->emitters[e].n_tris);
    }
    assert_int_equal(a->n_edits, b->n_edits);
    for (int i = 0; i < a->n_edits; i++) {
        assert_string_equal(a->edits[i].name, b->edits[i].name);
        assert_int_equal(a->edits[i].size, b->edits[i].size);
        assert_memory_equal(a->edits[i].text, b->edits[i].text, a->edits[i].size);
    }
    const lie_env *x = a->env, *y = b->env;
    assert_int_equal(x->n_tris, y->n_tris);
    assert_int_equal(x->n_clusters, y->n_clusters);
    assert_int_equal(x->n_nodes, y->n_nodes);
    assert_int_equal(x->n_pool, y->n_pool);
    assert_true(x->scene_hash == y->scene_hash);
    assert_int_equal(x->params.samples, y->params.samples);
    assert_int_equal(x->params.max_samples, y->params.max_samples);
    assert_int_equal(x->params.max_blockers, y->params.max_blockers);
    assert_int_equal(x->params.complex_cap, y->params.complex_cap);
    assert_memory_equal(&x->params.min_patch, &y->params.min_patch, sizeof(float));
    assert_int_equal(x->params.mode, y->params.mode);
    size_t units = (size_t)x->n_tris * (size_t)x->n_clusters;
    assert_memory_equal(x->root, y->root, units * sizeof *x->root);
    for (uint32_t i = 0; i < x->n_nodes; i++) {
        assert_int_equal(x->nodes[i].child, y->nodes[i].child);
        assert_int_equal(x->nodes[i].cls, y->nodes[i].cls);
        assert_int_equal(x->nodes[i].quality, y->nodes[i].quality);
        assert_int_equal(x->nodes[i].list, y->nodes[i].list);
        assert_int_equal(x->nodes[i].count, y->nodes[i].count);
    }
    if (x->n_pool)
        assert_memory_equal(x->pool, y->pool, x->n_pool * sizeof *x->pool);
}

static void test_encode_decode_encode_gives_identical_bytes(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    unsigned char *a, *b;
    size_t na, nb;
    encode(c, &a, &na);
    lie_cache *d = decode_ok(a, na);
    encode(d, &b, &nb);
    assert_int_equal(na, nb);
    assert_memory_equal(a, b, na);
    /* and encoding is a pure function of the content */
    free(b);
    encode(c, &b, &nb);
    assert_memory_equal(a, b, na);
    free(a);
    free(b);
    lie_cache_destroy(c);
    lie_cache_destroy(d);
}

static void test_decode_preserves_every_field_of_a_real_env(void **state)
{
    (void)state;
    for (int mode = 0; mode < 2; mode++) {
        lie_cache *c = cornell_cache((lie_blocker_mode)mode);
        assert_true(c->env->n_pool > 0);
        unsigned char *a;
        size_t na;
        encode(c, &a, &na);
        lie_cache *d = decode_ok(a, na);
        assert_caches_equal(c, d);
        assert_int_equal(d->env->params.threads, 0);
        free(a);
        lie_cache_destroy(c);
        lie_cache_destroy(d);
    }
}

static void test_edit_log_round_trips_byte_exact(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    add_edit(c, "move-cube.yaml", "move:\n  node: Cube\n", 20);
    add_edit(c, "binary\xc3\xa9.yaml", "a\0b\xff", 4);
    add_edit(c, "", "", 0);
    unsigned char *a, *b;
    size_t na, nb;
    encode(c, &a, &na);
    lie_cache *d = decode_ok(a, na);
    assert_caches_equal(c, d);
    assert_int_equal(d->edits[0].text[d->edits[0].size], 0); /* terminated for convenience */
    encode(d, &b, &nb);
    assert_int_equal(na, nb);
    assert_memory_equal(a, b, na);
    free(a);
    free(b);
    lie_cache_destroy(c);
    lie_cache_destroy(d);
}

static void test_encoder_written_from_the_spec_gives_the_same_bytes(void **state)
{
    (void)state;
    lie_cache *c = cornell_cache(LIE_BLOCKERS_SAMPLED);
    add_edit(c, "e.yaml", "x: 1\n", 5);
    sect s[N_SECT];
    spec_sections(c, s);
    unsigned char *a, *b;
    size_t na, nb;
    assemble(s, N_SECT, &a, &na);
    encode(c, &b, &nb);
    assert_int_equal(na, nb);
    assert_memory_equal(a, b, na);
    free_sections(s, N_SECT);
    free(a);
    free(b);
    lie_cache_destroy(c);
}

static void test_sections_lists_the_table_in_file_order(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    unsigned char *a;
    size_t na;
    encode(c, &a, &na);
    lie_cache_section sec[LIE_CACHE_MAX_SECTIONS];
    int n = 0;
    lie_error err;
    assert_int_equal(lie_cache_sections(a, na, "t.lie", sec, &n, &err), LIE_OK);
    assert_int_equal(n, 7);
    const char *names[7] = {"META", "PARAMS", "EDITS", "EMITTERS", "ROOTS", "NODES", "POOL"};
    uint64_t end = 32 + 32 * 7;
    for (int i = 0; i < 7; i++) {
        assert_string_equal(sec[i].name, names[i]);
        assert_int_equal(sec[i].offset, end);
        assert_int_equal(sec[i].offset % 8, 0);
        end = (sec[i].offset + sec[i].size + 7) & ~(uint64_t)7;
    }
    assert_int_equal(end + 8, na);
    assert_int_equal(sec[5].size, 20 * (uint64_t)file_nodes(c->env));
    free(a);
    lie_cache_destroy(c);
}

static lie_status to_stream(void *ctx, const lie_pnode *nodes, const uint32_t *pool, uint32_t root)
{
    lie_error err;
    return lie_cache_stream_unit(ctx, nodes, pool, root, &err);
}

/* The file at path, which must hold exactly `size` bytes equal to want. */
static void assert_file_bytes(const char *path, const unsigned char *want, size_t size)
{
    unsigned char *got = NULL;
    size_t n = 0;
    lie_error err;
    assert_int_equal(lie_read_file(path, &got, &n, &err), LIE_OK);
    assert_int_equal(n, size);
    assert_memory_equal(got, want, size);
    free(got);
}

/* A cache streamed unit by unit (lie_cache_stream, as lie-build writes a
 * whole build) is byte for byte the encoder's: from an env's units, with
 * an edit log, partial or not; and straight from a build's sink, which
 * hands units over in order as triangles are done, on two threads. */
static void test_stream_gives_the_bytes_of_encode(void **state)
{
    (void)state;
    char dir[] = "/tmp/lie-test-stream.XXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/s.lie", dir);
    lie_scene *s = NULL;
    lie_error err;
    lie_scene_options so = lie_scene_options_default();
    assert_int_equal(lie_scene_load(TEST_SCENES "/cornell.gltf", &so, &s, &err), LIE_OK);
    lie_cache *c = cache_from_scene(s, TEST_SCENES "/cornell.gltf", LIE_BLOCKERS_SAMPLED);
    static const char edit[] = "- move: {node: TallBlock, by: [0, 0, 0]}\n";
    add_edit(c, "e.yaml", edit, sizeof edit - 1);
    const size_t units = (size_t)c->n_tris * (size_t)c->env->n_clusters;
    for (int partial = 0; partial < 2; partial++) {
        c->env->partial = partial;
        unsigned char *a;
        size_t na, bytes = 0;
        encode(c, &a, &na);
        lie_cache_stream *st = NULL;
        assert_int_equal(lie_cache_stream_open(path, c, &st, &err), LIE_OK);
        for (size_t u = 0; u < units; u++)
            assert_int_equal(lie_cache_stream_unit(st, c->env->nodes, c->env->pool, c->env->root[u], &err), LIE_OK);
        assert_int_equal(lie_cache_stream_close(st, partial, &bytes, &err), LIE_OK);
        assert_int_equal(bytes, na);
        assert_file_bytes(path, a, na);
        free(a);
    }
    c->env->partial = 0;
    /* through a build's sink: the units of c's env again */
    lie_rt *rt = NULL;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_build_params p = c->env->params;
    p.threads = 2;
    lie_cache_stream *st = NULL;
    assert_int_equal(lie_cache_stream_open(path, c, &st, &err), LIE_OK);
    lie_build_control ctl;
    memset(&ctl, 0, sizeof ctl);
    ctl.sink = to_stream;
    ctl.sink_ctx = st;
    lie_env *built = NULL;
    assert_int_equal(lie_env_build_with(s, rt, &p, &ctl, &built, NULL, &err), LIE_OK);
    assert_null(built->root); /* the units went to the sink */
    assert_int_equal(built->partial, 0);
    size_t bytes = 0;
    assert_int_equal(lie_cache_stream_close(st, built->partial, &bytes, &err), LIE_OK);
    lie_env_destroy(built);
    unsigned char *a;
    size_t na;
    encode(c, &a, &na);
    assert_file_bytes(path, a, na);
    free(a);
    /* a stream given too few units writes nothing */
    assert_int_equal(remove(path), 0);
    assert_int_equal(lie_cache_stream_open(path, c, &st, &err), LIE_OK);
    assert_int_equal(lie_cache_stream_unit(st, c->env->nodes, c->env->pool, c->env->root[0], &err), LIE_OK);
    assert_int_equal(lie_cache_stream_close(st, 0, &bytes, &err), LIE_ERR_ARG);
    assert_int_equal(access(path, F_OK), -1);
    assert_int_equal(rmdir(dir), 0);
    lie_rt_destroy(rt);
    lie_cache_destroy(c);
    lie_scene_destroy(s);
}

static void test_write_then_read_round_trips_and_leaves_no_temporary(void **state)
{
    (void)state;
    char dir[] = "/tmp/lie-test-cache.XXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/out.lie", dir);
    lie_cache *c = small_cache();
    lie_error err;
    size_t bytes = 0;
    assert_int_equal(lie_cache_write(path, c, &bytes, &err), LIE_OK);
    struct stat stt;
    assert_int_equal(stat(path, &stt), 0);
    assert_int_equal((size_t)stt.st_size, bytes);
    lie_cache *d = NULL;
    assert_int_equal(lie_cache_read(path, &d, &err), LIE_OK);
    assert_caches_equal(c, d);
    lie_cache_destroy(d);
    /* a failed write reports the path and leaves nothing behind */
    char bad[300];
    snprintf(bad, sizeof bad, "%s/no/such/dir/out.lie", dir);
    assert_int_equal(lie_cache_write(bad, c, &bytes, &err), LIE_ERR_IO);
    assert_string_equal(err.file, bad);
    assert_int_equal(lie_cache_read(bad, &d, &err), LIE_ERR_IO);
    assert_null(d);
    unlink(path);
    assert_int_equal(rmdir(dir), 0); /* empty: no temporary file left */
    lie_cache_destroy(c);
}

static void test_encode_refuses_what_a_reader_would_reject(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    unsigned char *a = NULL;
    size_t na = 0;
    lie_error err;
    uint32_t keep = c->env->nodes[0].cls;
    c->env->nodes[0].cls = 9;
    assert_int_equal(lie_cache_encode(c, &a, &na, &err), LIE_ERR_ARG);
    assert_null(a);
    assert_non_null(strstr(err.msg, "class 9"));
    c->env->nodes[0].cls = keep;
    c->state_hash ^= 1;
    assert_int_equal(lie_cache_encode(c, &a, &na, &err), LIE_ERR_ARG);
    c->state_hash ^= 1;
    c->env->params.min_patch = 0.0f;
    assert_int_equal(lie_cache_encode(c, &a, &na, &err), LIE_ERR_ARG);
    c->env->params.min_patch = 0.01f;
    c->emitters[0].n_tris = 100;
    assert_int_equal(lie_cache_encode(c, &a, &na, &err), LIE_ERR_ARG);
    lie_cache_destroy(c);
}

/* ---- damage --------------------------------------------------------------- */

static void test_every_single_bit_flip_is_rejected(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    add_edit(c, "e.yaml", "x: 1\n", 5);
    unsigned char *a;
    size_t na;
    encode(c, &a, &na);
    assert_true(na < 16384);
    for (size_t i = 0; i < na; i++) {
        for (int bit = 0; bit < 8; bit++) {
            a[i] ^= (unsigned char)(1u << bit);
            lie_cache *d = (lie_cache *)1;
            lie_error err;
            lie_status st = lie_cache_decode(a, na, "t.lie", &d, &err);
            if (st == LIE_OK)
                fail_msg("flipping bit %d of byte %zu was accepted", bit, i);
            assert_null(d);
            a[i] ^= (unsigned char)(1u << bit);
        }
    }
    lie_cache_destroy(decode_ok(a, na));
    free(a);
    lie_cache_destroy(c);
}

static void test_every_truncation_is_rejected(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    unsigned char *a;
    size_t na;
    encode(c, &a, &na);
    for (size_t len = 0; len < na; len++) {
        /* a copy of exactly len bytes, so ASan sees any read past it */
        unsigned char *t = malloc(len ? len : 1);
        memcpy(t, a, len);
        lie_cache *d = (lie_cache *)1;
        lie_error err;
        assert_int_equal(lie_cache_decode(len ? t : NULL, len, "t.lie", &d, &err), LIE_ERR_FORMAT);
        assert_null(d);
        free(t);
    }
    expect_reject(a, na - 8, LIE_ERR_FORMAT, "truncated");
    /* and bytes appended */
    unsigned char *longer = calloc(1, na + 8);
    memcpy(longer, a, na);
    expect_reject(longer, na + 8, LIE_ERR_FORMAT, NULL);
    free(longer);
    free(a);
    lie_cache_destroy(c);
}

static void test_not_a_cache_is_rejected(void **state)
{
    (void)state;
    expect_reject((const unsigned char *)"{\"asset\":{}}", 12, LIE_ERR_FORMAT, "not a LIE cache");
    expect_reject((const unsigned char *)"LIECA", 5, LIE_ERR_FORMAT, "truncated");
    expect_reject(NULL, 0, LIE_ERR_FORMAT, "empty");
}

/* EMITTERS as versions 1 and 2 lay it out: 16 bytes, no clusters. */
static void emitters_v2(const lie_cache *c, sect s[N_SECT])
{
    free(s[EMIT].data);
    s[EMIT] = (sect){id4("EMIT"), calloc(1, 16 * (size_t)c->n_emitters + 1), 16 * (size_t)c->n_emitters};
    for (int e = 0; e < c->n_emitters; e++) {
        assert_int_equal(c->emitters[e].n_clusters, 1);
        put32(s[EMIT].data + 16 * e, c->emitters[e].type);
        put32(s[EMIT].data + 16 * e + 4, (uint32_t)c->emitters[e].node);
        put32(s[EMIT].data + 16 * e + 8, c->emitters[e].first_tri);
        put32(s[EMIT].data + 16 * e + 12, c->emitters[e].n_tris);
    }
}

/* c's sections as a file of an older version: 16-byte EMITTERS, PARAMS of
 * params_size bytes. */
static void old_file(const lie_cache *c, sect s[N_SECT], uint32_t version, size_t params_size, unsigned char **a,
                     size_t *na)
{
    spec_sections_as(c, SPEC_V5, s);
    emitters_v2(c, s);
    s[PARM].size = params_size;
    assemble(s, N_SECT, a, na);
    put32(*a + 8, version);
    reseal(*a, *na);
}

/* A file of an older format version made from a cache, and that file decoded. */
typedef struct old_version {
    lie_cache *c; /* the cache it was made from */
    sect s[N_SECT];
    unsigned char *a;
    size_t na;
    lie_cache *d; /* the file decoded */
} old_version;

/* c as a file of `version` with a PARAMS of params_size bytes: it must read. */
static void old_version_read(old_version *o, lie_cache *c, uint32_t version, size_t params_size)
{
    o->c = c;
    o->d = NULL;
    old_file(c, o->s, version, params_size, &o->a, &o->na);
    lie_error err;
    assert_int_equal(lie_cache_decode(o->a, o->na, "old.lie", &o->d, &err), LIE_OK);
}

/* The same bytes labelled the next version are damaged (msg); then all is freed. */
static void old_version_done(old_version *o, const char *msg)
{
    lie_cache_destroy(o->d);
    put32(o->a + 8, get32(o->a + 8) + 1);
    reseal(o->a, o->na);
    expect_reject(o->a, o->na, LIE_ERR_FORMAT, msg);
    free_sections(o->s, N_SECT);
    free(o->a);
    lie_cache_destroy(o->c);
}

/* A version 3 file (16-byte EMITTERS) reads with one cluster per emitter;
 * a version 4 file with 16-byte records is damaged. */
static void test_version_3_reads_with_one_cluster_each(void **state)
{
    (void)state;
    old_version o;
    old_version_read(&o, cornell_cache(LIE_BLOCKERS_SAMPLED), 3, 48);
    assert_int_equal(o.d->n_emitters, o.c->n_emitters);
    for (int e = 0; e < o.d->n_emitters; e++) {
        assert_int_equal(o.d->emitters[e].n_clusters, 1);
        assert_int_equal(o.d->emitters[e].partition, 0);
    }
    assert_int_equal(o.d->env->n_clusters, o.c->env->n_clusters);
    old_version_done(&o, "section EMITTERS");
}

/* A version 1 file (PARAMS of 24 bytes, no split_gain) still reads: its
 * trees were built splitting wherever a list was too long, split_gain 0;
 * a version 2 file with a 24-byte PARAMS is damaged. */
static void test_version_1_reads_with_split_gain_0(void **state)
{
    (void)state;
    old_version o;
    old_version_read(&o, cornell_cache(LIE_BLOCKERS_SAMPLED), 1, 24);
    assert_true(o.d->env->params.split_gain == 0.0f);
    assert_int_equal(o.d->env->params.complex_cap, o.c->env->params.complex_cap);
    assert_int_equal(file_nodes(o.d->env), file_nodes(o.c->env));
    old_version_done(&o, "section PARAMS: 24 bytes, expected 28");
}

/* A version 2 file reads with the default cost model; a version 3 file
 * with a 28-byte PARAMS is damaged. */
static void test_version_2_reads_with_the_default_cost_model(void **state)
{
    (void)state;
    lie_cache *c = cornell_cache(LIE_BLOCKERS_SAMPLED);
    c->env->params.frames = 77;
    old_version o;
    old_version_read(&o, c, 2, 28);
    lie_build_params def = lie_build_params_default();
    assert_int_equal(o.d->env->params.frames, def.frames);
    assert_true(o.d->env->params.ns_ray == def.ns_ray);
    assert_true(o.d->env->params.split_gain == c->env->params.split_gain);
    assert_int_equal(o.d->views.n_cams, 0);
    old_version_done(&o, "section PARAMS: 28 bytes, expected 48");
}

static void test_views_round_trip_and_bad_views_are_rejected(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    unsigned char *a0, *a;
    size_t n0, na;
    encode(c, &a0, &n0);
    c->views.cams = calloc(2, sizeof *c->views.cams);
    assert_non_null(c->views.cams);
    c->views.n_cams = 2;
    c->views.width = 64;
    c->views.height = 48;
    c->views.max_depth = 2;
    for (int i = 0; i < 2; i++) {
        c->views.cams[i].eye = (lie_vec3){1.0f + (float)i, 2.0f, 3.0f};
        c->views.cams[i].forward = (lie_vec3){0.0f, 0.0f, -1.0f};
        c->views.cams[i].up = (lie_vec3){0.0f, 1.0f, 0.0f};
        c->views.cams[i].yfov = 0.8f;
    }
    c->views.cams[1].ymag = 2.5f;
    encode(c, &a, &na);
    assert_int_equal(na, n0 + 32 + 16 + 2 * 48);
    lie_cache *d = NULL;
    lie_error err;
    assert_int_equal(lie_cache_decode(a, na, "v.lie", &d, &err), LIE_OK);
    assert_int_equal(d->views.n_cams, 2);
    assert_int_equal(d->views.width, 64);
    assert_int_equal(d->views.height, 48);
    assert_int_equal(d->views.max_depth, 2);
    assert_memory_equal(&d->views.cams[1].eye, &c->views.cams[1].eye, sizeof(lie_vec3));
    assert_true(d->views.cams[1].ymag == 2.5f);
    lie_cache_destroy(d);
    free(a);
    /* what a reader rejects, the encoder refuses */
    c->views.cams[0].yfov = 0.0f;
    assert_int_equal(lie_cache_encode(c, &a, &na, &err), LIE_ERR_ARG);
    assert_non_null(strstr(err.msg, "views"));
    c->views.cams[0].yfov = 0.8f;
    c->views.width = 0;
    assert_int_equal(lie_cache_encode(c, &a, &na, &err), LIE_ERR_ARG);
    free(a0);
    lie_cache_destroy(c);
}

static void test_newer_version_is_unsupported(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    unsigned char *a;
    size_t na;
    encode(c, &a, &na);
    put32(a + 8, LIE_CACHE_VERSION + 1);
    /* a newer file may lay out anything after the version: only the
     * invariant trailing checksum must hold */
    memset(a + 12, 0xAB, na - 20);
    reseal(a, na);
    expect_reject(a, na, LIE_ERR_UNSUPPORTED, "version 8");
    free(a);
    encode(c, &a, &na);
    put32(a + 8, 0);
    reseal(a, na);
    expect_reject(a, na, LIE_ERR_FORMAT, "version 0");
    free(a);
    lie_cache_destroy(c);
}

/* Versions 4 and 5 have version 6's sections, with a node for every unit
 * (no tags in ROOTS): they read; version 4 says its units follow older
 * rules (an update recomputes them all, lib/update), version 5 and a cache
 * this library wrote do not; and either encodes again as this library
 * writes the same trees.  A tag in an older file is a root past the nodes.
 * Version 6 is version 7 without PARAMS' whole_pixels: it reads as 0 (no
 * model: a whole build of version 6 built every unit) and encodes again. */
static void test_versions_4_to_6_read_and_encode_as_version_7(void **state)
{
    (void)state;
    lie_cache *c = small_cache(), *d = NULL;
    unsigned char *a, *b, *v6;
    size_t na, nb, n6;
    lie_error err;
    c->env->params.complex_predict = 0; /* what an older file reads as */
    c->env->params.whole_pixels = 0;
    encode(c, &v6, &n6);
    assert_int_equal(lie_cache_decode(v6, n6, "t.lie", &d, &err), LIE_OK);
    assert_int_equal(d->version, LIE_CACHE_VERSION);
    assert_false(lie_cache_rules_old(d));
    assert_false(lie_cache_rules_old(c));
    lie_cache_destroy(d);
    sect s[N_SECT];
    spec_sections_as(c, SPEC_V5, s);
    s[PARM].size = 48;
    assemble(s, N_SECT, &a, &na);
    assert_true(na > n6); /* a node for each lone unit */
    for (uint32_t version = 4; version <= 5; version++) {
        put32(a + 8, version);
        reseal(a, na);
        assert_int_equal(lie_cache_decode(a, na, "t.lie", &d, &err), LIE_OK);
        assert_int_equal(d->version, version);
        assert_int_equal(lie_cache_rules_old(d), version < 5);
        assert_int_equal(file_nodes(d->env), file_nodes(c->env));
        encode(d, &b, &nb);
        assert_int_equal(nb, n6);
        assert_memory_equal(b, v6, n6);
        free(b);
        lie_cache_destroy(d);
    }
    free(a);
    free_sections(s, N_SECT);
    /* version 6: version 7's trees, PARAMS 52 bytes */
    sect s6[N_SECT];
    spec_sections(c, s6);
    s6[PARM].size = 52;
    assemble(s6, N_SECT, &a, &na);
    put32(a + 8, 6);
    reseal(a, na);
    assert_int_equal(lie_cache_decode(a, na, "t.lie", &d, &err), LIE_OK);
    assert_int_equal(d->env->params.whole_pixels, 0);
    assert_false(lie_cache_rules_old(d));
    encode(d, &b, &nb);
    assert_int_equal(nb, n6);
    assert_memory_equal(b, v6, n6);
    free(b);
    lie_cache_destroy(d);
    free(a);
    free_sections(s6, N_SECT);
    /* a version 6 tag read as version 5 */
    size_t units = (size_t)c->n_tris * (size_t)c->env->n_clusters, tagged = units;
    for (size_t u = 0; u < units && tagged == units; u++)
        if (lie_pnode_lone(&c->env->nodes[c->env->root[u]]))
            tagged = u;
    assert_true(tagged < units);
    spec_sections(c, s);
    s[PARM].size = 48;
    assemble(s, N_SECT, &a, &na);
    put32(a + 8, 5);
    reseal(a, na);
    expect_reject(a, na, LIE_ERR_FORMAT, "beyond the");
    free(a);
    free_sections(s, N_SECT);
    free(v6);
    lie_cache_destroy(c);
}

static void test_unknown_required_flag_is_unsupported_optional_ignored(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    unsigned char *a;
    size_t na;
    encode(c, &a, &na);
    put32(a + 12, 0x10);
    reseal(a, na);
    expect_reject(a, na, LIE_ERR_UNSUPPORTED, "required feature flags");
    put32(a + 12, 0);
    put32(a + 16, 0x80000001u);
    reseal(a, na);
    lie_cache *d = decode_ok(a, na);
    assert_caches_equal(c, d);
    lie_cache_destroy(d);
    free(a);
    lie_cache_destroy(c);
}

/* ---- the section table ------------------------------------------------------- */

static void test_unknown_sections_are_skipped_and_order_is_free(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    sect s[N_SECT + 2];
    spec_sections(c, s);
    /* an unknown section in the middle and the reserved RST one at the end */
    sect t[N_SECT + 2];
    unsigned char junk[13] = "hello, world";
    for (int i = 0; i < 3; i++)
        t[i] = s[i];
    t[3] = (sect){id4("XTRA"), junk, 13};
    for (int i = 3; i < N_SECT; i++)
        t[i + 1] = s[i];
    t[N_SECT + 1] = (sect){id4("RSTS"), junk, 5};
    unsigned char *a, *b;
    size_t na, nb;
    assemble(t, N_SECT + 2, &a, &na);
    lie_cache *d = decode_ok(a, na);
    assert_caches_equal(c, d);
    lie_cache_section sec[LIE_CACHE_MAX_SECTIONS];
    int n;
    lie_error err;
    assert_int_equal(lie_cache_sections(a, na, "t.lie", sec, &n, &err), LIE_OK);
    assert_int_equal(n, N_SECT + 2);
    assert_string_equal(sec[3].name, "XTRA");
    assert_string_equal(sec[N_SECT + 1].name, "RST");
    lie_cache_destroy(d);
    free(a);
    /* reversed order */
    for (int i = 0; i < N_SECT; i++)
        t[i] = s[N_SECT - 1 - i];
    assemble(t, N_SECT, &b, &nb);
    d = decode_ok(b, nb);
    assert_caches_equal(c, d);
    lie_cache_destroy(d);
    free(b);
    free_sections(s, N_SECT);
    lie_cache_destroy(c);
}

static void test_missing_or_repeated_section_is_rejected(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    sect s[N_SECT];
    spec_sections(c, s);
    const char *names[N_SECT] = {"META", "PARAMS", "EDITS", "EMITTERS", "ROOTS", "NODES", "POOL"};
    for (int drop = 0; drop < N_SECT; drop++) {
        sect t[N_SECT];
        int n = 0;
        for (int i = 0; i < N_SECT; i++)
            if (i != drop)
                t[n++] = s[i];
        unsigned char *a;
        size_t na;
        assemble(t, n, &a, &na);
        char want[64];
        snprintf(want, sizeof want, "required section %s missing", names[drop]);
        expect_reject(a, na, LIE_ERR_FORMAT, want);
        free(a);
    }
    sect t[N_SECT + 1];
    memcpy(t, s, sizeof s);
    t[N_SECT] = s[EDIT];
    unsigned char *a;
    size_t na;
    assemble(t, N_SECT + 1, &a, &na);
    expect_reject(a, na, LIE_ERR_FORMAT, "section EDITS appears twice");
    free(a);
    free_sections(s, N_SECT);
    lie_cache_destroy(c);
}

static void test_misplaced_sections_are_rejected_even_with_valid_checksums(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    unsigned char *a;
    size_t na;
    encode(c, &a, &na);
    unsigned char *orig = malloc(na);
    memcpy(orig, a, na);
    unsigned char *e;
    size_t node_off = section_at(a, "NODE", &e);
    struct {
        int field; /* 8 offset, 16 size */
        uint64_t value;
        const char *msg;
    } cases[] = {
        {8, (uint64_t)na + 64, "offset"},             /* outside the file */
        {8, UINT64_MAX - 3, "offset"},                /* wraps around */
        {8, node_off + 4, "offset"},                  /* misaligned */
        {8, node_off - 8, "offset"},                  /* overlaps the previous section */
        {16, (uint64_t)na, "pass the end"},           /* longer than the file */
        {16, UINT64_MAX, "pass the end"},             /* wraps around */
        {16, 20 * (uint64_t)file_nodes(c->env) + 8, ""}, /* overlaps the next section */
        {16, 20 * (uint64_t)file_nodes(c->env) - 20, ""}, /* leaves a gap */
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        memcpy(a, orig, na);
        put64(e + cases[k].field, cases[k].value);
        reseal(a, na);
        expect_reject(a, na, LIE_ERR_FORMAT, cases[k].msg);
    }
    /* the table itself larger than the file */
    memcpy(a, orig, na);
    put32(a + 20, 32);
    reseal(a, na);
    expect_reject(a, na, LIE_ERR_FORMAT, NULL);
    memcpy(a, orig, na);
    put32(a + 20, 0);
    reseal(a, na);
    expect_reject(a, na, LIE_ERR_FORMAT, "section table");
    memcpy(a, orig, na);
    put32(a + 20, 1000000);
    reseal(a, na);
    expect_reject(a, na, LIE_ERR_FORMAT, "section table");
    /* header size field, reserved field, non-zero padding */
    memcpy(a, orig, na);
    put64(a + 24, na + 8);
    reseal(a, na);
    expect_reject(a, na, LIE_ERR_FORMAT, "header records");
    memcpy(a, orig, na);
    put32(e + 4, 1);
    reseal(a, na);
    expect_reject(a, na, LIE_ERR_FORMAT, "reserved");
    memcpy(a, orig, na);
    size_t meta = section_at(a, "META", &e);
    uint64_t meta_end = meta + get64(e + 16);
    assert_true(meta_end % 8 != 0); /* the fixture's path leaves padding */
    a[meta_end] = 1;
    reseal(a, na);
    expect_reject(a, na, LIE_ERR_FORMAT, "padding");
    /* a section checksum alone */
    memcpy(a, orig, na);
    a[node_off + 4] ^= 1;
    put64(a + na - 8, lie_hash_bytes(a, na - 8, 0));
    expect_reject(a, na, LIE_ERR_FORMAT, "section NODES: checksum mismatch");
    free(orig);
    free(a);
    lie_cache_destroy(c);
}

/* ---- section contents ---------------------------------------------------------- */

/* Encode c's sections with one u32 replaced, through the spec encoder. */
static void expect_patched_reject(const lie_cache *c, int section, size_t at, uint32_t value, lie_status status,
                                  const char *msg)
{
    sect s[N_SECT];
    spec_sections(c, s);
    assert_true(at + 4 <= s[section].size);
    put32(s[section].data + at, value);
    unsigned char *a;
    size_t na;
    assemble(s, N_SECT, &a, &na);
    expect_reject(a, na, status, msg);
    free(a);
    free_sections(s, N_SECT);
}

static void test_bad_meta_params_edits_emitters_are_rejected(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    add_edit(c, "e.yaml", "x: 1\n", 5);
    expect_patched_reject(c, META, 24, 7, LIE_ERR_FORMAT, "units");     /* n_units */
    expect_patched_reject(c, META, 40, 3, LIE_ERR_FORMAT, "section META"); /* path length */
    expect_patched_reject(c, META, 44, 1, LIE_ERR_FORMAT, "reserved");
    expect_patched_reject(c, META, 48, 0x41410041, LIE_ERR_FORMAT, "zero byte");
    expect_patched_reject(c, META, 20, 0x80000000u, LIE_ERR_FORMAT, "emitters");
    expect_patched_reject(c, PARM, 0, 0, LIE_ERR_FORMAT, "section PARAMS: samples");
    expect_patched_reject(c, PARM, 4, 1, LIE_ERR_FORMAT, "section PARAMS: max-samples");
    expect_patched_reject(c, PARM, 16, 0x7fc00000u, LIE_ERR_FORMAT, "min-patch"); /* NaN */
    expect_patched_reject(c, PARM, 16, 0x3f800001u, LIE_ERR_FORMAT, "min-patch"); /* just above 1 */
    expect_patched_reject(c, PARM, 20, 2, LIE_ERR_FORMAT, "blocker mode");
    expect_patched_reject(c, EDIT, 0, 2, LIE_ERR_FORMAT, "section EDITS");
    expect_patched_reject(c, EDIT, 0, 0, LIE_ERR_FORMAT, "after the last edit");
    expect_patched_reject(c, EDIT, 4, 7, LIE_ERR_FORMAT, "section EDITS: edit 0");
    expect_patched_reject(c, EDIT, 8, 0xFFFFFFFFu, LIE_ERR_FORMAT, "section EDITS: edit 0");
    expect_patched_reject(c, EDIT, 12, 0x00790065, LIE_ERR_FORMAT, "zero byte");
    expect_patched_reject(c, EMIT, 0, 3, LIE_ERR_FORMAT, "unknown emitter type");
    expect_patched_reject(c, EMIT, 4, 0xFFFFFFFFu, LIE_ERR_FORMAT, "negative node");
    expect_patched_reject(c, EMIT, 8, 5, LIE_ERR_FORMAT, "beyond");
    expect_patched_reject(c, EMIT, 12, 0, LIE_ERR_FORMAT, "without triangles");
    expect_patched_reject(c, EMIT, 0, 1, LIE_ERR_FORMAT, "point or directional");
    lie_cache_destroy(c);
}

/* Index of the first node after node 0 of class cls with (child != 0) ==
 * interior, among those the file holds (the env's first, as a build lays
 * it out: its shared lone leaves come last, as tags). */
static uint32_t find_node(const lie_env *env, uint32_t cls, int interior)
{
    for (uint32_t i = 1; i < file_nodes(env); i++)
        if (env->nodes[i].cls == cls && (env->nodes[i].child != 0) == interior)
            return i;
    fail_msg("no %s node of class %u", interior ? "interior" : "leaf", cls);
    return 0;
}

static void test_structurally_invalid_env_is_rejected_despite_valid_checksums(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    const lie_env *env = c->env;
    uint32_t split = find_node(env, LIE_CLASS_SPLIT, 1);
    uint32_t partial = 0;
    for (uint32_t i = 0; i < env->n_nodes && !partial; i++)
        if (env->nodes[i].cls == LIE_CLASS_PARTIAL && env->nodes[i].list > 0 && env->nodes[i].count >= 2)
            partial = i;
    assert_true(partial > 0);
    uint32_t unlit = find_node(env, LIE_CLASS_VISIBLE, 0); /* unlit roots are tags */
    const lie_pnode *pn = &env->nodes[partial];
    assert_true(pn->count >= 2);
    size_t sn = 20 * (size_t)split, pp = 20 * (size_t)partial, un = 20 * (size_t)unlit;
    /* cycles and links */
    expect_patched_reject(c, NODE, sn, split, LIE_ERR_FORMAT, "does not come after");
    expect_patched_reject(c, NODE, sn, 0, LIE_ERR_FORMAT, "split node without children");
    expect_patched_reject(c, NODE, sn, env->n_nodes - 2, LIE_ERR_FORMAT, "beyond");
    expect_patched_reject(c, NODE, sn, 0xFFFFFFFEu, LIE_ERR_FORMAT, "beyond");
    expect_patched_reject(c, NODE, sn, env->nodes[split].child + 1, LIE_ERR_FORMAT, NULL);
    expect_patched_reject(c, NODE, un, split + 1, LIE_ERR_FORMAT, "has children but class visible");
    expect_patched_reject(c, NODE, sn + 12, 1, LIE_ERR_FORMAT, "split node with a list");
    /* classes */
    expect_patched_reject(c, NODE, un + 4, 7, LIE_ERR_FORMAT, "class 7 is unknown");
    expect_patched_reject(c, NODE, un + 4, LIE_CLASS_SPLIT, LIE_ERR_FORMAT, "without children");
    expect_patched_reject(c, NODE, un + 16, 1, LIE_ERR_FORMAT, "visible leaf with a blocker list");
    expect_patched_reject(c, NODE, un + 4, LIE_CLASS_PARTIAL, LIE_ERR_FORMAT, "empty list");
    /* lists */
    expect_patched_reject(c, NODE, pp + 12, env->n_pool, LIE_ERR_FORMAT, "beyond the");
    expect_patched_reject(c, NODE, pp + 12, 0xFFFFFFFFu, LIE_ERR_FORMAT, "beyond the");
    expect_patched_reject(c, NODE, pp + 16, 0xFFFFFFFFu, LIE_ERR_FORMAT, "beyond the");
    expect_patched_reject(c, NODE, pp + 4, LIE_CLASS_COMPLEX, LIE_ERR_FORMAT, "complex leaf with a list offset");
    uint32_t l0 = env->pool[pn->list], l1 = env->pool[pn->list + 1];
    expect_patched_reject(c, POOL, 4 * (size_t)pn->list, l1, LIE_ERR_FORMAT, "not strictly increasing");
    expect_patched_reject(c, POOL, 4 * ((size_t)pn->list + 1), l0, LIE_ERR_FORMAT, "not strictly increasing");
    expect_patched_reject(c, POOL, 4 * ((size_t)pn->list + pn->count - 1), env->n_tris, LIE_ERR_FORMAT,
                          "beyond the 6 triangles");
    /* roots */
    expect_patched_reject(c, ROOT, 0, file_nodes(env), LIE_ERR_FORMAT, "section ROOTS: unit 0");
    size_t owner = 0;
    while (lie_pnode_lone(&env->nodes[env->root[owner]]))
        owner++;
    expect_patched_reject(c, ROOT, 4 * (owner + 1), env->root[owner], LIE_ERR_FORMAT, "already a root");
    expect_patched_reject(c, ROOT, 0, env->nodes[split].child, LIE_ERR_FORMAT, NULL);
    lie_cache_destroy(c);
}

/* Synthetic envs the builder would not make: a chain deeper than the patch
 * trees allow, and orphan nodes. */
static void test_trees_deeper_than_max_depth_or_with_orphans_are_rejected(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    lie_env *env = c->env;
    size_t units = (size_t)env->n_tris * (size_t)env->n_clusters;
    for (int depth = LIE_PATCH_MAX_DEPTH; depth <= LIE_PATCH_MAX_DEPTH + 1; depth++) {
        uint32_t n = (uint32_t)units + 4u * (uint32_t)depth;
        lie_pnode *nodes = calloc(n, sizeof *nodes);
        uint32_t *root = calloc(units, sizeof *root);
        for (size_t u = 0; u < units; u++) {
            root[u] = (uint32_t)u;
            nodes[u].cls = LIE_CLASS_VISIBLE;
        }
        /* unit 0: split, then split child 0 at every level */
        uint32_t cur = 0;
        for (int d = 0; d < depth; d++) {
            uint32_t first = (uint32_t)units + 4u * (uint32_t)d;
            nodes[cur].cls = LIE_CLASS_SPLIT;
            nodes[cur].child = first;
            for (uint32_t k = 0; k < 4; k++)
                nodes[first + k].cls = LIE_CLASS_OCCLUDED;
            cur = first;
        }
        lie_env fake = *env;
        fake.nodes = nodes;
        fake.root = root;
        fake.n_nodes = n;
        fake.n_pool = 0;
        lie_cache cc = *c;
        cc.env = &fake;
        sect s[N_SECT];
        spec_sections_as(&cc, SPEC_RAW, s);
        unsigned char *a;
        size_t na;
        assemble(s, N_SECT, &a, &na);
        if (depth == LIE_PATCH_MAX_DEPTH) {
            lie_cache *d = decode_ok(a, na);
            lie_build_stats st;
            lie_env_stats(d->env, &st);
            assert_int_equal(st.patches_per_depth[LIE_PATCH_MAX_DEPTH], 4);
            lie_cache_destroy(d);
        } else {
            expect_reject(a, na, LIE_ERR_FORMAT, "deeper than 24");
        }
        free(a);
        free_sections(s, N_SECT);
        /* the same with the chain cut off from its unit */
        nodes[0].child = 0;
        nodes[0].cls = LIE_CLASS_VISIBLE;
        spec_sections_as(&cc, SPEC_RAW, s);
        assemble(s, N_SECT, &a, &na);
        expect_reject(a, na, LIE_ERR_FORMAT, "belongs to no unit");
        free(a);
        free_sections(s, N_SECT);
        free(nodes);
        free(root);
    }
    lie_cache_destroy(c);
}

static void test_empty_scene_round_trips(void **state)
{
    (void)state;
    /* no emitters: no units, no nodes */
    lie_cache *c = small_cache();
    lie_env *env = c->env;
    env->n_clusters = 0;
    env->n_nodes = 0;
    env->n_pool = 0;
    c->n_emitters = 0;
    unsigned char *a, *b;
    size_t na, nb;
    encode(c, &a, &na);
    lie_cache *d = decode_ok(a, na);
    assert_int_equal(d->env->n_nodes, 0);
    encode(d, &b, &nb);
    assert_memory_equal(a, b, na);
    /* nodes nobody reaches are refused even then */
    sect s[N_SECT];
    env->n_nodes = 1;
    spec_sections_as(c, SPEC_RAW, s);
    free(a);
    assemble(s, N_SECT, &a, &na);
    expect_reject(a, na, LIE_ERR_FORMAT, "belongs to no unit");
    free_sections(s, N_SECT);
    free(a);
    free(b);
    lie_cache_destroy(d);
    lie_cache_destroy(c);
}

/* ---- absurd counts ------------------------------------------------------------- */

/* Decode the crafted file in a child whose address space is capped near
 * its current size: any allocation sized from the claimed counts rather
 * than the bytes present fails there, and LIE_ERR_NOMEM is not the
 * expected LIE_ERR_FORMAT.  (Under AddressSanitizer the cap would break
 * the sanitizer itself, so the child runs uncapped: the status still holds.) */
#if defined(__SANITIZE_ADDRESS__)
#define CAP_ADDRESS_SPACE 0
#else
#define CAP_ADDRESS_SPACE 1
#endif

static void expect_refused_in_capped_child(const unsigned char *a, size_t na, const char *msg)
{
    fflush(NULL);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        if (CAP_ADDRESS_SPACE) {
            FILE *fp = fopen("/proc/self/statm", "r");
            unsigned long pages = 0;
            if (!fp || fscanf(fp, "%lu", &pages) != 1)
                _exit(3);
            fclose(fp);
            rlim_t cap = (rlim_t)pages * (rlim_t)sysconf(_SC_PAGESIZE) + ((rlim_t)256 << 20);
            struct rlimit rl = {cap, cap};
            if (setrlimit(RLIMIT_AS, &rl) != 0)
                _exit(3);
        }
        lie_cache *d = NULL;
        lie_error err;
        lie_status st = lie_cache_decode(a, na, "t.lie", &d, &err);
        _exit(st == LIE_ERR_FORMAT && strstr(err.msg, msg) ? 0 : st == LIE_ERR_NOMEM ? 4 : 5);
    }
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFEXITED(status));
    if (WEXITSTATUS(status) != 0)
        print_error("child exit %d for '%s'\n", WEXITSTATUS(status), msg);
    assert_int_equal(WEXITSTATUS(status), 0);
}

static void test_absurd_counts_are_refused_without_allocating(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    struct {
        int section;
        size_t at;
        uint64_t value;
        int wide;
        const char *msg;
    } cases[] = {
        {META, 16, 0xFFFFFFFFu, 0, "units is not"},                /* n_tris without n_units */
        {META, 32, 0xFFFFFFFFu, 0, "section NODES"},              /* n_nodes */
        {META, 36, 0xFFFFFFFFu, 0, "section POOL"},               /* n_pool */
        {META, 20, 0x7FFFFFFFu, 0, "section EMITTERS"},           /* n_emitters */
        {EDIT, 0, 0xFFFFFFFFu, 0, "section EDITS"},               /* n_edits */
        {EDIT, 4, 0xFFFFFFF0u, 0, "section EDITS"},               /* a name length */
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        sect s[N_SECT];
        spec_sections(c, s);
        if (cases[k].section == EDIT && cases[k].at == 4) {
            /* give the section one edit to hold the length */
            free(s[EDIT].data);
            s[EDIT].data = calloc(1, 12);
            s[EDIT].size = 12;
            put32(s[EDIT].data, 1);
        }
        put32(s[cases[k].section].data + cases[k].at, (uint32_t)cases[k].value);
        unsigned char *a;
        size_t na;
        assemble(s, N_SECT, &a, &na);
        expect_refused_in_capped_child(a, na, cases[k].msg);
        free(a);
        free_sections(s, N_SECT);
    }
    /* consistent huge META (n_units agrees) against small arrays */
    sect s[N_SECT];
    spec_sections(c, s);
    put32(s[META].data + 16, 0xFFFFFFFFu);
    put32(s[META].data + 20, 0x7FFFFFFFu);
    put64(s[META].data + 24, 0xFFFFFFFFull * 0x7FFFFFFFull);
    unsigned char *a;
    size_t na;
    assemble(s, N_SECT, &a, &na);
    expect_refused_in_capped_child(a, na, "section EMITTERS");
    free(a);
    put32(s[META].data + 20, 1);
    put64(s[META].data + 24, 0xFFFFFFFFull);
    assemble(s, N_SECT, &a, &na);
    expect_refused_in_capped_child(a, na, "section ROOTS");
    free(a);
    free_sections(s, N_SECT);
    lie_cache_destroy(c);
}

/* ---- random damage behind valid checksums ---------------------------------------- */

static void test_random_damage_behind_resealed_checksums_never_crashes(void **state)
{
    (void)state;
    lie_cache *c = small_cache();
    add_edit(c, "e.yaml", "x: 1\n", 5);
    unsigned char *orig;
    size_t na;
    encode(c, &orig, &na);
    unsigned char *a = malloc(na);
    uint64_t rng = 0x9E3779B97F4A7C15ull;
    int accepted = 0;
    for (int iter = 0; iter < 20000; iter++) {
        memcpy(a, orig, na);
        int changes = 1 + (int)(rng % 4);
        for (int k = 0; k < changes; k++) {
            rng = rng * 6364136223846793005ull + 1442695040888963407ull;
            size_t at = (size_t)(rng >> 33) % (na - 8);
            if (at < 8)
                at += 8; /* keep the magic: the interesting checks lie behind it */
            uint32_t r = (uint32_t)(rng >> 20);
            switch (r % 4) {
            case 0: a[at] ^= (unsigned char)(1u << (r >> 8) % 8); break;
            case 1: a[at] = (unsigned char)(r >> 8); break;
            case 2: a[at] = 0; break;
            default: a[at] = 0xFF; break;
            }
        }
        reseal(a, na);
        lie_cache *d = NULL;
        lie_error err;
        lie_status st = lie_cache_decode(a, na, "t.lie", &d, &err);
        if (st == LIE_OK) {
            /* whatever was accepted is usable and re-encodes to itself */
            accepted++;
            unsigned char *b;
            size_t nb;
            encode(d, &b, &nb);
            assert_int_equal(nb, na);
            lie_build_stats stt;
            lie_env_stats(d->env, &stt);
            free(b);
            lie_cache_destroy(d);
        } else {
            assert_null(d);
            assert_null(strchr(err.msg, '\n'));
        }
    }
    assert_true(accepted < 20000);
    free(a);
    free(orig);
    lie_cache_destroy(c);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_encode_decode_encode_gives_identical_bytes),
        cmocka_unit_test(test_decode_preserves_every_field_of_a_real_env),
        cmocka_unit_test(test_edit_log_round_trips_byte_exact),
        cmocka_unit_test(test_encoder_written_from_the_spec_gives_the_same_bytes),
        cmocka_unit_test(test_sections_lists_the_table_in_file_order),
        cmocka_unit_test(test_write_then_read_round_trips_and_leaves_no_temporary),
        cmocka_unit_test(test_encode_refuses_what_a_reader_would_reject),
        cmocka_unit_test(test_every_single_bit_flip_is_rejected),
        cmocka_unit_test(test_every_truncation_is_rejected),
        cmocka_unit_test(test_not_a_cache_is_rejected),
        cmocka_unit_test(test_version_1_reads_with_split_gain_0),
        cmocka_unit_test(test_version_2_reads_with_the_default_cost_model),
        cmocka_unit_test(test_views_round_trip_and_bad_views_are_rejected),
        cmocka_unit_test(test_newer_version_is_unsupported),
        cmocka_unit_test(test_versions_4_to_6_read_and_encode_as_version_7),
        cmocka_unit_test(test_stream_gives_the_bytes_of_encode),
        cmocka_unit_test(test_version_3_reads_with_one_cluster_each),
        cmocka_unit_test(test_unknown_required_flag_is_unsupported_optional_ignored),
        cmocka_unit_test(test_unknown_sections_are_skipped_and_order_is_free),
        cmocka_unit_test(test_missing_or_repeated_section_is_rejected),
        cmocka_unit_test(test_misplaced_sections_are_rejected_even_with_valid_checksums),
        cmocka_unit_test(test_bad_meta_params_edits_emitters_are_rejected),
        cmocka_unit_test(test_structurally_invalid_env_is_rejected_despite_valid_checksums),
        cmocka_unit_test(test_trees_deeper_than_max_depth_or_with_orphans_are_rejected),
        cmocka_unit_test(test_empty_scene_round_trips),
        cmocka_unit_test(test_absurd_counts_are_refused_without_allocating),
        cmocka_unit_test(test_random_damage_behind_resealed_checksums_never_crashes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
