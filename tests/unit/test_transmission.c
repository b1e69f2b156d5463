/* SPDX-License-Identifier: Apache-2.0 */
/* KHR_materials_transmission: the importer's factor and texture, the thin
 * surface's transmittance (lib/scene/texture.c), and lib/rt's queries:
 * transmissive triangles occlude nothing, are no shaft candidates, and
 * tint the segments that cross them (lie_rt_transmittance).  Fixtures:
 * tests/data/gltf/glass_box*.gltf (gen_fixtures.py): a point light at
 * (0, 0.6, 0) inside a 0.8 box of glass, base colour (1, 0.5, 0.25),
 * transmission 0.9, on a floor; mesh 1 (triangles 2..11) is the glass. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "rt/rt.h"
#include "scene/scene.h"

#define DATA "tests/data/gltf/"
#define assert_near(a, b, tol) assert_true(fabs((double)(a) - (double)(b)) <= (tol))

static lie_scene *load(const char *name)
{
    char path[256];
    snprintf(path, sizeof path, DATA "%s", name);
    lie_scene *s = NULL;
    lie_error err;
    lie_error_clear(&err);
    assert_int_equal(lie_scene_load(path, NULL, &s, &err), LIE_OK);
    return s;
}

static lie_rt *rt_of(const lie_scene *s)
{
    lie_rt *rt = NULL;
    lie_error err;
    lie_error_clear(&err);
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    return rt;
}

static void test_transmission_read_and_tinted_by_base_colour(void **state)
{
    (void)state;
    lie_scene *s = load("glass_box.gltf"), *o = load("glass_box_opaque.gltf");
    const lie_material *m = &s->materials[1];
    assert_near(m->transmission, 0.9, 1e-7);
    assert_true(lie_material_transmits(m));
    assert_false(lie_material_transmits(&s->materials[0]));
    assert_false(lie_material_transmits(&o->materials[1]));
    assert_true(s->hash != o->hash); /* transmission is part of the scene's content */
    float t[3];
    lie_scene_transmittance(s, 2, 0.2f, 0.3f, t);
    assert_near(t[0], 0.9, 1e-6);
    assert_near(t[1], 0.45, 1e-6);
    assert_near(t[2], 0.225, 1e-6);
    lie_scene_destroy(s);
    lie_scene_destroy(o);
}

/* From the light, through one wall, to the floor outside; and through the
 * whole box (two walls). */
static void test_glass_occludes_nothing_and_tints_what_crosses_it(void **state)
{
    (void)state;
    lie_scene *s = load("glass_box.gltf"), *o = load("glass_box_opaque.gltf");
    lie_rt *rt = rt_of(s), *rto = rt_of(o);
    lie_vec3 light = lie_v3(0.0f, 0.6f, 0.0f), floor = lie_v3(2.0f, 0.001f, 0.3f);
    lie_vec3 d = lie_v3_sub(floor, light);
    assert_true(lie_rt_transmits(rt));
    assert_false(lie_rt_transmits(rto));
    assert_false(lie_rt_occluded(rt, light, d, 0.0f, 0.999f));
    assert_true(lie_rt_occluded(rto, light, d, 0.0f, 0.999f));
    assert_false(lie_rt_any_hit(rt, light, d, 0.0f, 0.999f, NULL, 0));
    float t[3];
    assert_true(lie_rt_transmittance(rt, light, d, 0.0f, 0.999f, t));
    assert_near(t[0], 0.9, 1e-6);
    assert_near(t[1], 0.45, 1e-6);
    assert_near(t[2], 0.225, 1e-6);
    lie_vec3 a = lie_v3(-2.0f, 0.5f, 0.1f), b = lie_v3(2.0f, 0.5f, -0.1f);
    assert_true(lie_rt_transmittance(rt, a, lie_v3_sub(b, a), 0.0f, 1.0f, t));
    assert_near(t[1], 0.45 * 0.45, 1e-6);
    /* a segment that misses the glass keeps everything */
    lie_vec3 c = lie_v3(2.0f, 0.5f, 2.0f);
    assert_false(lie_rt_transmittance(rt, lie_v3(-2.0f, 0.5f, 2.0f), lie_v3_sub(c, lie_v3(-2.0f, 0.5f, 2.0f)), 0.0f,
                                      1.0f, t));
    assert_true(t[0] == 1.0f && t[1] == 1.0f && t[2] == 1.0f);
    /* camera rays still see the glass */
    lie_hit hit;
    assert_true(lie_rt_intersect(rt, lie_v3(0.0f, 0.4f, 3.0f), lie_v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY, 0, &hit));
    assert_true(lie_material_transmits(lie_scene_material(s, s->tri_material[hit.tri])));
    lie_rt_destroy(rt);
    lie_rt_destroy(rto);
    lie_scene_destroy(s);
    lie_scene_destroy(o);
}

static void collect(void *ctx, uint32_t tri)
{
    int *seen = ctx;
    seen[tri] = 1;
}

/* lie-build's shafts never take glass as a blocker candidate. */
static void test_glass_is_no_shaft_candidate(void **state)
{
    (void)state;
    lie_scene *s = load("glass_box.gltf");
    lie_rt *rt = rt_of(s);
    int seen[64] = {0};
    assert_true(s->n_tris <= 64);
    lie_box3 all = {lie_v3(-5, -1, -5), lie_v3(5, 5, 5)};
    lie_rt_box_query(rt, all, collect, seen);
    for (uint32_t t = 0; t < s->n_tris; t++)
        assert_int_equal(seen[t], !lie_material_transmits(lie_scene_material(s, s->tri_material[t])));
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_transmission_read_and_tinted_by_base_colour),
        cmocka_unit_test(test_glass_occludes_nothing_and_tints_what_crosses_it),
        cmocka_unit_test(test_glass_is_no_shaft_candidate),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
