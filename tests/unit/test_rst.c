/* SPDX-License-Identifier: Apache-2.0 */
/* lib/rst: the ray segment trees (§5.1–5.3) against brute force.  On a
 * scene of random boxes under two lights, for random query boxes: a query
 * never misses a unit root whose exact region (the hull of patch and
 * emitter, lib/lie/pair.h) meets the box, flags only roots that can
 * interact, and refine then gives exactly the nodes a brute-force walk of
 * every patch tree finds; spread flags whole subtrees; the trees answer
 * the same for any thread count. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "lie/shaft.h"

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static float rnd(float lo, float hi)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return lo + (hi - lo) * (float)((rng_state >> 40) & 0xFFFFFF) / (float)0x1000000;
}

static void add_quad(lie_scene *s, const char *name, const float p[12], int mat)
{
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    lie_scene_add_node(s, name, -1, NULL, lie_scene_add_mesh(s, name, p, NULL, NULL, 4, idx, 2, mat), -1, -1);
}

/* An axis-aligned box of 12 triangles, centre c, half sizes h. */
static void add_box(lie_scene *s, const char *name, const float c[3], const float h[3], int mat)
{
    float p[24];
    for (int k = 0; k < 8; k++) {
        p[3 * k + 0] = c[0] + (k & 1 ? h[0] : -h[0]);
        p[3 * k + 1] = c[1] + (k & 2 ? h[1] : -h[1]);
        p[3 * k + 2] = c[2] + (k & 4 ? h[2] : -h[2]);
    }
    uint32_t idx[36] = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                        2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
    lie_scene_add_node(s, name, -1, NULL, lie_scene_add_mesh(s, name, p, NULL, NULL, 8, idx, 12, mat), -1, -1);
}

/* A floor, n random boxes and two area lights (one tilted). */
static lie_scene *random_scene(int n)
{
    lie_scene *s = lie_scene_new("random-boxes");
    int mw = test_material(s, 1.0f, 0.0f, 0);
    int ml = test_material(s, 1.0f, 5.0f, 0);
    float fl[12] = {-3, 0, -3, -3, 0, 3, 3, 0, 3, 3, 0, -3};
    add_quad(s, "Floor", fl, mw);
    for (int i = 0; i < n; i++) {
        char name[16];
        snprintf(name, sizeof name, "Box%d", i);
        float c[3] = {rnd(-2.5f, 2.5f), rnd(0.2f, 2.0f), rnd(-2.5f, 2.5f)};
        float h[3] = {rnd(0.05f, 0.4f), rnd(0.05f, 0.4f), rnd(0.05f, 0.4f)};
        add_box(s, name, c, h, mw);
    }
    float l1[12] = {-0.5f, 3, -0.5f, 0.5f, 3, -0.5f, 0.5f, 3, 0.5f, -0.5f, 3, 0.5f};
    float l2[12] = {2.8f, 1.0f, -0.4f, 2.8f, 1.0f, 0.4f, 2.6f, 1.6f, 0.4f, 2.6f, 1.6f, -0.4f};
    add_quad(s, "Light1", l1, ml);
    add_quad(s, "Light2", l2, ml);
    lie_error err;
    assert_int_equal(lie_scene_flatten(s, &err), LIE_OK);
    assert_int_equal(s->n_emitters, 2);
    return s;
}

typedef struct fixture {
    lie_scene *s;
    lie_rt *rt;
    lie_env *env;
    lie_rst *rst;
    lie_vec3 *hull;
    float tol;
} fixture;

static int setup(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    lie_error err;
    f->s = random_scene(12);
    assert_int_equal(lie_rt_create(f->s, &f->rt, &err), LIE_OK);
    lie_build_params p = lie_build_params_default();
    p.min_patch = 1e-2f;
    p.samples = 32;
    p.max_samples = 64;
    p.max_blockers = 2;
    p.whole_pixels = 0; /* every unit built, as fine as its lists need: trees to walk */
    lie_build_stats st;
    assert_int_equal(lie_env_build(f->s, f->rt, &p, NULL, &f->env, &st, &err), LIE_OK);
    lie_rst_stats rs;
    assert_int_equal(lie_rst_build(f->s, f->env, 2, &f->rst, &rs, &err), LIE_OK);
    assert_true(rs.regions > 0);
    /* patch trees below the roots, for refine to walk */
    assert_true(st.splits_kept > (uint64_t)f->env->n_tris * (uint64_t)f->env->n_clusters / 4);
    int cap = 0;
    for (int e = 0; e < f->s->n_emitters; e++)
        cap = cap > lie_pair_hull_cap(f->s, e) ? cap : lie_pair_hull_cap(f->s, e);
    f->hull = malloc(sizeof *f->hull * ((size_t)cap + 1));
    /* refine's tolerance (lib/rst/refine.c) */
    f->tol = 1e-5f * fmaxf(1.0f, lie_v3_len(lie_v3_sub(f->s->bounds.hi, f->s->bounds.lo)));
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    free(f->hull);
    lie_rst_destroy(f->rst);
    lie_env_destroy(f->env);
    lie_rt_destroy(f->rt);
    lie_scene_destroy(f->s);
    free(f);
    return 0;
}

