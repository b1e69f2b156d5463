/* SPDX-License-Identifier: Apache-2.0 */
/* The asynchronous constructor (lib/update, lie_ctor; §4.3.1): whatever the
 * order units land in and whatever views came first, the cache it saves is
 * one build for its views (lie_env_build_views), partial while units are
 * pending; a held constructor lands nothing; units met unbuilt are built
 * on request; an edit during construction ends in the build of the edited
 * scene (update = rebuild); lie_env_compact lays out an env as a build. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lie.h"
#include "fixtures.h"

static int same_env(const lie_env *a, const lie_env *b)
{
    size_t units = (size_t)a->n_tris * (size_t)a->n_clusters;
    return a->n_nodes == b->n_nodes && a->n_pool == b->n_pool && a->partial == b->partial &&
           memcmp(a->root, b->root, sizeof *a->root * units) == 0 &&
           memcmp(a->nodes, b->nodes, sizeof *a->nodes * a->n_nodes) == 0 &&
           (a->n_pool == 0 || memcmp(a->pool, b->pool, sizeof *a->pool * a->n_pool) == 0);
}

typedef struct fixture {
    lie_scene *s;
    lie_rt *rt;
    lie_camera cams[2];
    lie_ctor_options co;
} fixture;

static void open_museum(fixture *f)
{
    lie_error err;
    memset(f, 0, sizeof *f);
    assert_int_equal(lie_scene_load(TEST_SCENES "/museum1.gltf", NULL, &f->s, &err), LIE_OK);
    assert_int_equal(lie_rt_create(f->s, &f->rt, &err), LIE_OK);
    assert_int_equal(lie_camera_parse(f->s, "0", &f->cams[0], &err), LIE_OK);
    assert_int_equal(lie_camera_parse(f->s, "eye=3,2,3,target=0,0.5,0", &f->cams[1], &err), LIE_OK);
    f->co = lie_ctor_options_default();
    f->co.params.min_patch = 1e-2f;
    f->co.view_width = f->co.view_height = 64;
    f->co.max_depth = 2;
    f->co.threads = 2;
}

static void close_fixture(fixture *f)
{
    lie_rt_destroy(f->rt);
    lie_scene_destroy(f->s);
}

/* One build for the views, as lie-build --view makes it. */
static lie_env *batch(const fixture *f, int n_views)
{
    lie_error err;
    lie_pixels *px = NULL;
    lie_env *env = NULL;
    lie_build_stats st;
    assert_int_equal(lie_camera_pixels(f->s, f->rt, f->cams, n_views, f->co.view_width, f->co.view_height,
                                       f->co.max_depth, &px, &err),
                     LIE_OK);
    assert_int_equal(lie_env_build_views(f->s, f->rt, &f->co.params, px, NULL, &env, &st, &err), LIE_OK);
    lie_pixels_destroy(px);
    return env;
}

static lie_env *saved(lie_ctor *c, const lie_scene *s)
{
    lie_cache prov;
    memset(&prov, 0, sizeof prov);
    prov.scene_path = (char *)s->path;
    prov.scene_hash = s->hash;
    lie_cache *cache = NULL;
    lie_error err;
    assert_int_equal(lie_ctor_cache(c, &prov, &cache, &err), LIE_OK);
    lie_env *env = cache->env;
    cache->env = NULL;
    lie_cache_destroy(cache);
    return env;
}

/* Two views, the second while the first is being built: the saved env is
 * one build for both; a built env compacts to itself. */
