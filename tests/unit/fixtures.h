/* SPDX-License-Identifier: Apache-2.0 */
/* Scenes built in memory that several unit test files share. */
#ifndef LIE_TEST_FIXTURES_H
#define LIE_TEST_FIXTURES_H

#include <stdlib.h>

#include "lie.h"

#include <stdio.h>

/* A bundled scene (tests/scenes/NAME), loaded, or the test fails. */
static inline lie_scene *test_scene(const char *name)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", TEST_SCENES, name);
    lie_scene *s = NULL;
    lie_error err;
    assert_int_equal(lie_scene_load(path, NULL, &s, &err), LIE_OK);
    return s;
}

/* A material of grey base colour `base` (metallic 0: Lambert when rough)
 * emitting radiance `emit` (0: none), one- or two-sided; its index. */
static inline int test_material(lie_scene *s, float base, float emit, int double_sided)
{
    lie_material m = lie_material_default();
    m.metallic = 0.0f;
    m.base_color[0] = m.base_color[1] = m.base_color[2] = base;
    m.emissive[0] = m.emissive[1] = m.emissive[2] = emit;
    m.double_sided = double_sided;
    return lie_scene_add_material(s, &m);
}

/* The default build parameters with the smallest patch at min_patch. */
static inline lie_build_params test_params(float min_patch)
{
    lie_build_params p = lie_build_params_default();
    p.min_patch = min_patch;
    return p;
}

/* The default render options for a w x h image, light_samples shadow rays
 * and `threads` threads (0: all cores). */
static inline lie_render_options test_render_options(int w, int h, int light_samples, int threads)
{
    lie_render_options o = lie_render_options_default();
    o.width = w;
    o.height = h;
    o.light_samples = light_samples;
    o.threads = threads;
    return o;
}

/* What a test of the LIE oracle needs over a scene: its ray tracer, its
 * environments built at min_patch, and the oracle over them. */
typedef struct test_oracle {
    lie_rt *rt;
    lie_env *env;
    lie_env_shadows *lv;
    const lie_vis_oracle *orc;
} test_oracle;

static inline void test_oracle_make(const lie_scene *s, float min_patch, test_oracle *t)
{
    lie_error err;
    t->rt = NULL;
    t->env = NULL;
    t->lv = NULL;
    assert_int_equal(lie_rt_create(s, &t->rt, &err), LIE_OK);
    lie_build_params bp = test_params(min_patch);
    lie_build_stats bst;
    assert_int_equal(lie_env_build(s, t->rt, &bp, NULL, &t->env, &bst, &err), LIE_OK);
    assert_int_equal(lie_env_shadows_create(s, t->env, &t->lv, &err), LIE_OK);
    t->orc = lie_env_shadows_oracle(t->lv);
}

static inline void test_oracle_free(test_oracle *t)
{
    lie_env_shadows_destroy(t->lv);
    lie_env_destroy(t->env);
    lie_rt_destroy(t->rt);
}

/* Form factor from a point to a parallel rectangle a x b whose corner is
 * straight above it at height h (Howell's catalogue, configuration B-3). */
static inline double ff_corner(double a, double b, double h)
{
    double X = a / h, Y = b / h;
    double sx = sqrt(1.0 + X * X), sy = sqrt(1.0 + Y * Y);
    return (X / sx * atan(Y / sx) + Y / sy * atan(X / sy)) / (2.0 * M_PI);
}

/* floor 4x4 at y=0 (2 triangles, tris 0-1), an occluder quad 0.6x0.6 at
 * y=1 (tris 2-3, double-sided), a 1x1 light at y=2 facing down (tris 4-5). */
static inline lie_scene *occluder_scene(void)
{
    lie_scene *s = lie_scene_new("occluder");
    lie_material white = lie_material_default();
    white.metallic = 0.0f;
    int mw = lie_scene_add_material(s, &white);
    lie_material occ = white;
    occ.double_sided = 1;
    int mo = lie_scene_add_material(s, &occ);
    lie_material light = white;
    light.base_color[0] = light.base_color[1] = light.base_color[2] = 0.0f;
    light.emissive[0] = light.emissive[1] = light.emissive[2] = 5.0f;
    int ml = lie_scene_add_material(s, &light);
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    float fl[12] = {-2, 0, -2, -2, 0, 2, 2, 0, 2, 2, 0, -2};
    float oc[12] = {-0.3f, 1, -0.3f, -0.3f, 1, 0.3f, 0.3f, 1, 0.3f, 0.3f, 1, -0.3f};
    float li[12] = {-0.5f, 2, -0.5f, 0.5f, 2, -0.5f, 0.5f, 2, 0.5f, -0.5f, 2, 0.5f};
    lie_scene_add_node(s, "Floor", -1, NULL, lie_scene_add_mesh(s, "Floor", fl, NULL, NULL, 4, idx, 2, mw), -1, -1);
    lie_scene_add_node(s, "Occluder", -1, NULL, lie_scene_add_mesh(s, "Occ", oc, NULL, NULL, 4, idx, 2, mo), -1, -1);
    lie_scene_add_node(s, "Light", -1, NULL, lie_scene_add_mesh(s, "Light", li, NULL, NULL, 4, idx, 2, ml), -1, -1);
    lie_error err;
    assert_int_equal(lie_scene_flatten(s, &err), LIE_OK);
    assert_int_equal(s->n_tris, 6);
    assert_int_equal(s->n_emitters, 1);
    return s;
}

