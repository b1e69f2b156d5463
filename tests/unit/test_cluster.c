/* Clusters of emitter triangles (lib/scene/cluster.c): the partition, the
 * per-cluster shapes lib/lie asks for, and that an LIE of a clustered
 * emitter still equals the reference (conservative lists) and updates as
 * it rebuilds.  Fixture: tests/data/gltf/light_strip.gltf (gen_fixtures.py):
 * an 80-triangle strip down a corridor. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "lie.h"
#include "fixtures.h"

#define STRIP "tests/data/gltf/light_strip.gltf"

static lie_scene *load(void)
{
    lie_scene *s = NULL;
    lie_error err;
    assert_int_equal(lie_scene_load(STRIP, NULL, &s, &err), LIE_OK);
    return s;
}

static int strip_emitter(const lie_scene *s)
{
    for (int e = 0; e < s->n_emitters; e++)
        if (s->emitters[e].type == LIE_EMITTER_AREA && s->emitters[e].n_tris == 80)
            return e;
    fail_msg("no 80-triangle emitter");
    return -1;
}

/* The strip splits into several clusters that partition its triangles,
 * each ascending, each its own, the same on every load. */
static void test_strip_is_partitioned_into_clusters(void **state)
{
    (void)state;
    lie_scene *s = load(), *t = load();
    int e = strip_emitter(s);
    const lie_emitter *em = &s->emitters[e];
    assert_true(em->n_clusters >= 2 && em->n_clusters <= LIE_CLUSTER_MAX);
    assert_int_equal(s->n_clusters, t->n_clusters);
    assert_int_equal(lie_scene_cluster_digest(s, e), lie_scene_cluster_digest(t, e));
    assert_true(lie_scene_cluster_digest(s, e) != 0);
    uint8_t *seen = calloc(s->n_tris, 1);
    uint32_t total = 0;
    for (int c = em->first_cluster; c < em->first_cluster + em->n_clusters; c++) {
        const lie_cluster *cl = &s->clusters[c];
        assert_int_equal(cl->emitter, e);
        assert_true(cl->n_tris >= LIE_CLUSTER_MIN_TRIS);
        float area = 0.0f;
        for (uint32_t k = 0; k < cl->n_tris; k++) {
            uint32_t g = s->cluster_tris[cl->first + k];
            assert_true(lie_emitter_owns(em, g));
            assert_int_equal(s->tri_cluster[g], c);
            assert_false(seen[g]);
            seen[g] = 1;
            if (k)
                assert_true(g > s->cluster_tris[cl->first + k - 1]);
            area += s->tri_area[g];
        }
        assert_float_equal(cl->area, area, 1e-4f * area);
        assert_memory_equal(&s->clusters[c], &t->clusters[c], sizeof *cl);
        total += cl->n_tris;
    }
    assert_int_equal(total, em->n_tris);
    /* the other emitters' and plain triangles belong to no cluster of the strip */
    for (uint32_t g = 0; g < s->n_tris; g++)
        if (!lie_emitter_owns(em, g))
            assert_true(s->tri_cluster[g] < em->first_cluster ||
                        s->tri_cluster[g] >= em->first_cluster + em->n_clusters);
    free(seen);
    lie_scene_destroy(s);
    lie_scene_destroy(t);
}

/* Each cluster's hull holds its triangles, is smaller than the emitter's,
 * and its segment targets lie on its own triangles. */