static void test_two_views_end_in_one_build_for_both(void **state)
{
    (void)state;
    fixture f;
    open_museum(&f);
    lie_ctor *c = NULL;
    lie_error err;
    assert_int_equal(lie_ctor_create(f.s, f.rt, &f.co, NULL, &c, &err), LIE_OK);
    lie_ctor_stats cs;
    /* the second view once the first is taken (a view asked for before the
     * last is taken replaces it), while its units land */
    lie_ctor_view(c, &f.cams[0]);
    do {
        lie_ctor_wait(c, 0.001, NULL);
        lie_ctor_get_stats(c, &cs);
    } while (cs.views < 1);
    lie_ctor_view(c, &f.cams[1]);
    do {
        lie_ctor_wait(c, 0.001, NULL);
        lie_ctor_get_stats(c, &cs);
    } while (cs.views < 2);
    lie_ctor_view(c, &f.cams[0]); /* known: reorders only */
    assert_int_equal(lie_ctor_wait(c, -1.0, &err), 1);
    lie_ctor_get_stats(c, &cs);
    assert_int_equal(cs.units_pending, 0);
    assert_int_equal(cs.views, 2);
    lie_env *got = saved(c, f.s), *want = batch(&f, 2);
    assert_true(same_env(got, want));
    lie_env *again = NULL;
    assert_int_equal(lie_env_compact(want, &again, &err), LIE_OK);
    assert_true(same_env(again, want));
    lie_env_destroy(again);
    lie_env_destroy(got);
    lie_env_destroy(want);
    lie_ctor_destroy(c);
    close_fixture(&f);
}

/* Held: nothing lands, the saved env is partial with no unit built; a
 * manual constructor builds what a camera sees, then what was met unbuilt. */
static void test_held_and_manual_constructors(void **state)
{
    (void)state;
    fixture f;
    open_museum(&f);
    lie_error err;
    f.co.views = f.cams;
    f.co.n_views = 1;
    f.co.manual = 1;
    lie_ctor *c = NULL;
    assert_int_equal(lie_ctor_create(f.s, f.rt, &f.co, NULL, &c, &err), LIE_OK);
    lie_env *none = saved(c, f.s);
    assert_true(none->partial);
    size_t units = (size_t)f.s->n_tris * (size_t)f.s->n_clusters;
    for (size_t u = 0; u < units; u++)
        assert_int_equal(none->nodes[none->root[u]].cls, LIE_CLASS_NONE);
    uint64_t built = 0;
    assert_int_equal(lie_ctor_build(c, NULL, &f.cams[0], 2, &built, &err), LIE_OK);
    assert_true(built > 0);
    uint8_t *all = malloc(f.s->n_tris);
    assert_non_null(all);
    memset(all, 1, f.s->n_tris);
    assert_int_equal(lie_ctor_build(c, all, NULL, 2, &built, &err), LIE_OK);
    assert_int_equal(lie_ctor_wait(c, 0.0, &err), 1);
    lie_env *got = saved(c, f.s), *want = batch(&f, 1);
    assert_true(same_env(got, want));
    free(all);
    lie_env_destroy(none);
    lie_env_destroy(got);
    lie_env_destroy(want);
    lie_ctor_destroy(c);
    close_fixture(&f);
}

/* An edit while units land: the end is the build of the edited scene. */
static void test_an_edit_during_construction_ends_in_the_edited_build(void **state)
{
    (void)state;
    fixture f;
    open_museum(&f);
    lie_error err;
    lie_ctor *c = NULL;
    assert_int_equal(lie_ctor_create(f.s, f.rt, &f.co, NULL, &c, &err), LIE_OK);
    lie_ctor_view(c, &f.cams[0]);
    lie_ctor_wait(c, 0.05, NULL);
    static const char text[] = "- move: {node: Cube, by: [0.4, 0, -0.3]}\n";
    lie_edit *e = NULL;
    assert_int_equal(lie_edit_parse((const unsigned char *)text, sizeof text - 1, "e.yaml", &e, &err), LIE_OK);
    lie_ctor_hold(c);
    assert_int_equal(lie_edit_apply(f.s, e, NULL, NULL, &err), LIE_OK);
    lie_rt *rt = NULL;
    assert_int_equal(lie_rt_create(f.s, &rt, &err), LIE_OK);
    assert_int_equal(lie_ctor_edited(c, rt, 1, &err), LIE_OK);
    lie_rt_destroy(f.rt);
    f.rt = rt;
    lie_ctor_release(c);
    assert_int_equal(lie_ctor_wait(c, -1.0, &err), 1);
    lie_env *got = saved(c, f.s), *want = batch(&f, 1);
    assert_true(same_env(got, want));
    lie_edit_destroy(e);
    lie_env_destroy(got);
    lie_env_destroy(want);
    lie_ctor_destroy(c);
    close_fixture(&f);
}

