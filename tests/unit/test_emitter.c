/* SPDX-License-Identifier: Apache-2.0 */
/* The emitter interface (lib/scene/scene.h): each type's sampling,
 * radiance, closed-form light, polygon and power, against the values the
 * glTF and the geometry give by hand. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "fixtures.h"

#define assert_near(a, b, tol) assert_true(fabs((double)(a) - (double)(b)) <= (tol))

static int find(const lie_scene *s, lie_emitter_type t, int spot)
{
    for (int e = 0; e < s->n_emitters; e++)
        if (s->emitters[e].type == t && (t != LIE_EMITTER_POINT || (s->emitters[e].cos_outer > -1.5f) == spot))
            return e;
    fail();
    return -1;
}

static void test_emitter_area_samples_lie_on_the_light_with_its_radiance(void **state)
{
    (void)state;
    lie_scene *s = occluder_scene();
    const lie_emitter *em = &s->emitters[0];
    assert_string_equal(lie_emitter_type_name(em->type), "area");
    assert_false(lie_emitter_is_delta(em));
    assert_int_equal(lie_emitter_sample_count(em, 37), 37);
    assert_true(lie_emitter_uniform(s, 0));
    assert_near(lie_emitter_pdf(s, 0), 1.0, 1e-6); /* a 1 x 1 light */
    for (int i = 0; i < 16; i++) {
        lie_emitter_sample q;
        lie_emitter_sample_point(s, 0, ((float)i + 0.5f) / 16.0f, (float)((i * 7) % 16) / 16.0f, &q);
        assert_near(q.p.y, 2.0, 1e-6);
        assert_true(fabsf(q.p.x) <= 0.5f && fabsf(q.p.z) <= 0.5f);
        assert_near(q.n.y, -1.0, 1e-6);
        assert_near(q.le[0], 5.0, 0);
        assert_near(q.inv_pdf, 1.0, 1e-6);
        assert_true(lie_emitter_owns(em, q.tri));
    }
    lie_emitter_incident li;
    assert_int_equal(lie_emitter_light_at(s, 0, lie_v3(0, 0, 0), 100.0f, &li), 0); /* sampled, not closed */
    lie_emitter_polygon pg;
    assert_int_equal(lie_emitter_polygon_of(s, 0, &pg), 1);
    assert_int_equal(pg.n_tris, 2);
    assert_near(pg.n.y, -1.0, 1e-6);
    assert_near(pg.radiance[2], 5.0, 0);
    float phi[3];
    lie_emitter_power(s, 0, phi); /* pi Le A, one-sided */
    assert_near(phi[1], M_PI * 5.0, 1e-4);
    const lie_vec3 *pts;
    int np = lie_emitter_extent(s, 0, &pts);
    assert_int_equal(np, 6); /* two triangles: their vertices */
    float sp[4];
    lie_emitter_bounding_sphere(s, 0, sp);
    for (int k = 0; k < np; k++)
        assert_true(lie_v3_len(lie_v3_sub(pts[k], lie_v3(sp[0], sp[1], sp[2]))) <= sp[3]);
    assert_false(lie_emitter_owns(em, 0)); /* the floor */
    lie_scene_destroy(s);
}