static void test_cluster_shapes_and_targets(void **state)
{
    (void)state;
    lie_scene *s = load();
    int e = strip_emitter(s);
    const lie_emitter *em = &s->emitters[e];
    lie_box3 whole = lie_box3_empty();
    for (int k = 0; k < em->n_hull; k++)
        lie_box3_grow(&whole, em->hull[k]);
    lie_vec3 V[3] = {lie_v3(0, 0, 0), lie_v3(1, 0, 0), lie_v3(0, 0, 1)};
    for (int c = em->first_cluster; c < em->first_cluster + em->n_clusters; c++) {
        const lie_cluster *cl = &s->clusters[c];
        lie_vec3 pts[64 * 3];
        assert_true(lie_cluster_hull_cap(s, c) <= 64 * 3);
        int n = lie_cluster_hull_points(s, c, V, 100.0f, pts);
        assert_true(n >= 3);
        lie_box3 b = lie_box3_empty();
        for (int k = 0; k < n; k++)
            lie_box3_grow(&b, pts[k]);
        float tol = 1e-4f;
        for (uint32_t k = 0; k < cl->n_tris; k++)
            for (int j = 0; j < 3; j++) {
                lie_vec3 p = s->tri_p[3 * (size_t)s->cluster_tris[cl->first + k] + (size_t)j];
                assert_true(p.x >= b.lo.x - tol && p.x <= b.hi.x + tol);
                assert_true(p.z >= b.lo.z - tol && p.z <= b.hi.z + tol);
            }
        assert_true(b.hi.x - b.lo.x < 0.6f * (whole.hi.x - whole.lo.x));
        for (int i = 0; i < 16; i++) {
            lie_vec3 q, nq;
            int one_sided;
            uint32_t g = lie_cluster_target(s, c, (float)i / 16.0f, 0.37f, lie_v3(0, 0, 0), 100.0f, &q, &nq, &one_sided);
            assert_int_equal(s->tri_cluster[g], c);
            assert_true(one_sided);
            assert_true(nq.y < -0.99f); /* the strip faces down */
        }
        /* the floor under the strip is reached; a patch above it is not */
        lie_vec3 up[3] = {lie_v3(-4, 3, -1), lie_v3(4, 3, -1), lie_v3(0, 3, 1)};
        lie_vec3 down[3] = {lie_v3(-4, 0, -1), lie_v3(-4, 0, 1), lie_v3(4, 0, 1)};
        assert_true(lie_cluster_can_reach(s, c, 0, down, lie_v3(0, 1, 0), 0));
        assert_false(lie_cluster_can_reach(s, c, 0, up, lie_v3(0, -1, 0), 0));
    }
    lie_scene_destroy(s);
}

static lie_env *build(const lie_scene *s, lie_blocker_mode mode, int threads)
{
    lie_error err;
    lie_rt *rt = NULL;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_build_params p = lie_build_params_default();
    p.min_patch = 1e-3f;
    p.mode = mode;
    p.threads = threads;
    lie_env *env = NULL;
    assert_int_equal(lie_env_build(s, rt, &p, NULL, &env, NULL, &err), LIE_OK);
    lie_rt_destroy(rt);
    return env;
}

/* Units per cluster; the same env for any thread count; a cluster's pairs
 * differ from its neighbour's (each sees its part of the strip). */
static void test_build_has_a_unit_per_cluster(void **state)
{
    (void)state;
    lie_scene *s = load();
    lie_env *a = build(s, LIE_BLOCKERS_SAMPLED, 1), *b = build(s, LIE_BLOCKERS_SAMPLED, 2);
    assert_int_equal(a->n_clusters, s->n_clusters);
    assert_env_equal(a, b);
    int e = strip_emitter(s);
    const lie_emitter *em = &s->emitters[e];
    /* a floor triangle: its classes differ between clusters */
    int differ = 0;
    for (uint32_t t = 0; t < s->n_tris && !differ; t++) {
        if (s->tri_emitter[t] >= 0 || s->tri_ng[t].y < 0.9f)
            continue;
        int c0 = em->first_cluster;
        for (int c = c0 + 1; c < c0 + em->n_clusters; c++) {
            const lie_pnode *x = &a->nodes[a->root[(size_t)t * (size_t)a->n_clusters + (size_t)c0]];
            const lie_pnode *y = &a->nodes[a->root[(size_t)t * (size_t)a->n_clusters + (size_t)c]];
            differ |= x->cls != y->cls || x->count != y->count || x->child != 0 || y->child != 0;
        }
    }
    assert_true(differ);
    lie_env_destroy(a);
    lie_env_destroy(b);
    lie_scene_destroy(s);
}

/* A cache of the strip, as lie-build makes it. */
static lie_cache *make_cache(const lie_scene *s)
{
    lie_error err;
    lie_cache *c = calloc(1, sizeof *c);
    c->scene_path = strdup(STRIP);
    c->scene_hash = s->hash;
    assert_int_equal(lie_cache_set_state(c, s, &err), LIE_OK);
    c->env = build(s, LIE_BLOCKERS_SAMPLED, 2);
    return c;
}

/* A cache of a clustered emitter round-trips, and a scene clustered
 * otherwise is refused with a message that says so. */