/* Apply one edit as lie-view does: held, the scene edited, its Embree scene
 * made again, the constructor told. */
static void ctor_edit(lie_ctor *c, fixture *f, const char *text)
{
    lie_error err;
    lie_edit *e = NULL;
    assert_int_equal(lie_edit_parse((const unsigned char *)text, strlen(text), "e.yaml", &e, &err), LIE_OK);
    lie_ctor_hold(c);
    assert_int_equal(lie_edit_apply(f->s, e, NULL, NULL, &err), LIE_OK);
    lie_rt *rt = NULL;
    assert_int_equal(lie_rt_create(f->s, &rt, &err), LIE_OK);
    assert_int_equal(lie_ctor_edited(c, rt, 1, &err), LIE_OK);
    lie_rt_destroy(f->rt);
    f->rt = rt;
    lie_ctor_release(c);
    lie_edit_destroy(e);
}

/* Six emitters: an edit sends back only the units whose shafts the moved
 * geometry may reach, not their triangles' other units, and a second edit
 * while those are pending adds to them; a moved light sends back its own
 * units, not every unit; each time the end is the edited scene's build,
 * byte for byte. */
static void test_edits_send_back_units_not_triangles(void **state)
{
    (void)state;
    fixture f;
    lie_error err;
    memset(&f, 0, sizeof f);
    assert_int_equal(lie_scene_load(TEST_SCENES "/museum3.gltf", NULL, &f.s, &err), LIE_OK);
    assert_int_equal(lie_rt_create(f.s, &f.rt, &err), LIE_OK);
    /* inside the room, over the first table group under its light */
    assert_int_equal(lie_camera_parse(f.s, "eye=-3,2.5,0,target=-6,0.5,-3.5", &f.cams[0], &err), LIE_OK);
    f.co = lie_ctor_options_default();
    f.co.params.min_patch = 1e-2f;
    f.co.view_width = f.co.view_height = 48;
    f.co.max_depth = 2;
    f.co.threads = 2;
    assert_true(f.s->n_clusters > 1);
    lie_ctor *c = NULL;
    assert_int_equal(lie_ctor_create(f.s, f.rt, &f.co, NULL, &c, &err), LIE_OK);
    lie_ctor_view(c, &f.cams[0]);
    assert_int_equal(lie_ctor_wait(c, -1.0, &err), 1);
    lie_ctor_stats st;
    lie_ctor_get_stats(c, &st);
    uint64_t before = st.units_built;
    ctor_edit(c, &f, "- move: {node: G1Chair1, by: [0.3, 0, 0.2]}\n");
    ctor_edit(c, &f, "- move: {node: G1Table, by: [-0.2, 0, 0.1]}\n");
    assert_int_equal(lie_ctor_wait(c, -1.0, &err), 1);
    lie_ctor_get_stats(c, &st);
    /* some units went again, far from all of the view's */
    assert_true(st.units_built > before);
    assert_true(st.units_built - before < before / 2);
    lie_env *got = saved(c, f.s), *want = batch(&f, 1);
    assert_true(same_env(got, want));
    lie_env_destroy(got);
    lie_env_destroy(want);
    /* a light moved: its units go again, and those of the others whose
     * cost-model decision its light turns; not all */
    uint64_t built = st.units_built;
    ctor_edit(c, &f, "- move: {node: Light1, by: [0.5, 0, 0.25]}\n");
    assert_int_equal(lie_ctor_wait(c, -1.0, &err), 1);
    lie_ctor_get_stats(c, &st);
    assert_true(st.units_built > built);
    assert_true(st.units_built - built < before);
    got = saved(c, f.s);
    want = batch(&f, 1);
    assert_true(same_env(got, want));
    lie_env_destroy(got);
    lie_env_destroy(want);
    lie_ctor_destroy(c);
    close_fixture(&f);
}