static lie_box3 random_box(void)
{
    lie_vec3 c = lie_v3(rnd(-3.0f, 3.0f), rnd(0.0f, 3.0f), rnd(-3.0f, 3.0f));
    lie_vec3 h = lie_v3(rnd(0.01f, 0.5f), rnd(0.01f, 0.5f), rnd(0.01f, 0.5f));
    lie_box3 b = {lie_v3_sub(c, h), lie_v3_add(c, h)};
    return b;
}

/* Brute force: does the exact region of (tri, path, e) meet box b? */
static int hull_meets(fixture *f, uint32_t tri, lie_patch_path path, int e, const lie_box3 *b)
{
    lie_vec3 V[3];
    lie_patch_world(path, &f->s->tri_p[3 * (size_t)tri], V);
    int n = lie_pair_hull_points(f->s, tri, V, e, f->hull);
    lie_vec3 corners[8];
    for (int k = 0; k < 8; k++)
        corners[k] = lie_v3(k & 1 ? b->hi.x : b->lo.x, k & 2 ? b->hi.y : b->lo.y, k & 4 ? b->hi.z : b->lo.z);
    return lie_hull_meets_hull(f->hull, n, corners, 8, f->tol);
}

/* Every node whose region meets b, and whose ancestors' regions do. */
static void brute_walk(fixture *f, uint32_t node, uint32_t tri, lie_patch_path path, int e, const lie_box3 *b,
                       uint8_t *out)
{
    if (!hull_meets(f, tri, path, e, b))
        return;
    out[node] = 1;
    const lie_pnode *x = &f->env->nodes[node];
    for (uint32_t k = 0; x->child && k < 4; k++)
        brute_walk(f, x->child + k, tri, lie_patch_child(path, (int)k), e, b, out);
}

static void test_rst_query_never_misses_a_root_whose_hull_meets_the_box(void **state)
{
    fixture *f = *state;
    const lie_env *env = f->env;
    uint8_t *flags = malloc(env->n_nodes + 1), *is_root = calloc(env->n_nodes + 1, 1);
    size_t n_units = (size_t)env->n_tris * (size_t)env->n_clusters;
    for (size_t u = 0; u < n_units; u++)
        is_root[env->root[u]] = 1;
    uint64_t exact = 0, flagged = 0;
    for (int q = 0; q < 60; q++) {
        lie_box3 b = random_box();
        memset(flags, 0, env->n_nodes);
        lie_rst_query(f->rst, b, flags);
        for (uint32_t t = 0; t < env->n_tris; t++)
            for (int e = 0; e < env->n_clusters; e++) {
                uint32_t r = env->root[(size_t)t * (size_t)env->n_clusters + (size_t)e];
                int cls = (int)env->nodes[r].cls;
                int meets = hull_meets(f, t, lie_patch_root(), e, &b);
                exact += meets && cls != LIE_CLASS_UNLIT;
                flagged += flags[r];
                if (cls == LIE_CLASS_UNLIT || cls == LIE_CLASS_NONE)
                    assert_false(flags[r]); /* never inserted: nothing can change them */
                else if (meets)
                    assert_true(flags[r]);
            }
        for (uint32_t i = 0; i < env->n_nodes; i++)
            if (flags[i])
                assert_true(is_root[i]); /* the trees hold roots only */
    }
    /* conservative, and not everything */
    assert_true(exact > 0);
    assert_true(flagged >= exact);
    assert_true(flagged < 60 * (uint64_t)n_units);
    free(flags);
    free(is_root);
}

