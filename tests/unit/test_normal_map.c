/* SPDX-License-Identifier: Apache-2.0 */
/* Normal maps: the importer's normalTexture and TANGENT (lib/scene/gltf_*.cpp),
 * tangents made from texture coordinates (lib/scene/tangent.c), their world
 * form (lie_scene_flatten) and the bent shading normal (lib/shade/surface.c).
 * Fixtures: tests/data/gltf/normal_map*.gltf (gen_fixtures.py). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "edit/edit.h"
#include "scene/scene.h"
#include "shade/shade.h"

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

/* The floor is triangles 0 and 1 (u along +x, v along +z, normal +y). */
static void test_normal_map_read_with_scale_and_world_tangents(void **state)
{
    (void)state;
    lie_scene *s = load("normal_map.gltf");
    const lie_material *m = &s->materials[0];
    assert_true(m->normal_tex >= 0);
    assert_near(m->normal_scale, 0.9, 1e-7);
    assert_int_equal(m->tex_set[LIE_TEX_NORMAL], 0);
    assert_true(s->materials[1].normal_tex < 0);
    assert_non_null(s->tri_tan);
    /* glTF's v grows down the image: u along +x and v along +z make the
     * frame (+x, cross(+y, +x) = -z = -dP/dv, +y), right-handed, w = +1 */
    for (int k = 0; k < 6; k++) {
        const float *t = &s->tri_tan[4 * k];
        assert_near(t[0], 1.0, 1e-6);
        assert_near(t[1], 0.0, 1e-6);
        assert_near(t[2], 0.0, 1e-6);
        assert_true(t[3] == 1.0f);
    }
    /* the box has no normal map: its corners carry no tangent */
    for (size_t k = 6 * 4; k < 12 * (size_t)s->n_tris; k++)
        assert_true(s->tri_tan[k] == 0.0f);
    lie_scene_destroy(s);
}

/* TANGENT given equals the tangents made where it is missing, bit for bit
 * here; and a scene without a normal map has no tangents at all. */
static void test_normal_map_tangents_made_match_given(void **state)
{
    (void)state;
    lie_scene *a = load("normal_map.gltf"), *b = load("normal_map_tangent.gltf"), *c = load("normal_map_none.gltf");
    assert_null(a->meshes[0].prims[0].tan);
    assert_non_null(b->meshes[0].prims[0].tan);
    assert_int_equal(a->n_tris, b->n_tris);
    assert_memory_equal(a->tri_tan, b->tri_tan, sizeof(float) * 12 * a->n_tris);
    assert_null(c->tri_tan);
    assert_true(a->hash != c->hash);
    lie_scene_destroy(a);
    lie_scene_destroy(b);
    lie_scene_destroy(c);
}

/* A mirrored UV island (u decreasing along +x) gives the tangent -x and the
 * opposite handedness; a primitive without texture coordinates still gets
 * a unit tangent orthogonal to its normal. */
static void test_tangents_follow_texture_space_handedness(void **state)
{
    (void)state;
    float pos[12] = {-1, 0, -1, -1, 0, 1, 1, 0, 1, 1, 0, -1};
    float nrm[12] = {0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0};
    float uv[8] = {1, 0, 1, 1, 0, 1, 0, 0}; /* u reversed */
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    lie_primitive p;
    memset(&p, 0, sizeof p);
    p.n_verts = 4;
    p.n_tris = 2;
    p.pos = pos;
    p.nrm = nrm;
    p.uv = uv;
    p.idx = idx;
    float t[16];
    assert_true(lie_primitive_tangents(&p, 0, t));
    for (int v = 0; v < 4; v++) {
        assert_near(t[4 * v], -1.0, 1e-6);
        assert_near(t[4 * v + 2], 0.0, 1e-6);
        assert_true(t[4 * v + 3] == -1.0f);
    }
    p.uv = NULL;
    assert_true(lie_primitive_tangents(&p, 0, t));
    for (int v = 0; v < 4; v++) {
        lie_vec3 tv = lie_v3(t[4 * v], t[4 * v + 1], t[4 * v + 2]);
        assert_near(lie_v3_len(tv), 1.0, 1e-6);
        assert_near(tv.y, 0.0, 1e-6);
    }
}