/* A floor 8 x 8 under a square light, with nine small blockers between
 * them, each a node of its own: the floor's patch trees split deep along
 * the nine shadows, and moving one blocker reaches a corner of them. */
static lie_scene *blockers_scene(void)
{
    lie_scene *s = lie_scene_new("blockers");
    int mw = test_material(s, 1.0f, 0.0f, 0), mb = test_material(s, 1.0f, 0.0f, 1);
    int ml = test_material(s, 0.0f, 5.0f, 0);
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    float fl[12] = {-4, 0, -4, -4, 0, 4, 4, 0, 4, 4, 0, -4};
    float li[12] = {-0.5f, 3, -0.5f, 0.5f, 3, -0.5f, 0.5f, 3, 0.5f, -0.5f, 3, 0.5f};
    lie_scene_add_node(s, "Floor", -1, NULL, lie_scene_add_mesh(s, "Floor", fl, NULL, NULL, 4, idx, 2, mw), -1, -1);
    lie_scene_add_node(s, "Light", -1, NULL, lie_scene_add_mesh(s, "Light", li, NULL, NULL, 4, idx, 2, ml), -1, -1);
    for (int i = 0; i < 9; i++) {
        float x = -1.2f + 1.2f * (float)(i % 3), z = -1.2f + 1.2f * (float)(i / 3), r = 0.2f;
        float q[12] = {x - r, 1, z - r, x - r, 1, z + r, x + r, 1, z + r, x + r, 1, z - r};
        char name[16];
        snprintf(name, sizeof name, "B%d", i);
        lie_scene_add_node(s, name, -1, NULL, lie_scene_add_mesh(s, name, q, NULL, NULL, 4, idx, 2, mb), -1, -1);
    }
    lie_error err;
    assert_int_equal(lie_scene_flatten(s, &err), LIE_OK);
    assert_int_equal(s->n_emitters, 1);
    return s;
}

static lie_build_params blockers_params(void)
{
    lie_build_params p = lie_build_params_default();
    p.min_patch = 1e-4f;
    p.max_blockers = 1;
    p.split_gain = 0.0f;
    return p;
}

static lie_edit *parse_edit(const char *text)
{
    lie_edit *e = NULL;
    lie_error err;
    assert_int_equal(lie_edit_parse((const unsigned char *)text, strlen(text), "e.yaml", &e, &err), LIE_OK);
    return e;
}

/* What rst-update recomputes for edits texts[n_pre, n) of a whole build of
 * the scene after texts[0, n_pre): the nodes, and the env after them. */
static uint64_t update_nodes(const char *const *texts, int n_pre, int n, lie_env **after)
{
    lie_error err;
    lie_scene *s = blockers_scene();
    for (int i = 0; i < n_pre; i++) {
        lie_edit *e = parse_edit(texts[i]);
        assert_int_equal(lie_edit_apply(s, e, NULL, NULL, &err), LIE_OK);
        lie_edit_destroy(e);
    }
    lie_rt *rt = NULL;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_build_params p = blockers_params();
    lie_cache *c = calloc(1, sizeof *c);
    assert_non_null(c);
    c->scene_path = strdup("blockers");
    c->scene_hash = s->hash;
    assert_int_equal(lie_cache_set_state(c, s, &err), LIE_OK);
    assert_int_equal(lie_env_build(s, rt, &p, NULL, &c->env, NULL, &err), LIE_OK);
    lie_edit *e[4];
    for (int i = n_pre; i < n; i++)
        e[i - n_pre] = parse_edit(texts[i]);
    lie_update_stats st;
    assert_int_equal(lie_update_apply(c, s, (const lie_edit *const *)e, n - n_pre, NULL, &st, &err), LIE_OK);
    for (int i = n_pre; i < n; i++)
        lie_edit_destroy(e[i - n_pre]);
    *after = c->env;
    c->env = NULL;
    lie_cache_destroy(c);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
    return st.nodes_recomputed;
}