static void test_rst_refine_equals_brute_force_walk_of_every_patch_tree(void **state)
{
    fixture *f = *state;
    const lie_env *env = f->env;
    uint8_t *flags = malloc(env->n_nodes + 1), *brute = malloc(env->n_nodes + 1);
    uint64_t total = 0;
    for (int q = 0; q < 40; q++) {
        lie_box3 b = random_box();
        memset(flags, 0, env->n_nodes);
        memset(brute, 0, env->n_nodes);
        lie_rst_query(f->rst, b, flags);
        lie_rst_refine(f->s, env, &b, 1, flags, 1 + q % 3); /* 1, 2, 3 workers: the same flags */
        for (uint32_t t = 0; t < env->n_tris; t++)
            for (int e = 0; e < env->n_clusters; e++) {
                uint32_t r = env->root[(size_t)t * (size_t)env->n_clusters + (size_t)e];
                if (env->nodes[r].cls != LIE_CLASS_UNLIT)
                    brute_walk(f, r, t, lie_patch_root(), e, &b, brute);
            }
        assert_memory_equal(flags, brute, env->n_nodes);
        for (uint32_t i = 0; i < env->n_nodes; i++)
            total += brute[i];
    }
    assert_true(total > 0); /* the boxes did meet something */
    free(flags);
    free(brute);
}

static void test_rst_query_of_a_box_outside_the_scene_flags_nothing(void **state)
{
    fixture *f = *state;
    uint8_t *flags = calloc(f->env->n_nodes + 1, 1);
    lie_box3 far = {lie_v3(50, 50, 50), lie_v3(51, 51, 51)};
    lie_rst_query(f->rst, far, flags);
    for (uint32_t i = 0; i < f->env->n_nodes; i++)
        assert_int_equal(flags[i], 0);
    free(flags);
}

static uint32_t tree_nodes(const lie_env *env, uint32_t r)
{
    uint32_t n = 1;
    for (uint32_t k = 0; env->nodes[r].child && k < 4; k++)
        n += tree_nodes(env, env->nodes[r].child + k);
    return n;
}

static void test_rst_spread_flags_whole_subtrees(void **state)
{
    fixture *f = *state;
    const lie_env *env = f->env;
    uint8_t *flags = calloc(env->n_nodes + 1, 1);
    size_t n_units = (size_t)env->n_tris * (size_t)env->n_clusters, trees = 0;
    for (size_t u = 0; u < n_units; u += 3)
        if (!lie_pnode_lone(&env->nodes[env->root[u]])) /* lone leaves are shared by many units */
            flags[env->root[u]] = 1;
    lie_rst_spread(env, flags);
    for (size_t u = 0; u < n_units; u++) {
        if (lie_pnode_lone(&env->nodes[env->root[u]]))
            continue;
        /* a unit's nodes lie contiguously from its root (lib/lie's assembly) */
        uint32_t end = env->root[u] + tree_nodes(env, env->root[u]);
        for (uint32_t i = env->root[u]; i < end; i++)
            assert_int_equal(flags[i], u % 3 == 0);
        trees += env->nodes[env->root[u]].child != 0 && u % 3 == 0;
    }
    assert_true(trees > 0);
    free(flags);
}

static void test_rst_answers_are_the_same_for_any_thread_count(void **state)
{
    fixture *f = *state;
    lie_error err;
    lie_rst *one = NULL;
    assert_int_equal(lie_rst_build(f->s, f->env, 1, &one, NULL, &err), LIE_OK);
    uint8_t *a = malloc(f->env->n_nodes + 1), *b = malloc(f->env->n_nodes + 1);
    for (int q = 0; q < 20; q++) {
        lie_box3 box = random_box();
        memset(a, 0, f->env->n_nodes);
        memset(b, 0, f->env->n_nodes);
        uint64_t ta = lie_rst_query(one, box, a), tb = lie_rst_query(f->rst, box, b);
        assert_int_equal(ta, tb);
        assert_memory_equal(a, b, f->env->n_nodes);
    }
    free(a);
    free(b);
    lie_rst_destroy(one);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rst_query_never_misses_a_root_whose_hull_meets_the_box),
        cmocka_unit_test(test_rst_refine_equals_brute_force_walk_of_every_patch_tree),
        cmocka_unit_test(test_rst_query_of_a_box_outside_the_scene_flags_nothing),
        cmocka_unit_test(test_rst_spread_flags_whole_subtrees),
        cmocka_unit_test(test_rst_answers_are_the_same_for_any_thread_count),
    };
    return cmocka_run_group_tests_name("rst", tests, setup, teardown);
}