static lie_surface floor_point(const lie_scene *s, float u, float v)
{
    lie_hit hit = {0};
    hit.tri = 0;
    hit.u = u;
    hit.v = v;
    hit.t = 1.0f;
    lie_surface sf;
    lie_surface_from_hit(s, &hit, lie_v3_norm(lie_v3(0.0f, -1.0f, -1.0f)), &sf);
    return sf;
}

/* The map bends the shading normal (by the texel's X toward the tangent),
 * leaves the geometric normal alone, and never below the geometric
 * horizon, however large the scale. */
static void test_normal_map_bends_shading_normal_above_horizon(void **state)
{
    (void)state;
    lie_scene *s = load("normal_map.gltf"), *flat = load("normal_map_none.gltf");
    lie_surface a = floor_point(s, 0.3f, 0.3f), b = floor_point(flat, 0.3f, 0.3f);
    assert_true(b.n.x == 0.0f && b.n.y == 1.0f && b.n.z == 0.0f);
    assert_true(a.ng.x == b.ng.x && a.ng.y == b.ng.y && a.ng.z == b.ng.z);
    assert_true(fabsf(a.n.x) > 0.3f); /* the grooves tilt X by +-0.5 x 0.9 */
    assert_near(lie_v3_len(a.n), 1.0, 1e-5);
    s->materials[0].normal_scale = 1e4f;
    for (float u = 0.05f; u < 0.5f; u += 0.07f) {
        lie_surface c = floor_point(s, u, 0.4f);
        assert_true(lie_v3_dot(c.n, c.ng) >= 0.0099f);
        assert_near(lie_v3_len(c.n), 1.0, 1e-5);
    }
    lie_scene_destroy(s);
    lie_scene_destroy(flat);
}

/* An `add` edit brings a normal-mapped object with its map, its tangents
 * and its texture indices moved past the scene's own. */
static void test_added_object_keeps_its_normal_map(void **state)
{
    (void)state;
    lie_scene *s = load("materials.gltf"), *src = load("normal_map_tangent.gltf");
    assert_true(s->n_textures > 0); /* so that the added texture indices move */
    const char text[] = "- add: {file: normal_map_tangent.gltf, node: Floor, as: Floor2}\n";
    lie_edit *e = NULL;
    lie_error err;
    lie_error_clear(&err);
    assert_int_equal(lie_edit_parse((const unsigned char *)text, sizeof text - 1, DATA "add.yaml", &e, &err), LIE_OK);
    assert_int_equal(lie_edit_apply(s, e, NULL, NULL, &err), LIE_OK);
    assert_int_equal(lie_scene_flatten(s, &err), LIE_OK);
    const lie_material *m = lie_scene_material(s, s->tri_material[s->n_tris - 1]);
    assert_true(m->normal_tex >= 0 && m->normal_tex < s->n_textures);
    assert_int_equal(s->textures[m->normal_tex].width, src->textures[src->materials[0].normal_tex].width);
    assert_non_null(s->tri_tan);
    assert_memory_equal(&s->tri_tan[12 * (size_t)(s->n_tris - 2)], src->tri_tan, sizeof(float) * 24);
    lie_edit_destroy(e);
    lie_scene_destroy(s);
    lie_scene_destroy(src);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_normal_map_read_with_scale_and_world_tangents),
        cmocka_unit_test(test_normal_map_tangents_made_match_given),
        cmocka_unit_test(test_tangents_follow_texture_space_handedness),
        cmocka_unit_test(test_normal_map_bends_shading_normal_above_horizon),
        cmocka_unit_test(test_added_object_keeps_its_normal_map),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
