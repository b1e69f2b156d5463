/* SPDX-License-Identifier: Apache-2.0 */
/* Clusters of emitter triangles (lib/scene/cluster.c): the partition, the
 * per-cluster shapes lib/lie asks for, and that LIEs build per cluster,
 * round-trip through the cache and update as they rebuild.  Fixtures
 * (gen_fixtures.py): tests/data/gltf/dark_panel.gltf, a panel whose
 * emissive texture is black over its left quarter and one black all over
 * (a dark cluster); light_strip.gltf, an 80-triangle strip down a corridor. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lie.h"
#include "fixtures.h"

#define PANEL "tests/data/gltf/dark_panel.gltf"
#define STRIP "tests/data/gltf/light_strip.gltf"

/* Loaded with at most `clusters` spatial clusters per untextured emitter
 * (lie_scene_options.emitter_clusters; 0: the default, 1). */
static lie_scene *load_split(const char *path, int clusters)
{
    lie_scene *s = NULL;
    lie_error err;
    lie_scene_options o = lie_scene_options_default();
    o.emitter_clusters = clusters;
    assert_int_equal(lie_scene_load(path, &o, &s, &err), LIE_OK);
    assert_int_equal(s->cluster_max, clusters);
    return s;
}

static lie_scene *load(const char *path)
{
    return load_split(path, 0);
}

static lie_env *build_mode(const lie_scene *s, int threads, lie_blocker_mode mode)
{
    lie_error err;
    lie_rt *rt = NULL;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_build_params p = lie_build_params_default();
    p.min_patch = 1e-3f;
    p.threads = threads;
    p.mode = mode;
    lie_env *env = NULL;
    assert_int_equal(lie_env_build(s, rt, &p, NULL, &env, NULL, &err), LIE_OK);
    lie_rt_destroy(rt);
    return env;
}

static lie_env *build(const lie_scene *s, int threads)
{
    return build_mode(s, threads, LIE_BLOCKERS_SAMPLED);
}

/* dark_panel.gltf: a panel whose texture is black over a quarter is one
 * lit cluster (a partly dark emitter is not split: CLUSTER_DARK_SPLIT); a
 * panel black everywhere is one dark cluster.  Clusters are the emitters'
 * triangles, in order, the same on every load; an untextured strip is one
 * cluster too. */
static void test_black_texture_makes_a_dark_cluster(void **state)
{
    (void)state;
    lie_scene *s = load(PANEL), *t = load(PANEL);
    assert_int_equal(s->n_emitters, 2);
    assert_int_equal(s->n_clusters, 2);
    assert_int_equal(t->n_clusters, 2);
    for (int e = 0; e < s->n_emitters; e++) {
        const lie_emitter *em = &s->emitters[e];
        assert_int_equal(em->n_clusters, 1);
        assert_int_equal(lie_scene_cluster_digest(s, e), 0);
        const lie_cluster *cl = &s->clusters[em->first_cluster];
        assert_memory_equal(cl, &t->clusters[em->first_cluster], sizeof *cl);
        assert_int_equal(cl->emitter, e);
        assert_int_equal(cl->n_tris, em->n_tris);
        assert_int_equal(cl->dark, em->n_tris == 2); /* the black panel's 2 triangles */
        for (uint32_t k = 0; k < cl->n_tris; k++) {
            assert_int_equal(s->cluster_tris[cl->first + k], em->first_tri + k);
            assert_int_equal(s->tri_cluster[em->first_tri + k], em->first_cluster);
        }
        assert_float_equal(cl->area, em->area, 1e-4f * em->area);
    }
    lie_scene *strip = load(STRIP);
    assert_int_equal(strip->n_clusters, strip->n_emitters);
    assert_false(strip->clusters[0].dark);
    lie_scene_destroy(strip);
    lie_scene_destroy(s);
    lie_scene_destroy(t);
}

/* The lit panel's cluster answers as its emitter: its hull holds its
 * triangles, its segment targets lie on them, it reaches the floor below
 * and not a patch above; the dark panel's cluster reaches nothing. */