static void test_cache_records_the_partition(void **state)
{
    (void)state;
    lie_error err;
    lie_scene *s = load();
    lie_cache *c = make_cache(s);
    unsigned char *data = NULL;
    size_t size = 0;
    assert_int_equal(lie_cache_encode(c, &data, &size, &err), LIE_OK);
    lie_cache *d = NULL;
    assert_int_equal(lie_cache_decode(data, size, "strip.lie", &d, &err), LIE_OK);
    int e = strip_emitter(s);
    assert_int_equal(d->emitters[e].n_clusters, s->emitters[e].n_clusters);
    assert_int_equal(d->emitters[e].partition, lie_scene_cluster_digest(s, e));
    assert_env_equal(c->env, d->env);
    lie_cache_destroy(d);
    free(data);
    /* a partition digest this scene does not give: the cache encodes, but
     * loading its scene is refused with a message naming the clusters */
    c->emitters[e].partition ^= 0x10u;
    assert_int_equal(lie_cache_encode(c, &data, &size, &err), LIE_OK);
    char path[] = "/tmp/lie-cluster-XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, data, size), (ssize_t)size);
    close(fd);
    lie_cache *r = NULL;
    assert_int_equal(lie_cache_read(path, &r, &err), LIE_OK);
    lie_scene *rs = NULL;
    assert_int_equal(lie_cache_load_scene(r, path, STRIP, NULL, &rs, &err), LIE_ERR_FORMAT);
    assert_non_null(strstr(err.msg, "clusters"));
    lie_cache_destroy(r);
    unlink(path);
    free(data);
    lie_cache_destroy(c);
    lie_scene_destroy(s);
}

/* An edit's update equals a rebuild of the edited scene when the edit
 * touches the clustered emitter (moving it moves all its clusters) or a
 * blocker in its clusters' shafts. */
static void check_update(const char *text)
{
    lie_error err;
    lie_scene *s = load();
    lie_cache *c = make_cache(s);
    lie_update_options o = lie_update_options_default();
    o.threads = 2;
    lie_update *u = NULL;
    assert_int_equal(lie_update_create(c, s, &o, &u, &err), LIE_OK);
    lie_edit *ed = NULL;
    assert_int_equal(lie_edit_parse((const unsigned char *)text, strlen(text), STRIP, &ed, &err), LIE_OK);
    assert_int_equal(lie_update_edit(u, ed, (const unsigned char *)text, strlen(text), &err), LIE_OK);
    lie_edit_destroy(ed);
    size_t left = 0;
    do
        assert_int_equal(lie_update_step(u, 0, &left, &err), LIE_OK);
    while (left);
    lie_update_destroy(u);

    lie_scene *r = load();
    lie_scene_options so = lie_scene_options_default();
    assert_int_equal(lie_edit_parse((const unsigned char *)text, strlen(text), STRIP, &ed, &err), LIE_OK);
    assert_int_equal(lie_edit_apply(r, ed, &so, NULL, &err), LIE_OK);
    lie_edit_destroy(ed);
    lie_env *ref = build(r, LIE_BLOCKERS_SAMPLED, 2);
    assert_true(c->state_hash == r->hash);
    assert_env_equal(c->env, ref);
    for (int e = 0; e < r->n_emitters; e++) {
        assert_int_equal(c->emitters[e].n_clusters, r->emitters[e].n_clusters);
        assert_int_equal(c->emitters[e].partition, lie_scene_cluster_digest(r, e));
    }
    lie_env_destroy(ref);
    lie_scene_destroy(r);
    lie_cache_destroy(c);
    lie_scene_destroy(s);
}

static void test_update_equals_rebuild_with_clusters(void **state)
{
    (void)state;
    check_update("- move: {node: Pillar1, by: [0.4, 0, 0.1]}\n");
    check_update("- move: {node: Strip, by: [0.3, -0.05, 0]}\n");
    check_update("- rotate: {node: Strip, axis: [0, 1, 0], degrees: 10}\n");
    check_update("- remove: {node: Beam}\n");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_strip_is_partitioned_into_clusters),
        cmocka_unit_test(test_cluster_shapes_and_targets),
        cmocka_unit_test(test_build_has_a_unit_per_cluster),
        cmocka_unit_test(test_cache_records_the_partition),
        cmocka_unit_test(test_update_equals_rebuild_with_clusters),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