/* Two environments are the same bytes: counts, roots, nodes, lists. */
static inline void assert_env_equal(const lie_env *a, const lie_env *b)
{
    assert_int_equal(a->n_clusters, b->n_clusters);
    assert_int_equal(a->n_nodes, b->n_nodes);
    assert_int_equal(a->n_pool, b->n_pool);
    assert_memory_equal(a->root, b->root, sizeof(uint32_t) * a->n_tris * (size_t)a->n_clusters);
    assert_memory_equal(a->nodes, b->nodes, sizeof(lie_pnode) * a->n_nodes);
    if (a->n_pool)
        assert_memory_equal(a->pool, b->pool, sizeof(uint32_t) * a->n_pool);
}

/* Two textures hold the same texels (as floats: codes or floats alike). */
static inline void assert_texels_equal(const lie_texture *a, const lie_texture *b)
{
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    for (size_t i = 0; i < (size_t)a->width * (size_t)a->height; i++) {
        float x[4], y[4];
        lie_texture_texel(a, i, x);
        lie_texture_texel(b, i, y);
        assert_memory_equal(x, y, sizeof x);
    }
}

/* A square emitter of side a centred at (0, h, 0), facing down (or both
 * ways), then the blocker triangles tris[0..n) (9 floats each). */
static inline lie_scene *square_light_and_blockers(float a, float h, int two_sided, const float *tris, int n)
{
    lie_scene *s = lie_scene_new("polylight");
    assert_non_null(s);
    int ml = test_material(s, 0.0f, 1.0f, two_sided);
    int mg = test_material(s, 1.0f, 0.0f, 0);
    float r = 0.5f * a;
    float lp[12] = {-r, h, -r, r, h, -r, r, h, r, -r, h, r};
    uint32_t li[6] = {0, 1, 2, 0, 2, 3};
    int mesh_l = lie_scene_add_mesh(s, "Light", lp, NULL, NULL, 4, li, 2, ml);
    assert_true(lie_scene_add_node(s, "Light", -1, NULL, mesh_l, -1, -1) >= 0);
    if (n > 0) {
        uint32_t *idx = malloc(sizeof *idx * 3 * (size_t)n);
        assert_non_null(idx);
        for (int i = 0; i < 3 * n; i++)
            idx[i] = (uint32_t)i;
        int mesh_b = lie_scene_add_mesh(s, "Blockers", tris, NULL, NULL, 3 * n, idx, n, mg);
        free(idx);
        assert_true(lie_scene_add_node(s, "Blockers", -1, NULL, mesh_b, -1, -1) >= 0);
    }
    lie_error err;
    assert_int_equal(lie_scene_flatten(s, &err), LIE_OK);
    assert_int_equal(s->n_emitters, 1);
    assert_true(s->emitters[0].planar);
    return s;
}

/* Segment o -> p (stopping eps short) against triangle T, in double: the
 * quadratures of test_polylight and test_polyshape. */
static inline int test_segment_hits(const double o[3], const double p[3], double eps, const lie_vec3 *T)
{
    double d[3] = {p[0] - o[0], p[1] - o[1], p[2] - o[2]};
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    double tmax = 1.0 - eps / len;
    double a[3] = {T[0].x, T[0].y, T[0].z}, e1[3] = {T[1].x - a[0], T[1].y - a[1], T[1].z - a[2]},
           e2[3] = {T[2].x - a[0], T[2].y - a[1], T[2].z - a[2]};
    double pv[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
    double det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
    if (fabs(det) < 1e-300)
        return 0;
    double tv[3] = {o[0] - a[0], o[1] - a[1], o[2] - a[2]};
    double u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) / det;
    if (u < 0.0 || u > 1.0)
        return 0;
    double qv[3] = {tv[1] * e1[2] - tv[2] * e1[1], tv[2] * e1[0] - tv[0] * e1[2], tv[0] * e1[1] - tv[1] * e1[0]};
    double v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) / det;
    if (v < 0.0 || u + v > 1.0)
        return 0;
    double t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) / det;
    return t > 0.0 && t < tmax;
}

#ifdef LIE_SHADE_BITMASK_H
/* The LIE oracle over scene s (built with patches of 0.5: lists that
 * hold every blocker), and emitter 0's fixed pattern of n samples as a
 * bitmask, for tests that ask the oracle directly (test_bitmask).
 * oracle_fixture_free destroys the scene too. */
typedef struct oracle_fixture {
    lie_scene *s;
    test_oracle t;
    const lie_vis_oracle *orc;
    lie_rt *rt;
    lie_light_samples ls;
    lie_bitmask *bm;
} oracle_fixture;

static inline void oracle_fixture_init(oracle_fixture *f, lie_scene *s, int n)
{
    f->s = s;
    test_oracle_make(s, 0.5f, &f->t);
    f->orc = f->t.orc;
    f->rt = f->t.rt;
    assert_non_null(f->orc->occluded_mask);
    assert_int_equal(lie_light_samples_alloc(&f->ls, n), LIE_OK);
    lie_light_samples_generate(s, 0, n, 0.37f, 0.71f, &f->ls);
    f->bm = NULL;
    assert_int_equal(lie_bitmask_create(&f->ls, &f->bm), LIE_OK);
    assert_non_null(f->bm);
}

static inline void oracle_fixture_free(oracle_fixture *f)
{
    lie_bitmask_destroy(f->bm);
    lie_light_samples_free(&f->ls);
    test_oracle_free(&f->t);
    lie_scene_destroy(f->s);
}
#endif

#endif