static void test_cluster_shapes_and_targets(void **state)
{
    (void)state;
    lie_scene *s = load(PANEL);
    const int lit = s->clusters[0].dark ? 1 : 0, dark = 1 - lit;
    const lie_cluster *cl = &s->clusters[lit];
    lie_vec3 V[3] = {lie_v3(0, 0, 0), lie_v3(1, 0, 0), lie_v3(0, 0, 1)};
    lie_vec3 pts[3 * 32];
    assert_true(lie_cluster_hull_cap(s, lit) <= 3 * 32);
    int n = lie_cluster_hull_points(s, lit, V, 100.0f, pts);
    assert_true(n >= 3);
    lie_box3 b = lie_box3_empty();
    for (int k = 0; k < n; k++)
        lie_box3_grow(&b, pts[k]);
    for (uint32_t k = 0; k < cl->n_tris; k++)
        for (int j = 0; j < 3; j++) {
            lie_vec3 p = s->tri_p[3 * (size_t)s->cluster_tris[cl->first + k] + (size_t)j];
            assert_true(p.x >= b.lo.x - 1e-4f && p.x <= b.hi.x + 1e-4f);
            assert_true(p.z >= b.lo.z - 1e-4f && p.z <= b.hi.z + 1e-4f);
        }
    for (int i = 0; i < 16; i++) {
        lie_vec3 q, nq;
        int one_sided;
        uint32_t g = lie_cluster_target(s, lit, (float)i / 16.0f, 0.37f, lie_v3(0, 0, 0), 100.0f, &q, &nq, &one_sided);
        assert_int_equal(s->tri_cluster[g], lit);
        assert_true(one_sided);
        assert_true(nq.y < -0.99f); /* the panel faces down */
    }
    lie_vec3 up[3] = {lie_v3(-3, 3, -3), lie_v3(3, 3, -3), lie_v3(0, 3, 3)};
    lie_vec3 down[3] = {lie_v3(-3, 0, -3), lie_v3(-3, 0, 3), lie_v3(3, 0, 3)};
    assert_true(lie_cluster_can_reach(s, lit, 0, down, lie_v3(0, 1, 0), 0));
    assert_false(lie_cluster_can_reach(s, lit, 0, up, lie_v3(0, -1, 0), 0));
    assert_true(lie_emitter_can_reach(s, s->clusters[dark].emitter, 0, down, lie_v3(0, 1, 0), 0));
    assert_false(lie_cluster_can_reach(s, dark, 0, down, lie_v3(0, 1, 0), 0));
    lie_scene_destroy(s);
}

/* Units per cluster, the same for any thread count: every unit of the
 * dark cluster is one unlit leaf; some of the lit one's are not. */
static void test_build_has_a_unit_per_cluster(void **state)
{
    (void)state;
    lie_scene *s = load(PANEL);
    lie_env *a = build(s, 1), *b = build(s, 2);
    assert_int_equal(a->n_clusters, s->n_clusters);
    assert_env_equal(a, b);
    const int lit = s->clusters[0].dark ? 1 : 0, dark = 1 - lit;
    int lit_pairs = 0;
    for (uint32_t t = 0; t < s->n_tris; t++) {
        const lie_pnode *d = &a->nodes[a->root[(size_t)t * (size_t)a->n_clusters + (size_t)dark]];
        assert_int_equal(d->child, 0);
        assert_int_equal(d->cls, LIE_CLASS_UNLIT);
        const lie_pnode *l = &a->nodes[a->root[(size_t)t * (size_t)a->n_clusters + (size_t)lit]];
        lit_pairs += l->child != 0 || l->cls != LIE_CLASS_UNLIT;
    }
    assert_true(lit_pairs > 0);
    lie_env_destroy(a);
    lie_env_destroy(b);
    lie_scene_destroy(s);
}

/* A cache of the panel, as lie-build makes it. */
static lie_cache *make_cache(const lie_scene *s, const char *path)
{
    lie_error err;
    lie_cache *c = calloc(1, sizeof *c);
    c->scene_path = strdup(path);
    c->scene_hash = s->hash;
    assert_int_equal(lie_cache_set_state(c, s, &err), LIE_OK);
    c->env = build(s, 2);
    return c;
}

/* A cache records each emitter's clusters and round-trips them; a
 * partition digest that does not fit the cluster count is refused. */
static void test_cache_records_the_partition(void **state)
{
    (void)state;
    lie_error err;
    lie_scene *s = load(PANEL);
    lie_cache *c = make_cache(s, PANEL);
    unsigned char *data = NULL;
    size_t size = 0;
    assert_int_equal(lie_cache_encode(c, &data, &size, &err), LIE_OK);
    lie_cache *d = NULL;
    assert_int_equal(lie_cache_decode(data, size, "panel.lie", &d, &err), LIE_OK);
    for (int e = 0; e < s->n_emitters; e++) {
        assert_int_equal(d->emitters[e].n_clusters, 1);
        assert_int_equal(d->emitters[e].partition, 0);
    }
    assert_env_equal(c->env, d->env);
    lie_cache_destroy(d);
    free(data);
    c->emitters[0].partition = 0x1234u;
    assert_int_equal(lie_cache_encode(c, &data, &size, &err), LIE_ERR_ARG);
    assert_non_null(strstr(err.msg, "partition"));
    lie_cache_destroy(c);
    lie_scene_destroy(s);
}