static void test_emitter_punctual_lights_give_the_khr_falloff_in_closed_form(void **state)
{
    (void)state;
    lie_scene *s = NULL;
    lie_error err;
    assert_int_equal(lie_scene_load("tests/data/gltf/lights_cameras.gltf", NULL, &s, &err), LIE_OK);
    int pt = find(s, LIE_EMITTER_POINT, 0), spot = find(s, LIE_EMITTER_POINT, 1),
        dir = find(s, LIE_EMITTER_DIRECTIONAL, 0);
    /* the point light: (10, 5, 2.5) cd at (0, 2, 0), range 5 */
    const lie_emitter *em = &s->emitters[pt];
    assert_true(lie_emitter_is_delta(em));
    assert_int_equal(lie_emitter_sample_count(em, 37), 1);
    assert_near(lie_emitter_pdf(s, pt), 0.0, 0);
    lie_emitter_incident li;
    assert_int_equal(lie_emitter_light_at(s, pt, lie_v3(0, -1, 0), 1e3f, &li), 1);
    double d = 3.0, window = 1.0 - pow(d / 5.0, 4);
    assert_near(li.dist, d, 1e-6);
    assert_near(li.wi.y, 1.0, 1e-6);
    assert_near(li.li[0], 10.0 / (d * d) * window, 1e-5);
    assert_near(li.li[2], 2.5 / (d * d) * window, 1e-5);
    assert_int_equal(lie_emitter_light_at(s, pt, lie_v3(0, -4, 0), 1e3f, &li), 1);
    assert_near(li.li[0], 0.0, 0); /* past the range */
    float phi[3];
    lie_emitter_power(s, pt, phi);
    assert_near(phi[0], 4.0 * M_PI * 10.0, 1e-3);
    lie_emitter_polygon pg;
    assert_int_equal(lie_emitter_polygon_of(s, pt, &pg), 0);
    assert_false(lie_emitter_uniform(s, pt));
    /* the spot at the origin, down -z, outer cone pi/4, inner 0: full on
     * its axis, none outside the outer cone */
    assert_int_equal(lie_emitter_light_at(s, spot, lie_v3(0, 0, -2), 1e3f, &li), 1);
    assert_near(li.li[1], 1.0 / 4.0, 1e-6);
    assert_int_equal(lie_emitter_light_at(s, spot, lie_v3(2, 0, -1), 1e3f, &li), 1);
    assert_near(li.li[1], 0.0, 0);
    lie_emitter_power(s, spot, phi);
    assert_near(phi[0], 2.0 * M_PI * (1.0 - 0.5 * (1.0 + cos(M_PI / 4))), 1e-5);
    float sp[4];
    lie_emitter_bounding_sphere(s, spot, sp);
    assert_near(sp[3], 0.0, 0);
    /* the directional light: 3 lux towards -z */
    assert_int_equal(lie_emitter_light_at(s, dir, lie_v3(1, 2, 3), 50.0f, &li), 1);
    assert_near(li.wi.z, 1.0, 1e-6);
    assert_near(li.dist, 50.0, 0);
    assert_near(li.li[0], 3.0, 0);
    lie_emitter_sample q;
    lie_emitter_sample_point(s, dir, 0.3f, 0.6f, &q);
    assert_near(q.p.z, 1.0, 1e-6); /* the direction towards it */
    assert_near(q.le[2], 3.0, 0);
    const lie_vec3 *pts;
    assert_int_equal(lie_emitter_extent(s, dir, &pts), 0);
    lie_emitter_bounding_sphere(s, dir, sp);
    assert_true(sp[3] < 0.0f);
    assert_int_equal(lie_emitter_extent(s, pt, &pts), 1);
    assert_near(pts[0].y, 2.0, 0);
    lie_emitter_power(s, dir, phi);
    assert_true(phi[0] > 0.0f);
    assert_string_equal(lie_emitter_type_name(LIE_EMITTER_DIRECTIONAL), "directional");
    lie_scene_destroy(s);
}

/* The light samples lib/shade draws go through the interface: an area
 * emitter's weights sum to Le A, a delta light gives one sample. */
static void test_emitter_light_samples_weights_sum_to_power_over_pi(void **state)
{
    (void)state;
    lie_scene *s = occluder_scene();
    lie_light_samples ls;
    assert_int_equal(lie_light_samples_alloc(&ls, 64), LIE_OK);
    lie_light_samples_generate(s, 0, 64, 0.25f, 0.5f, &ls);
    double sum = 0.0;
    for (int i = 0; i < ls.n; i++)
        sum += ls.r[i];
    float phi[3];
    lie_emitter_power(s, 0, phi);
    assert_near(sum, phi[0] / M_PI, 1e-4);
    assert_true(ls.uniform);
    assert_true(ls.planar);
    lie_light_samples_free(&ls);
    lie_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_emitter_area_samples_lie_on_the_light_with_its_radiance),
        cmocka_unit_test(test_emitter_punctual_lights_give_the_khr_falloff_in_closed_form),
        cmocka_unit_test(test_emitter_light_samples_weights_sum_to_power_over_pi),
    };
    return cmocka_run_group_tests_name("emitter", tests, NULL, NULL);
}