/* The nodes of triangle t's units in env. */
static uint64_t tri_nodes(const lie_env *env, uint32_t t, uint32_t node)
{
    if (node == UINT32_MAX) {
        uint64_t n = 0;
        for (int k = 0; k < env->n_clusters; k++)
            n += tri_nodes(env, t, env->root[(size_t)t * (size_t)env->n_clusters + (size_t)k]);
        return n;
    }
    uint64_t n = 1;
    for (uint32_t k = 0; env->nodes[node].child && k < 4; k++)
        n += tri_nodes(env, t, env->nodes[node].child + k);
    return n;
}

/* After a drag the constructor recomputes the nodes of the units it sends
 * back that the moved geometry may reach, and copies the rest, as
 * rst-update does: the very nodes rst-update recomputes, far fewer than
 * the sent-back floor's trees hold; so too for two edits made while the
 * first one's units are still pending (held).  Each time the saved env is
 * the edited scene's build, byte for byte. */
static void test_a_drag_recomputes_the_nodes_it_reaches(void **state)
{
    (void)state;
    lie_error err;
    fixture f;
    memset(&f, 0, sizeof f);
    f.s = blockers_scene();
    assert_int_equal(lie_rt_create(f.s, &f.rt, &err), LIE_OK);
    f.co = lie_ctor_options_default();
    f.co.params = blockers_params();
    f.co.whole = 1;
    f.co.threads = 2;
    lie_ctor *c = NULL;
    assert_int_equal(lie_ctor_create(f.s, f.rt, &f.co, NULL, &c, &err), LIE_OK);
    assert_int_equal(lie_ctor_wait(c, -1.0, &err), 1);
    lie_ctor_stats st;
    lie_ctor_get_stats(c, &st);
    uint64_t nodes0 = st.nodes_built, units0 = st.units_built;
    static const char *const drags[3] = {"- move: {node: B0, by: [-0.1, 0, 0.05]}\n",
                                         "- move: {node: B8, by: [0.05, 0, 0.1]}\n"
                                         "- move: {node: B2, by: [0, 0, 0.1]}\n",
                                         "- move: {node: B0, by: [0.05, 0, -0.1]}\n"};
    ctor_edit(c, &f, drags[0]);
    assert_int_equal(lie_ctor_wait(c, -1.0, &err), 1);
    lie_ctor_get_stats(c, &st);
    lie_env *want = NULL, *got = saved(c, f.s);
    uint64_t rst_nodes = update_nodes(drags, 0, 1, &want);
    assert_true(same_env(got, want));
    assert_true(st.units_built > units0);
    assert_int_equal(st.nodes_built - nodes0, rst_nodes);
    /* the floor's units went back (the blocker shadows them), and most of
     * their nodes were copied */
    uint64_t floor_nodes = tri_nodes(want, 0, UINT32_MAX) + tri_nodes(want, 1, UINT32_MAX);
    assert_true(floor_nodes > 100);
    assert_true(4 * (st.nodes_built - nodes0) < floor_nodes);
    lie_env_destroy(got);
    lie_env_destroy(want);
    /* two more edits while the units of the first wait (held), one of
     * them moving two nodes: their nodes are those of both */
    nodes0 = st.nodes_built;
    lie_ctor_hold(c);
    ctor_edit(c, &f, drags[1]);
    ctor_edit(c, &f, drags[2]);
    lie_ctor_release(c);
    assert_int_equal(lie_ctor_wait(c, -1.0, &err), 1);
    lie_ctor_get_stats(c, &st);
    got = saved(c, f.s);
    rst_nodes = update_nodes(drags, 1, 3, &want);
    assert_true(same_env(got, want));
    assert_int_equal(st.nodes_built - nodes0, rst_nodes);
    lie_env_destroy(got);
    lie_env_destroy(want);
    lie_ctor_destroy(c);
    close_fixture(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_drag_recomputes_the_nodes_it_reaches),
        cmocka_unit_test(test_edits_send_back_units_not_triangles),
        cmocka_unit_test(test_two_views_end_in_one_build_for_both),
        cmocka_unit_test(test_held_and_manual_constructors),
        cmocka_unit_test(test_an_edit_during_construction_ends_in_the_edited_build),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