/* An edit's update equals a rebuild of the edited scene, for edits that
 * touch the clustered emitter (moving it moves all its clusters) or a
 * blocker in its clusters' shafts. */
static void check_update_split(const char *scene, int clusters, const char *text)
{
    lie_error err;
    lie_scene *s = load_split(scene, clusters);
    lie_cache *c = make_cache(s, scene);
    lie_update_options o = lie_update_options_default();
    o.threads = 2;
    lie_update *u = NULL;
    assert_int_equal(lie_update_create(c, s, &o, &u, &err), LIE_OK);
    lie_edit *ed = NULL;
    assert_int_equal(lie_edit_parse((const unsigned char *)text, strlen(text), scene, &ed, &err), LIE_OK);
    assert_int_equal(lie_update_edit(u, ed, &err), LIE_OK);
    lie_edit_destroy(ed);
    size_t left = 0;
    do
        assert_int_equal(lie_update_step(u, 0, &left, &err), LIE_OK);
    while (left);
    lie_update_destroy(u);

    lie_scene *r = load_split(scene, clusters);
    lie_scene_options so = lie_scene_options_default();
    assert_int_equal(lie_edit_parse((const unsigned char *)text, strlen(text), scene, &ed, &err), LIE_OK);
    assert_int_equal(lie_edit_apply(r, ed, &so, NULL, &err), LIE_OK);
    lie_edit_destroy(ed);
    lie_env *ref = build(r, 2);
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

static void check_update(const char *scene, const char *text)
{
    check_update_split(scene, 0, text);
}

static void test_update_equals_rebuild_with_clusters(void **state)
{
    (void)state;
    check_update(PANEL, "- move: {node: Box, by: [0.3, 0, 0.2]}\n");
    check_update(PANEL, "- remove: {node: Box}\n");
    check_update(PANEL, "- move: {node: Panel, by: [0.2, 0.1, 0]}\n");
    check_update(PANEL, "- rotate: {node: Panel, axis: [0, 1, 0], degrees: 15}\n");
    check_update(PANEL, "- move: {node: BlackPanel, by: [0, -0.5, 0]}\n");
    check_update(STRIP, "- move: {node: Pillar1, by: [0.4, 0, 0.1]}\n");
    check_update(STRIP, "- remove: {node: Beam}\n");
}

/* ---- spatial clusters (lie_scene_options.emitter_clusters) ----------------
 * Off by default (measured: README, "Clusters"), but a real path: the strip
 * split in space must partition its triangles, build per cluster the same
 * for any thread count, render as full visibility does, refuse a cache of
 * another partition, and update as it rebuilds. */

/* The strip in up to 4 clusters: a partition of its triangles in
 * ascending order, each a connected stretch along the corridor, with the
 * same digest on every load, and a digest a 1-cluster load does not have. */
static void test_strip_splits_in_space(void **state)
{
    (void)state;
    lie_scene *s = load_split(STRIP, 4), *t = load_split(STRIP, 4), *one = load(STRIP);
    const lie_emitter *em = &s->emitters[0];
    assert_true(em->n_clusters >= 2 && em->n_clusters <= 4);
    assert_int_equal(one->emitters[0].n_clusters, 1);
    assert_int_not_equal(lie_scene_cluster_digest(s, 0), 0);
    assert_int_equal(lie_scene_cluster_digest(s, 0), lie_scene_cluster_digest(t, 0));
    unsigned char *seen = calloc(em->n_tris, 1);
    double area = 0.0;
    for (int c = em->first_cluster; c < em->first_cluster + em->n_clusters; c++) {
        const lie_cluster *cl = &s->clusters[c];
        assert_int_equal(cl->emitter, 0);
        assert_false(cl->dark);
        assert_true(cl->n_tris >= LIE_CLUSTER_MIN_TRIS);
        assert_memory_equal(cl, &t->clusters[c], sizeof *cl);
        for (uint32_t k = 0; k < cl->n_tris; k++) {
            uint32_t g = s->cluster_tris[cl->first + k];
            assert_true(g >= em->first_tri && g < em->first_tri + em->n_tris);
            if (k > 0)
                assert_true(g > s->cluster_tris[cl->first + k - 1]);
            assert_int_equal(seen[g - em->first_tri], 0);
            seen[g - em->first_tri] = 1;
            assert_int_equal(s->tri_cluster[g], c);
        }
        area += cl->area;
        /* its hull holds its triangles, and is smaller than the emitter's */
        lie_vec3 V[3] = {lie_v3(0, 0, 0), lie_v3(0.1f, 0, 0), lie_v3(0, 0, 0.1f)};
        lie_vec3 pts[3 * 64];
        assert_true(lie_cluster_hull_cap(s, c) <= 3 * 64);
        assert_true(lie_cluster_hull_points(s, c, V, 100.0f, pts) >= 3);
    }
    for (uint32_t k = 0; k < em->n_tris; k++)
        assert_int_equal(seen[k], 1);
    assert_float_equal(area, em->area, 1e-4 * em->area);
    free(seen);
    lie_scene_destroy(s);
    lie_scene_destroy(t);
    lie_scene_destroy(one);
}

static lie_frame *render_strip(const lie_scene *s, const lie_env *env, int threads)
{
    lie_error err;
    lie_rt *rt = NULL;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_camera cam = lie_scene_default_camera(s);
    lie_render_options o = test_render_options(48, 32, 24, threads);
    o.exact = LIE_EXACT_OFF; /* sampled partial pairs: the oracle's image is full visibility's */
    lie_env_shadows *lv = NULL;
    if (env) {
        assert_int_equal(lie_env_shadows_create(s, env, &lv, &err), LIE_OK);
        o.visibility = LIE_VIS_LIE;
        o.oracle = lie_env_shadows_oracle(lv);
    } else {
        o.visibility = LIE_VIS_FULL;
    }
    lie_frame *f = NULL;
    assert_int_equal(lie_render(s, rt, &cam, &o, &f, NULL, &err), LIE_OK);
    lie_env_shadows_destroy(lv);
    lie_rt_destroy(rt);
    return f;
}

/* Units per (triangle, cluster), the same for 1 and 2 threads; with
 * conservative lists the LIE image of the split strip is full
 * visibility's, pixel for pixel, and the same for any thread count. */
static void test_split_strip_builds_and_renders_as_full(void **state)
{
    (void)state;
    lie_scene *s = load_split(STRIP, 4);
    lie_env *a = build_mode(s, 1, LIE_BLOCKERS_CONSERVATIVE), *b = build_mode(s, 2, LIE_BLOCKERS_CONSERVATIVE);
    assert_int_equal(a->n_clusters, s->n_clusters);
    assert_true(a->n_clusters > s->n_emitters);
    assert_env_equal(a, b);
    lie_frame *full = render_strip(s, NULL, 2), *l1 = render_strip(s, a, 1), *l2 = render_strip(s, a, 2);
    size_t n = (size_t)3 * full->width * full->height;
    assert_memory_equal(l1->rgb, l2->rgb, sizeof(float) * n);
    double lit = 0.0;
    for (size_t i = 0; i < n; i++) {
        assert_float_equal(l1->rgb[i], full->rgb[i], 1e-5f * (1.0f + full->rgb[i]));
        lit += full->rgb[i];
    }
    assert_true(lit > 0.0);
    lie_frame_destroy(full);
    lie_frame_destroy(l1);
    lie_frame_destroy(l2);
    lie_env_destroy(a);
    lie_env_destroy(b);
    lie_scene_destroy(s);
}

/* The sampled build of the split strip shares the strip's segments among
 * its clusters (lib/lie/sample.c): a node of a cluster casts fewer
 * segments than a node of the whole strip does; the env is the same for 1
 * and 2 threads, and its image is full visibility's (leaves get their
 * cluster's exact list). */
static void test_split_strip_shares_its_sampling(void **state)
{
    (void)state;
    lie_scene *s = load_split(STRIP, 4), *one = load(STRIP);
    lie_error err;
    lie_build_stats st1, st4, st4b;
    lie_env *e1 = NULL, *a = NULL, *b = NULL;
    lie_rt *rt1 = NULL, *rt4 = NULL;
    assert_int_equal(lie_rt_create(one, &rt1, &err), LIE_OK);
    assert_int_equal(lie_rt_create(s, &rt4, &err), LIE_OK);
    lie_build_params p = lie_build_params_default();
    p.min_patch = 1e-3f;
    p.threads = 1;
    assert_int_equal(lie_env_build(one, rt1, &p, NULL, &e1, &st1, &err), LIE_OK);
    assert_int_equal(lie_env_build(s, rt4, &p, NULL, &a, &st4, &err), LIE_OK);
    p.threads = 2;
    assert_int_equal(lie_env_build(s, rt4, &p, NULL, &b, &st4b, &err), LIE_OK);
    assert_env_equal(a, b);
    assert_true(s->emitters[0].n_clusters > 1);
    assert_true((double)st4.segments / (double)a->n_nodes < (double)st1.segments / (double)e1->n_nodes);
    lie_frame *full = render_strip(s, NULL, 2), *l = render_strip(s, a, 2);
    size_t n = (size_t)3 * full->width * full->height, off = 0;
    for (size_t i = 0; i < n; i++)
        off += fabsf(l->rgb[i] - full->rgb[i]) > 1e-5f * (1.0f + full->rgb[i]);
    assert_int_equal(off, 0);
    lie_frame_destroy(full);
    lie_frame_destroy(l);
    lie_env_destroy(e1);
    lie_env_destroy(a);
    lie_env_destroy(b);
    lie_rt_destroy(rt1);
    lie_rt_destroy(rt4);
    lie_scene_destroy(s);
    lie_scene_destroy(one);
}

/* A cache of the split strip records its partition: loaded with the
 * default options, its scene is split the same way (the cache's cluster
 * count, lib/cache/scene.c); read against the strip in one cluster, it is
 * refused by name. */
static void test_cache_of_another_partition_is_refused(void **state)
{
    (void)state;
    lie_error err;
    lie_scene *s = load_split(STRIP, 4);
    lie_cache *c = make_cache(s, STRIP);
    assert_int_equal(c->emitters[0].n_clusters, (uint32_t)s->emitters[0].n_clusters);
    assert_int_equal(c->emitters[0].partition, lie_scene_cluster_digest(s, 0));
    unsigned char *data = NULL;
    size_t size = 0;
    assert_int_equal(lie_cache_encode(c, &data, &size, &err), LIE_OK);
    lie_cache *d = NULL;
    assert_int_equal(lie_cache_decode(data, size, "strip.lie", &d, &err), LIE_OK);
    assert_env_equal(c->env, d->env);
    lie_scene *same = NULL;
    assert_int_equal(lie_cache_load_scene(d, "strip.lie", NULL, NULL, &same, &err), LIE_OK);
    assert_int_equal(same->emitters[0].n_clusters, s->emitters[0].n_clusters);
    assert_int_equal(lie_scene_cluster_digest(same, 0), lie_scene_cluster_digest(s, 0));
    lie_scene_destroy(same);
    lie_scene_options o1 = lie_scene_options_default();
    o1.emitter_clusters = 1;
    lie_scene *one = NULL;
    assert_int_equal(lie_cache_load_scene(d, "strip.lie", NULL, &o1, &one, &err), LIE_ERR_FORMAT);
    assert_null(one);
    assert_non_null(strstr(err.msg, "clusters"));
    lie_cache_destroy(d);
    free(data);
    lie_cache_destroy(c);
    lie_scene_destroy(s);
}

static void test_update_equals_rebuild_with_split_clusters(void **state)
{
    (void)state;
    check_update_split(STRIP, 4, "- move: {node: Pillar1, by: [0.4, 0, 0.1]}\n");
    check_update_split(STRIP, 4, "- remove: {node: Beam}\n");
    check_update_split(STRIP, 4, "- move: {node: Strip, by: [0.3, -0.1, 0.2]}\n");
    check_update_split(STRIP, 4, "- rotate: {node: Strip, axis: [0, 1, 0], degrees: 10}\n");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_black_texture_makes_a_dark_cluster),
        cmocka_unit_test(test_cluster_shapes_and_targets),
        cmocka_unit_test(test_build_has_a_unit_per_cluster),
        cmocka_unit_test(test_cache_records_the_partition),
        cmocka_unit_test(test_update_equals_rebuild_with_clusters),
        cmocka_unit_test(test_strip_splits_in_space),
        cmocka_unit_test(test_split_strip_builds_and_renders_as_full),
        cmocka_unit_test(test_split_strip_shares_its_sampling),
        cmocka_unit_test(test_cache_of_another_partition_is_refused),
        cmocka_unit_test(test_update_equals_rebuild_with_split_clusters),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
