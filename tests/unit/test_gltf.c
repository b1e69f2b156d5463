/* SPDX-License-Identifier: Apache-2.0 */
/* lib/scene: the glTF importer (gltf_*.cpp) and texture lookup (texture.c),
 * through lie_scene_load.  Fixtures: tests/data/gltf/ (gen_fixtures.py).
 * Size: long as the importer's trust boundary is wide: one test per class of
 * bad input, one file per module (CONTRIBUTING.md, Tests). */
#include <limits.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "scene/scene.h"
#include "shade/shade.h"

#define DATA "tests/data/gltf/"

/* ---- helpers ------------------------------------------------------------- */

static const char *fx(const char *name)
{
    static char buf[4][PATH_MAX];
    static int next;
    char *p = buf[next++ & 3];
    snprintf(p, sizeof buf[0], DATA "%s", name);
    return p;
}

static lie_scene *load_with(const char *path, const lie_scene_options *opt)
{
    lie_scene *s = NULL;
    lie_error err;
    lie_error_clear(&err);
    lie_status st = lie_scene_load(path, opt, &s, &err);
    if (st != LIE_OK) {
        char line[2200];
        lie_error_format(&err, line, sizeof line);
        print_error("unexpected failure: %s\n", line);
    }
    assert_int_equal(st, LIE_OK);
    assert_non_null(s);
    return s;
}

static lie_scene *load(const char *name) { return load_with(fx(name), NULL); }

/* Loading `path` fails with `status`; the message is one line, names the
 * file (through lie_error_format) and contains `needle`. */
static void expect_error_at(const char *path, const lie_scene_options *opt, lie_status status,
                            const char *needle)
{
    lie_scene *s = (lie_scene *)0x1;
    lie_error err;
    lie_error_clear(&err);
    lie_status st = lie_scene_load(path, opt, &s, &err);
    char line[2200];
    lie_error_format(&err, line, sizeof line);
    if (st != status || !strstr(err.msg, needle))
        print_error("%s: got status %d, message: %s\n", path, st, line);
    assert_int_equal(st, status);
    assert_int_equal(err.status, status);
    assert_null(s);
    assert_null(strchr(err.msg, '\n'));
    assert_null(strchr(err.msg, '\r'));
    assert_true(err.msg[0] != '\0');
    const char *base = strrchr(path, '/');
    assert_non_null(strstr(line, base ? base + 1 : path));
    assert_non_null(strstr(err.msg, needle));
}

static void expect_error(const char *name, lie_status status, const char *needle)
{
    expect_error_at(fx(name), NULL, status, needle);
}

static double srgb_to_linear(double c)
{
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

static void assert_vec3(lie_vec3 v, double x, double y, double z)
{
    if (fabs(v.x - x) > 1e-5 || fabs(v.y - y) > 1e-5 || fabs(v.z - z) > 1e-5)
        print_error("got (%g, %g, %g), want (%g, %g, %g)\n", v.x, v.y, v.z, x, y, z);
    assert_true(fabs(v.x - x) <= 1e-5 && fabs(v.y - y) <= 1e-5 && fabs(v.z - z) <= 1e-5);
}

static void assert_near(double got, double want, double tol)
{
    if (fabs(got - want) > tol)
        print_error("got %.9g, want %.9g\n", got, want);
    assert_true(fabs(got - want) <= tol);
}

static void assert_idx(const lie_primitive *p, const uint32_t *want, uint32_t n_tris)
{
    assert_int_equal(p->n_tris, n_tris);
    for (uint32_t i = 0; i < 3 * n_tris; i++)
        assert_int_equal(p->idx[i], want[i]);
}

static const lie_instance *instance_of_node(const lie_scene *s, int node)
{
    for (int i = 0; i < s->n_instances; i++)
        if (s->instances[i].node == node)
            return &s->instances[i];
    fail_msg("no instance of node %d", node);
    return NULL;
}

/* ---- primitive modes ---------------------------------------------------- */

static void test_gltf_strip_converted_to_triangles(void **state)
{
    (void)state;
    lie_scene *s = load("modes.gltf");
    assert_int_equal(s->n_meshes, 1);
    assert_int_equal(s->meshes[0].n_prims, 6);
    /* 4 vertices -> 2 triangles; the odd one is {v1, v3, v2} (glTF §3.7.2.1) */
    const lie_primitive *p = &s->meshes[0].prims[0];
    assert_int_equal(p->n_verts, 4);
    assert_idx(p, (const uint32_t[]){0, 1, 2, 1, 3, 2}, 2);
    /* both counter-clockwise seen from +z, like the strip's first triangle */
    assert_int_equal(s->instances[0].prim, 0);
    for (uint32_t t = s->instances[0].first_tri; t < s->instances[0].first_tri + 2; t++)
        assert_vec3(s->tri_ng[t], 0, 0, 1);
    lie_scene_destroy(s);
}

static void test_gltf_fan_converted_to_triangles(void **state)
{
    (void)state;
    lie_scene *s = load("modes.gltf");
    const lie_primitive *p = &s->meshes[0].prims[1];
    assert_idx(p, (const uint32_t[]){1, 2, 0, 2, 3, 0}, 2);
    assert_int_equal(s->instances[1].prim, 1);
    for (uint32_t t = s->instances[1].first_tri; t < s->instances[1].first_tri + 2; t++)
        assert_vec3(s->tri_ng[t], 0, 0, 1);
    lie_scene_destroy(s);
}

static void test_gltf_points_and_lines_skipped_and_counted(void **state)
{
    (void)state;
    lie_scene *s = load("modes.gltf");
    assert_int_equal(s->stats.points_skipped, 1);
    assert_int_equal(s->stats.lines_skipped, 3);
    /* kept as empty primitives so primitive indices stay the file's */
    for (int i = 2; i < 6; i++) {
        assert_int_equal(s->meshes[0].prims[i].n_tris, 0);
        assert_null(s->meshes[0].prims[i].idx);
    }
    assert_int_equal(s->n_tris, 4);
    assert_int_equal(s->stats.prims_without_material, 2);
    lie_scene_destroy(s);
}

static void test_gltf_index_widths_and_no_indices_give_same_triangles(void **state)
{
    (void)state;
    lie_scene *s = load("indices.gltf");
    assert_int_equal(s->n_instances, 4);
    assert_int_equal(s->n_tris, 8);
    for (int i = 0; i < 4; i++) {
        const lie_instance *in = &s->instances[i];
        assert_int_equal(in->n_tris, 2);
        for (uint32_t k = 0; k < 6; k++) {
            lie_vec3 a = s->tri_p[3 * s->instances[0].first_tri + k];
            lie_vec3 b = s->tri_p[3 * in->first_tri + k];
            assert_vec3(b, a.x, a.y, a.z);
        }
    }
    assert_vec3(s->tri_p[3], 1, 0, 0); /* second triangle: 1, 3, 2 */
    assert_vec3(s->tri_p[4], 1, 1, 0);
    assert_vec3(s->tri_p[5], 0, 1, 0);
    /* non-indexed primitives get 0..n-1 */
    assert_idx(&s->meshes[0].prims[3], (const uint32_t[]){0, 1, 2, 3, 4, 5}, 2);
    lie_scene_destroy(s);
}

/* ---- nodes and scenes --------------------------------------------------- */

static void test_gltf_node_trs_and_matrix_compose_to_world(void **state)
{
    (void)state;
    lie_scene *s = load("hierarchy.gltf");
    assert_int_equal(s->n_nodes, 4);
    assert_string_equal(s->nodes[0].name, "root");
    assert_int_equal(s->nodes[0].parent, -1);
    assert_int_equal(s->nodes[1].parent, 0);
    assert_int_equal(s->nodes[0].n_children, 1);
    assert_int_equal(s->nodes[0].children[0], 1);
    assert_int_equal(s->nodes[1].mesh, 0);
    assert_int_equal(s->nodes[0].mesh, -1);
    assert_int_equal(s->nodes[0].camera, -1);
    assert_int_equal(s->nodes[0].light, -1);
    /* the default scene is scene 1: roots 0 and 2; node 3 is elsewhere */
    assert_int_equal(s->n_roots, 2);
    assert_int_equal(s->roots[0], 0);
    assert_int_equal(s->roots[1], 2);
    assert_int_equal(s->n_tris, 2);
    /* node 1's local matrix is the file's (column-major, translation last) */
    assert_near(s->nodes[1].local.m[13], 1.0, 0.0);
    /* world = T(10,0,0) Rz(90) S(2) T(0,1,0): (x, y) -> (10 - 2(y + 1), 2x) */
    const lie_instance *child = instance_of_node(s, 1), *plain = instance_of_node(s, 2);
    const lie_vec3 *p = &s->tri_p[3 * child->first_tri];
    assert_vec3(p[0], 8, 0, 0);
    assert_vec3(p[1], 8, 2, 0);
    assert_vec3(p[2], 6, 0, 0);
    p = &s->tri_p[3 * plain->first_tri];
    assert_vec3(p[0], 0, 0, 0);
    assert_vec3(p[1], 1, 0, 0);
    assert_vec3(p[2], 0, 1, 0);
    lie_scene_destroy(s);
}

static void test_gltf_world_follows_scene_root_order(void **state)
{
    (void)state;
    lie_scene *s = load("hierarchy.gltf");
    /* roots 0 then 2, depth first: node 1 (under 0) before node 2 (scene.h) */
    int n = s->n_instances, first = n > 0 ? s->instances[0].node : -1, second = n > 1 ? s->instances[1].node : -1;
    lie_scene_destroy(s); /* before asserting: nothing leaks when this fails */
    assert_int_equal(n, 2);
    assert_int_equal(first, 1);
    assert_int_equal(second, 2);
}

static void test_gltf_without_scenes_roots_are_parentless_nodes(void **state)
{
    (void)state;
    lie_scene *s = load("no_scene.gltf");
    assert_int_equal(s->n_roots, 3);
    assert_int_equal(s->roots[0], 0);
    assert_int_equal(s->roots[1], 1);
    assert_int_equal(s->roots[2], 3);
    assert_int_equal(s->nodes[2].parent, 0);
    assert_int_equal(s->n_tris, 2);
    lie_scene_destroy(s);
}

/* ---- materials and textures -------------------------------------------- */

static void test_gltf_base_color_texture_decoded_from_srgb(void **state)
{
    (void)state;
    lie_scene *s = load("materials.gltf");
    const lie_material *m = &s->materials[0];
    assert_true(m->base_color_tex >= 0 && m->base_color_tex < s->n_textures);
    const lie_texture *t = &s->textures[m->base_color_tex];
    assert_int_equal(t->width, 2);
    assert_int_equal(t->height, 2);
    float c[4];
    /* texel (0, 0) = (128, 64, 255, 255): row 0 is v = 0 */
    lie_texture_sample(t, 0.25f, 0.25f, c);
    assert_near(c[0], srgb_to_linear(128 / 255.0), 1e-5);
    assert_near(c[1], srgb_to_linear(64 / 255.0), 1e-5);
    assert_near(c[2], 1.0, 1e-5);
    assert_near(c[3], 1.0, 1e-5);
    /* texel (1, 0) = (0, 255, 32, 128): alpha stays linear */
    lie_texture_sample(t, 0.75f, 0.25f, c);
    assert_near(c[0], 0.0, 1e-6);
    assert_near(c[2], srgb_to_linear(32 / 255.0), 1e-5);
    assert_near(c[3], 128 / 255.0, 1e-5);
    /* texel (1, 1) = (10, 20, 30, 40) */
    lie_texture_sample(t, 0.75f, 0.75f, c);
    assert_near(c[0], srgb_to_linear(10 / 255.0), 1e-6);
    assert_near(c[3], 40 / 255.0, 1e-6);
    lie_scene_destroy(s);
}

static void test_gltf_textures_deduplicated_per_colour_space(void **state)
{
    (void)state;
    lie_scene *s = load("materials.gltf");
    const lie_material *m = &s->materials[0];
    /* texture 0 as sRGB (base colour, emission) and linear (metallic-roughness),
     * texture 1 as sRGB */
    assert_int_equal(s->n_textures, 3);
    assert_int_equal(m->base_color_tex, m->emissive_tex);
    assert_true(m->mr_tex >= 0 && m->mr_tex != m->base_color_tex);
    float c[4];
    lie_texture_sample(&s->textures[m->mr_tex], 0.25f, 0.25f, c);
    assert_near(c[1], 64 / 255.0, 1e-6); /* G: roughness, linear */
    assert_near(c[2], 1.0, 1e-6);        /* B: metallic */
    lie_scene_destroy(s);
}

static void test_gltf_material_factors_and_emissive_strength(void **state)
{
    (void)state;
    lie_scene *s = load("materials.gltf");
    assert_int_equal(s->n_materials, 2);
    const lie_material *m = &s->materials[0];
    assert_string_equal(m->name, "textured");
    assert_near(m->base_color[0], 0.5, 0);
    assert_near(m->base_color[3], 1.0, 0);
    assert_near(m->metallic, 0.25, 0);
    assert_near(m->roughness, 0.75, 0);
    assert_near(m->emissive[0], 4.0, 1e-6); /* emissiveFactor x emissiveStrength */
    assert_near(m->emissive[1], 2.0, 1e-6);
    assert_near(m->emissive[2], 0.0, 0);
    assert_int_equal(m->double_sided, 1);
    const lie_material *d = &s->materials[1]; /* glTF defaults */
    assert_null(d->name);
    for (int c = 0; c < 4; c++)
        assert_near(d->base_color[c], 1.0, 0);
    assert_near(d->metallic, 1.0, 0);
    assert_near(d->roughness, 1.0, 0);
    assert_near(d->emissive[0] + d->emissive[1] + d->emissive[2], 0.0, 0);
    assert_int_equal(d->mr_tex, -1);
    assert_int_equal(d->emissive_tex, -1);
    assert_int_equal(d->double_sided, 0);
    assert_int_equal(s->meshes[0].prims[0].material, 0);
    assert_int_equal(s->meshes[0].prims[2].material, -1);
    assert_int_equal(s->stats.prims_without_material, 1);
    lie_scene_destroy(s);
}

static void test_gltf_sampler_wrap_modes_read(void **state)
{
    (void)state;
    lie_scene *s = load("materials.gltf");
    const lie_texture *t = &s->textures[s->materials[0].base_color_tex];
    assert_int_equal(t->wrap_s, LIE_WRAP_CLAMP);
    assert_int_equal(t->wrap_t, LIE_WRAP_MIRROR);
    const lie_texture *r = &s->textures[s->materials[1].base_color_tex];
    assert_int_equal(r->wrap_s, LIE_WRAP_REPEAT); /* no sampler: REPEAT */
    assert_int_equal(r->wrap_t, LIE_WRAP_REPEAT);
    lie_scene_destroy(s);
}

static void test_gltf_normalized_ubyte_texcoords_read_as_unit_floats(void **state)
{
    (void)state;
    lie_scene *s = load("materials.gltf");
    const lie_primitive *p = &s->meshes[0].prims[0];
    assert_non_null(p->uv);
    assert_non_null(p->nrm);
    static const float want[] = {0, 0, 1, 0, 0, 1};
    for (int i = 0; i < 6; i++)
        assert_near(p->uv[i], want[i], 0);
    assert_near(p->nrm[2], 1.0, 0);
    assert_null(s->meshes[0].prims[1].uv);
    assert_null(s->meshes[0].prims[1].nrm);
    lie_scene_destroy(s);
}

static void test_gltf_sixteen_bit_grey_texture_decoded(void **state)
{
    (void)state;
    lie_scene *s = load("materials.gltf");
    const lie_texture *t = &s->textures[s->materials[1].base_color_tex];
    assert_int_equal(t->width, 1);
    float c[4];
    lie_texture_sample(t, 0.3f, 0.9f, c);
    double want = srgb_to_linear(40000 / 65535.0);
    assert_near(c[0], want, 1e-6);
    assert_near(c[1], want, 1e-6);
    assert_near(c[2], want, 1e-6);
    assert_near(c[3], 1.0, 0);
    lie_scene_destroy(s);
}

/* ---- texture lookup ------------------------------------------------------ */

static void test_gltf_quantized_attributes_dequantized(void **state)
{
    (void)state;
    lie_scene *s = load("quantized.gltf");
    assert_int_equal(s->n_tris, 1);
    const float want[3][3] = {{1, 2, 3}, {3, 2, 3}, {1, 4, 3}};
    for (int v = 0; v < 3; v++) {
        assert_near(s->tri_p[v].x, want[v][0], 1e-6);
        assert_near(s->tri_p[v].y, want[v][1], 1e-6);
        assert_near(s->tri_p[v].z, want[v][2], 1e-6);
        /* normalized BYTE 64 -> 0.504, then unit length */
        assert_near(s->tri_n[v].z, 1.0, 1e-6);
        assert_near(lie_v3_len(s->tri_n[v]), 1.0, 1e-6);
    }
    /* plain USHORT texture coordinates are integers, not fractions */
    const float uv[6] = {0, 0, 2, 0, 0, 2};
    for (int k = 0; k < 6; k++)
        assert_near(s->tri_uv[k], uv[k], 0);
    lie_scene_destroy(s);
}

/* TEXCOORD_1: read, chosen per slot by texCoord (or KHR_texture_transform's
 * texCoord), and looked up through lie_scene_slot_uv. */
static void test_gltf_second_texcoord_set_per_slot(void **state)
{
    (void)state;
    lie_scene *s = load("texcoord1.gltf");
    const lie_primitive *p = &s->meshes[0].prims[0];
    assert_non_null(p->uv1);
    assert_near(p->uv1[2], 0.75, 0);
    const lie_material *m = &s->materials[0];
    assert_int_equal(m->tex_set[LIE_TEX_BASE_COLOR], 1);
    assert_int_equal(m->tex_set[LIE_TEX_METALLIC_ROUGHNESS], 1);
    assert_int_equal(m->tex_set[LIE_TEX_EMISSIVE], 0);
    assert_non_null(s->tri_uv1);
    float u, v;
    lie_scene_slot_uv(s, m, LIE_TEX_BASE_COLOR, 0, 1.0f, 0.0f, &u, &v); /* at vertex 1 */
    assert_near(u, 0.75, 1e-6);
    assert_near(v, 0.25, 1e-6);
    lie_scene_slot_uv(s, m, LIE_TEX_EMISSIVE, 0, 1.0f, 0.0f, &u, &v);
    assert_near(u, 1.0, 1e-6);
    assert_near(v, 0.0, 1e-6);
    lie_scene_destroy(s);
    s = load("texture_transform.gltf"); /* one set: nothing more is kept */
    assert_null(s->tri_uv1);
    lie_scene_destroy(s);
    expect_error("texcoord1_bad.gltf", LIE_ERR_FORMAT,
                 "metallicRoughnessTexture.extensions.KHR_texture_transform.texCoord: 1.5 is not an integer");
}

static void test_gltf_texture_transform_read_and_applied(void **state)
{
    (void)state;
    lie_scene *s = load("texture_transform.gltf");
    const lie_material *m = &s->materials[0];
    const float *p = m->tex_param[LIE_TEX_BASE_COLOR];
    assert_near(p[0], 0.5, 0);
    assert_near(p[1], 0.0, 0);
    assert_near(p[2], M_PI / 2, 1e-6);
    assert_near(p[3], 2.0, 0);
    assert_near(p[4], 1.0, 0);
    assert_false(lie_material_tex_xf_is_identity(m, LIE_TEX_BASE_COLOR));
    assert_true(lie_material_tex_xf_is_identity(m, LIE_TEX_METALLIC_ROUGHNESS));
    assert_true(lie_material_tex_xf_is_identity(m, LIE_TEX_EMISSIVE));
    /* T(0.5, 0) R(pi/2) S(2, 1): (u, v) -> (v + 0.5, -2u) */
    float tu, tv;
    lie_material_tex_xf_apply(m->tex_xf[LIE_TEX_BASE_COLOR], 0.1f, 0.2f, &tu, &tv);
    assert_near(tu, 0.7, 1e-6);
    assert_near(tv, -0.2, 1e-6);
    lie_material_tex_xf_apply(m->tex_xf[LIE_TEX_METALLIC_ROUGHNESS], 0.1f, 0.2f, &tu, &tv);
    assert_near(tu, 0.1, 1e-7); /* floats against doubles */
    assert_near(tv, 0.2, 1e-7);
    /* a shading point sees the texel the transform picks: at uv (0, 0.25)
     * the base colour texture is read at (0.75, 0) -> texel (1, 0), whose
     * red is 0 (untransformed it would be texel (0, 0), red 128) */
    lie_hit hit = {0};
    hit.tri = 0;
    hit.u = 0.0f;
    hit.v = 0.25f;
    hit.t = 1.0f;
    lie_surface sf;
    lie_surface_from_hit(s, &hit, lie_v3(0, 0, -1), &sf);
    float expect[4];
    lie_texture_sample(&s->textures[m->base_color_tex], 0.75f, 0.0f, expect);
    assert_near(sf.base_color[0], expect[0], 1e-6);
    assert_near(sf.base_color[1], expect[1], 1e-6);
    /* a transform is part of the scene's content */
    lie_scene *plain = load("texture_transform.gltf");
    lie_material_tex_xf_identity(&plain->materials[0]);
    lie_error err;
    assert_int_equal(lie_scene_flatten(plain, &err), LIE_OK);
    assert_true(s->hash != plain->hash);
    lie_scene_destroy(plain);
    lie_scene_destroy(s);
    expect_error("texture_transform_bad.gltf", LIE_ERR_FORMAT, "KHR_texture_transform scale");
}

static void test_gltf_vertex_colors_multiply_base_color(void **state)
{
    (void)state;
    lie_scene *s = load("vertex_colors.gltf");
    assert_int_equal(s->n_tris, 3);
    assert_non_null(s->tri_color);
    /* triangle 0: VEC3 FLOAT, alpha 1, 2 clamped to 1 */
    const float want0[12] = {1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1};
    for (int k = 0; k < 12; k++)
        assert_near(s->tri_color[k], want0[k], 0);
    /* triangle 1: normalized USHORT RGBA */
    assert_near(s->tri_color[12 + 3], 32768 / 65535.0, 1e-6);
    assert_near(s->tri_color[12 + 8], 65535 / 65535.0, 0);
    assert_near(s->tri_color[12 + 9], 0.0, 0);
    /* triangle 2: no COLOR_0, white */
    for (int k = 0; k < 12; k++)
        assert_near(s->tri_color[24 + k], 1.0, 0);
    /* at vertex 1 of triangle 0 the base colour is (0.5, 1, 1) x (0, 1, 0) */
    lie_hit hit = {0};
    hit.tri = 0;
    hit.u = 1.0f;
    hit.v = 0.0f;
    hit.t = 1.0f;
    lie_surface sf;
    lie_surface_from_hit(s, &hit, lie_v3(0, 0, -1), &sf);
    assert_near(sf.base_color[0], 0.0, 1e-7);
    assert_near(sf.base_color[1], 1.0, 1e-7);
    assert_near(sf.base_color[2], 0.0, 1e-7);
    /* halfway between vertices 0 and 2: (0.5, 1, 1) x (0.5, 0, 0.5) */
    hit.u = 0.0f;
    hit.v = 0.5f;
    lie_surface_from_hit(s, &hit, lie_v3(0, 0, -1), &sf);
    assert_near(sf.base_color[0], 0.25, 1e-6);
    assert_near(sf.base_color[1], 0.0, 1e-6);
    assert_near(sf.base_color[2], 0.5, 1e-6);
    /* vertex colours are content; scenes without them keep no array */
    lie_scene *plain = load("materials.gltf");
    assert_null(plain->tri_color);
    lie_scene_destroy(plain);
    lie_scene_destroy(s);
}

/* A texture kept as an image's codes (8 and 16 bits, the importer's) reads
 * as the floats of its code values: the same samples as the float texture
 * of those values. */
static void test_texture_codes_read_as_their_values(void **state)
{
    (void)state;
    for (int bits = 8; bits <= 16; bits += 8) {
        const size_t levels = bits == 8 ? 256 : 65536;
        float *value[2] = {malloc(sizeof(float) * levels), malloc(sizeof(float) * levels)};
        assert_non_null(value[0]);
        assert_non_null(value[1]);
        for (size_t i = 0; i < levels; i++) {
            value[0][i] = lie_texture_code_value(i, levels, 1);
            value[1][i] = lie_texture_code_value(i, levels, 0);
        }
        /* 3 x 2 texels of codes spread over the range, alpha apart */
        unsigned char codes[3 * 2 * 4 * 2];
        float px[3 * 2 * 4];
        for (size_t i = 0; i < 3 * 2 * 4; i++) {
            size_t code = (i * 7919 + 13) % levels;
            if (bits == 8)
                codes[i] = (unsigned char)code;
            else
                codes[2 * i] = (unsigned char)(code & 255), codes[2 * i + 1] = (unsigned char)(code >> 8);
            px[i] = value[i % 4 == 3][code];
        }
        lie_texture c = {.width = 3, .height = 2, .wrap_s = LIE_WRAP_REPEAT, .wrap_t = LIE_WRAP_MIRROR, .image = -1,
                         .codes = codes, .code_bits = bits, .code_value = {value[0], value[1]}};
        lie_texture f = {.width = 3, .height = 2, .rgba = px, .wrap_s = LIE_WRAP_REPEAT, .wrap_t = LIE_WRAP_MIRROR,
                         .image = -1};
        assert_true(lie_texture_has_texels(&c));
        for (int k = 0; k < 6; k++) {
            float a[4], b[4];
            lie_texture_texel(&c, (size_t)k, a);
            lie_texture_texel(&f, (size_t)k, b);
            assert_memory_equal(a, b, sizeof a);
        }
        for (float u = -1.3f; u < 2.0f; u += 0.17f) {
            float a[4], b[4];
            lie_texture_sample(&c, u, 0.61f * u + 0.2f, a);
            lie_texture_sample(&f, u, 0.61f * u + 0.2f, b);
            assert_memory_equal(a, b, sizeof a);
        }
        free(value[0]);
        free(value[1]);
    }
}

static void test_texture_sample_wraps_and_blends(void **state)
{
    (void)state;
    float px[2 * 1 * 4] = {0, 0, 0, 1, 1, 1, 1, 1}; /* 2x1: black, white */
    lie_texture t = {.width = 2, .height = 1, .rgba = px, .wrap_s = LIE_WRAP_REPEAT, .wrap_t = LIE_WRAP_REPEAT,
                     .image = -1};
    float c[4];
    lie_texture_sample(&t, 0.25f, 0.5f, c); /* texel centre */
    assert_near(c[0], 0.0, 1e-6);
    lie_texture_sample(&t, 0.5f, 0.5f, c); /* half way between the centres */
    assert_near(c[0], 0.5, 1e-6);
    lie_texture_sample(&t, 0.0f, 0.5f, c); /* REPEAT blends across the edge */
    assert_near(c[0], 0.5, 1e-6);
    lie_texture_sample(&t, 1.25f, 0.5f, c);
    assert_near(c[0], 0.0, 1e-6);
    t.wrap_s = LIE_WRAP_CLAMP;
    lie_texture_sample(&t, 0.0f, 0.5f, c);
    assert_near(c[0], 0.0, 1e-6);
    lie_texture_sample(&t, 7.0f, 0.5f, c);
    assert_near(c[0], 1.0, 1e-6);
    t.wrap_s = LIE_WRAP_MIRROR; /* [0,1) as is, [1,2) reversed */
    lie_texture_sample(&t, 1.25f, 0.5f, c);
    assert_near(c[0], 1.0, 1e-6);
    lie_texture_sample(&t, -0.25f, 0.5f, c);
    assert_near(c[0], 0.0, 1e-6);
    lie_texture_sample(&t, 1.0f, 0.5f, c);
    assert_near(c[0], 1.0, 1e-6);
    lie_texture_sample(&t, NAN, INFINITY, c); /* no crash, a texel value */
    assert_true(c[0] >= 0.0f && c[0] <= 1.0f);
}

/* ---- cameras, lights, sparse ------------------------------------------- */

static void test_gltf_lights_and_cameras_read_with_defaults(void **state)
{
    (void)state;
    lie_scene *s = load("lights_cameras.gltf");
    assert_int_equal(s->n_light_defs, 3);
    const lie_light_def *l = s->light_defs;
    assert_string_equal(l[0].name, "bulb");
    assert_int_equal(l[0].type, LIE_LIGHT_POINT);
    assert_near(l[0].color[1], 0.5, 0);
    assert_near(l[0].intensity, 10, 0);
    assert_near(l[0].range, 5, 0);
    assert_int_equal(l[1].type, LIE_LIGHT_SPOT);
    assert_near(l[1].color[0] + l[1].color[1] + l[1].color[2], 3.0, 0);
    assert_near(l[1].intensity, 1.0, 0);
    assert_near(l[1].range, 0.0, 0);
    assert_near(l[1].inner_cone, 0.0, 0);
    assert_near(l[1].outer_cone, M_PI / 4, 1e-6);
    assert_int_equal(l[2].type, LIE_LIGHT_DIRECTIONAL);
    assert_near(l[2].intensity, 3.0, 0);
    assert_int_equal(s->nodes[1].light, 0);
    assert_int_equal(s->nodes[3].light, 2);

    assert_int_equal(s->n_camera_defs, 3);
    const lie_camera_def *c = s->camera_defs;
    assert_string_equal(c[0].name, "persp");
    assert_near(c[0].yfov, 0.5, 1e-7);
    assert_near(c[0].aspect, 1.5, 0);
    assert_near(c[0].znear, 0.1, 1e-7);
    assert_near(c[1].aspect, 0.0, 0); /* none in the file */
    assert_near(c[2].yfov, 0.0, 0); /* orthographic */
    assert_near(c[2].xmag, 1.0, 0);
    assert_near(c[2].ymag, 1.0, 0);
    assert_near(c[2].znear, 0.1, 1e-7);
    assert_near(c[2].zfar, 10.0, 0);
    assert_int_equal(s->nodes[4].camera, 0);
    assert_int_equal(s->nodes[6].camera, 2);
    /* all three are usable cameras; the orthographic one looks down -z */
    assert_int_equal(s->n_cameras, 3);
    assert_near(s->cameras[2].ymag, 1.0, 0);
    assert_near(s->cameras[0].ymag, 0.0, 0);
    assert_near(s->cameras[2].forward.z, -1.0, 1e-6);
    lie_scene_destroy(s);
}

static void test_gltf_sparse_accessor_substitutes_values(void **state)
{
    (void)state;
    lie_scene *s = load("sparse.gltf");
    const lie_primitive *p = &s->meshes[0].prims[0];
    static const float pos[] = {0, 0, 0, 1, 0, 0, 0, 3, 0};
    static const float nrm[] = {0, 0, 0, 0, 0, 1, 0, 0, 0}; /* no bufferView: zeros */
    for (int i = 0; i < 9; i++) {
        assert_near(p->pos[i], pos[i], 0);
        assert_near(p->nrm[i], nrm[i], 0);
    }
    lie_scene_destroy(s);
}

/* Morph targets are applied with the default weights: the node's, else the
 * mesh's; a node whose weights differ from its mesh's gets a morphed copy. */
static void test_gltf_morph_targets_applied_with_default_weights(void **state)
{
    (void)state;
    lie_scene *s = load("morph.gltf");
    assert_int_equal(s->n_meshes, 3); /* Sheet, and copies for Full and Rest */
    assert_int_equal(s->nodes[0].mesh, 0);
    assert_int_equal(s->nodes[1].mesh, 1);
    assert_int_equal(s->nodes[2].mesh, 2);
    assert_int_equal(s->n_tris, 6);
    /* Half: weights [0.5, 0], every vertex lifted by 0.5 (a sparse target) */
    for (int k = 0; k < 6; k++)
        assert_near(s->tri_p[k].z, 0.5, 0);
    assert_vec3(s->tri_p[5], 1, 1, 0.5);
    /* Full: [1, 1], lifted by 1, vertex 3 pushed by 1 in x, its normal
     * (0, 0, 1) + (1, 0, -1) = +x */
    for (int k = 6; k < 12; k++)
        assert_near(s->tri_p[k].z, 1, 0);
    assert_vec3(s->tri_p[11], 3 + 2, 1, 1);
    assert_vec3(s->tri_n[11], 1, 0, 0);
    assert_vec3(s->tri_n[6], 0, 0, 1);
    /* Rest: [0, 0], as the file's vertices */
    assert_vec3(s->tri_p[12], 6, 0, 0);
    assert_vec3(s->tri_p[17], 7, 1, 0);
    lie_scene_destroy(s);
    expect_error("morph_bad.gltf", LIE_ERR_FORMAT, "node 1: 1 morph weights for 2 targets");
}

/* ---- containers and files ----------------------------------------------- */

static void test_gltf_glb_loads_with_embedded_image(void **state)
{
    (void)state;
    lie_scene *s = load("triangle.glb");
    assert_int_equal(s->n_tris, 1);
    assert_vec3(s->tri_p[1], 1, 0, 0);
    assert_int_equal(s->n_textures, 1);
    float c[4];
    lie_texture_sample(&s->textures[0], 0.25f, 0.75f, c); /* texel (0, 1) = white */
    assert_near(c[0], 1.0, 1e-6);
    assert_near(c[3], 0.0, 1e-6);
    lie_scene_destroy(s);
}

static void test_gltf_format_detected_by_content_not_extension(void **state)
{
    (void)state;
    lie_scene *s = load("glb_named.gltf");
    assert_int_equal(s->n_tris, 1);
    assert_int_equal(s->n_textures, 1);
    lie_scene_destroy(s);
    s = load("json_named.glb");
    assert_int_equal(s->n_tris, 1);
    lie_scene_destroy(s);
}

static void test_gltf_external_bin_and_image_load(void **state)
{
    (void)state;
    lie_scene *s = load("external.gltf");
    assert_int_equal(s->n_tris, 1);
    assert_int_equal(s->n_textures, 1);
    assert_int_equal(s->textures[0].width, 2);
    assert_non_null(s->meshes[0].prims[0].uv);
    lie_scene_destroy(s);
    s = load("inside_dotdot.gltf"); /* "sub/../external.bin" stays inside */
    assert_int_equal(s->n_tris, 1);
    lie_scene_destroy(s);
}

static void test_gltf_uri_leaving_folder_refused_unless_allowed(void **state)
{
    (void)state;
    expect_error("escape/escape.gltf", LIE_ERR_UNSUPPORTED, "'../external.bin' leaves the scene's folder");
    lie_scene_options opt = lie_scene_options_default();
    opt.allow_external_uris = 1;
    lie_scene *s = load_with(fx("escape/escape.gltf"), &opt);
    assert_int_equal(s->n_tris, 1);
    assert_int_equal(s->n_textures, 1);
    lie_scene_destroy(s);
}

/* Replaces the first `from` in `buf` (of capacity `size`) by `to`. */
static void replace_once(char *buf, size_t size, const char *from, const char *to)
{
    char *at = strstr(buf, from);
    assert_non_null(at);
    size_t nf = strlen(from), nt = strlen(to), tail = strlen(at + nf);
    assert_true((size_t)(at - buf) + nt + tail < size);
    memmove(at + nt, at + nf, tail + 1);
    memcpy(at, to, nt);
}

/* Writes external.gltf with its URIs replaced by `prefix` + absolute path. */
static void write_absolute_variant(const char *out, const char *prefix)
{
    char dir[PATH_MAX], json[16384], uri[PATH_MAX + 64];
    assert_non_null(realpath(DATA, dir));
    FILE *f = fopen(fx("external.gltf"), "rb");
    assert_non_null(f);
    size_t n = fread(json, 1, sizeof json / 2, f);
    fclose(f);
    json[n] = '\0';
    snprintf(uri, sizeof uri, "\"%s%s/external.bin\"", prefix, dir);
    replace_once(json, sizeof json, "\"external.bin\"", uri);
    snprintf(uri, sizeof uri, "\"%s%s/ext%%20image.png\"", prefix, dir);
    replace_once(json, sizeof json, "\"ext%20image.png\"", uri);
    f = fopen(out, "wb");
    assert_non_null(f);
    fputs(json, f);
    fclose(f);
}

static void test_gltf_absolute_and_file_uris_refused_unless_allowed(void **state)
{
    (void)state;
    char tmpl[] = "/tmp/lie_test_gltf_XXXXXX";
    assert_non_null(mkdtemp(tmpl));
    char abs_path[PATH_MAX + 64], file_path[PATH_MAX + 64];
    snprintf(abs_path, sizeof abs_path, "%s/absolute.gltf", tmpl);
    snprintf(file_path, sizeof file_path, "%s/file_uri.gltf", tmpl);
    write_absolute_variant(abs_path, "");
    write_absolute_variant(file_path, "file://");

    expect_error_at(abs_path, NULL, LIE_ERR_UNSUPPORTED, "leaves the scene's folder");
    expect_error_at(file_path, NULL, LIE_ERR_UNSUPPORTED, "leaves the scene's folder");
    lie_scene_options opt = lie_scene_options_default();
    opt.allow_external_uris = 1;
    lie_scene *s = load_with(abs_path, &opt);
    assert_int_equal(s->n_textures, 1);
    lie_scene_destroy(s);
    s = load_with(file_path, &opt);
    assert_int_equal(s->n_textures, 1);
    lie_scene_destroy(s);

    remove(abs_path);
    remove(file_path);
    rmdir(tmpl);
}

/* ---- bad inputs ------------------------------------------------------------ */

static void test_gltf_missing_file_is_io_error(void **state)
{
    (void)state;
    expect_error("no_such_file.gltf", LIE_ERR_IO, "cannot open: No such file or directory");
}

static void test_gltf_invalid_json_is_format_error_with_position(void **state)
{
    (void)state;
    expect_error("bad_json.gltf", LIE_ERR_FORMAT, "parse error");
    lie_scene *s = NULL;
    lie_error err;
    lie_error_clear(&err);
    assert_int_equal(lie_scene_load(fx("bad_json.gltf"), NULL, &s, &err), LIE_ERR_FORMAT);
    assert_int_equal(err.line, 3);
    expect_error("empty.gltf", LIE_ERR_FORMAT, "empty file");
}

static void test_gltf_truncated_glb_refused(void **state)
{
    (void)state;
    expect_error("truncated.glb", LIE_ERR_FORMAT, "truncated GLB");
    expect_error("bin_overrun.glb", LIE_ERR_FORMAT, "BIN chunk");
}

static void test_gltf_glb_image_view_outside_buffer_refused(void **state)
{
    (void)state;
    expect_error("image_view_oob.glb", LIE_ERR_FORMAT, "bufferView lies outside its buffer");
}

static void test_gltf_missing_bin_is_io_error(void **state)
{
    (void)state;
    expect_error("missing_bin.gltf", LIE_ERR_IO, "cannot open 'no_such.bin'");
}

static void test_gltf_missing_image_is_io_error_naming_it(void **state)
{
    (void)state;
    expect_error("missing_image.gltf", LIE_ERR_IO, "image 0 'no_such_image.png'");
}

static void test_gltf_accessor_beyond_its_view_refused(void **state)
{
    (void)state;
    expect_error("accessor_oob.gltf", LIE_ERR_FORMAT, "run past its bufferView");
    expect_error("accessor_offset_oob.gltf", LIE_ERR_FORMAT, "run past its bufferView");
    expect_error("view_oob.gltf", LIE_ERR_FORMAT, "lies outside buffer 0");
}

static void test_gltf_index_beyond_vertex_count_refused(void **state)
{
    (void)state;
    expect_error("index_oob.gltf", LIE_ERR_FORMAT, "mesh 0 primitive 0: index 7 beyond vertex count 3");
}

static void test_gltf_primitive_without_position_refused(void **state)
{
    (void)state;
    expect_error("no_position.gltf", LIE_ERR_FORMAT, "mesh 0 primitive 0 has no POSITION");
}

static void test_gltf_attribute_types_and_counts_checked(void **state)
{
    (void)state;
    expect_error("position_type.gltf", LIE_ERR_FORMAT, "POSITION must be VEC3 FLOAT");
    expect_error("normal_count.gltf", LIE_ERR_FORMAT, "NORMAL has 2 elements, POSITION 3");
    expect_error("sparse_index_oob.gltf", LIE_ERR_FORMAT, "sparse index 9 beyond its count 3");
    expect_error("ortho_zero.gltf", LIE_ERR_FORMAT, "camera 0: orthographic xmag and ymag must be finite and nonzero");
    expect_error("draco_required.gltf", LIE_ERR_UNSUPPORTED, "requires extension KHR_draco_mesh_compression");
}

static void test_gltf_node_graph_errors_refused(void **state)
{
    (void)state;
    expect_error("cycle.gltf", LIE_ERR_FORMAT, "cycle");
    expect_error("two_parents.gltf", LIE_ERR_FORMAT, "node 2 has two parents");
    expect_error("child_oob.gltf", LIE_ERR_FORMAT, "node 0: child 5 out of range");
}

static void test_gltf_references_out_of_range_refused(void **state)
{
    (void)state;
    expect_error("mesh_oob.gltf", LIE_ERR_FORMAT, "node 0: mesh 3 out of range");
    expect_error("material_oob.gltf", LIE_ERR_FORMAT, "material 2 out of range");
    expect_error("texture_oob.gltf", LIE_ERR_FORMAT, "texture 4 out of range");
}

static void test_gltf_unsupported_required_extension_refused(void **state)
{
    (void)state;
    expect_error("required_ext.gltf", LIE_ERR_UNSUPPORTED, "requires extension KHR_draco_mesh_compression");
}

static void test_gltf_triangle_limit_checked_before_allocating(void **state)
{
    (void)state;
    lie_scene_options opt = lie_scene_options_default();
    opt.max_triangles = 7; /* indices.gltf has 8 */
    expect_error_at(fx("indices.gltf"), &opt, LIE_ERR_LIMIT, "beyond the limit of 7");
    opt.max_triangles = 5; /* instanced.gltf: 2 in the document, 6 in the world */
    expect_error_at(fx("instanced.gltf"), &opt, LIE_ERR_LIMIT, "instancing");
    opt.max_triangles = 6;
    lie_scene *s = load_with(fx("instanced.gltf"), &opt);
    assert_int_equal(s->n_tris, 6);
    lie_scene_destroy(s);
}

int main(int argc, char **argv)
{
    /* fixtures are relative to the repository root; allow running from elsewhere */
    struct stat st;
    if (stat(DATA, &st) != 0 && argc > 0) {
        char dir[PATH_MAX];
        snprintf(dir, sizeof dir, "%s", argv[0]);
        char *slash = strrchr(dir, '/');
        if (slash) {
            snprintf(slash, sizeof dir - (size_t)(slash - dir), "/../../..");
            if (chdir(dir) != 0)
                return 1;
        }
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gltf_strip_converted_to_triangles),
        cmocka_unit_test(test_gltf_fan_converted_to_triangles),
        cmocka_unit_test(test_gltf_points_and_lines_skipped_and_counted),
        cmocka_unit_test(test_gltf_index_widths_and_no_indices_give_same_triangles),
        cmocka_unit_test(test_gltf_node_trs_and_matrix_compose_to_world),
        cmocka_unit_test(test_gltf_world_follows_scene_root_order),
        cmocka_unit_test(test_gltf_without_scenes_roots_are_parentless_nodes),
        cmocka_unit_test(test_gltf_base_color_texture_decoded_from_srgb),
        cmocka_unit_test(test_gltf_textures_deduplicated_per_colour_space),
        cmocka_unit_test(test_gltf_material_factors_and_emissive_strength),
        cmocka_unit_test(test_gltf_sampler_wrap_modes_read),
        cmocka_unit_test(test_gltf_normalized_ubyte_texcoords_read_as_unit_floats),
        cmocka_unit_test(test_gltf_sixteen_bit_grey_texture_decoded),
        cmocka_unit_test(test_gltf_quantized_attributes_dequantized),
        cmocka_unit_test(test_gltf_texture_transform_read_and_applied),
        cmocka_unit_test(test_gltf_second_texcoord_set_per_slot),
        cmocka_unit_test(test_gltf_vertex_colors_multiply_base_color),
        cmocka_unit_test(test_texture_sample_wraps_and_blends),
        cmocka_unit_test(test_texture_codes_read_as_their_values),
        cmocka_unit_test(test_gltf_lights_and_cameras_read_with_defaults),
        cmocka_unit_test(test_gltf_sparse_accessor_substitutes_values),
        cmocka_unit_test(test_gltf_morph_targets_applied_with_default_weights),
        cmocka_unit_test(test_gltf_glb_loads_with_embedded_image),
        cmocka_unit_test(test_gltf_format_detected_by_content_not_extension),
        cmocka_unit_test(test_gltf_external_bin_and_image_load),
        cmocka_unit_test(test_gltf_uri_leaving_folder_refused_unless_allowed),
        cmocka_unit_test(test_gltf_absolute_and_file_uris_refused_unless_allowed),
        cmocka_unit_test(test_gltf_missing_file_is_io_error),
        cmocka_unit_test(test_gltf_invalid_json_is_format_error_with_position),
        cmocka_unit_test(test_gltf_truncated_glb_refused),
        cmocka_unit_test(test_gltf_glb_image_view_outside_buffer_refused),
        cmocka_unit_test(test_gltf_missing_bin_is_io_error),
        cmocka_unit_test(test_gltf_missing_image_is_io_error_naming_it),
        cmocka_unit_test(test_gltf_accessor_beyond_its_view_refused),
        cmocka_unit_test(test_gltf_index_beyond_vertex_count_refused),
        cmocka_unit_test(test_gltf_primitive_without_position_refused),
        cmocka_unit_test(test_gltf_attribute_types_and_counts_checked),
        cmocka_unit_test(test_gltf_node_graph_errors_refused),
        cmocka_unit_test(test_gltf_references_out_of_range_refused),
        cmocka_unit_test(test_gltf_unsupported_required_extension_refused),
        cmocka_unit_test(test_gltf_triangle_limit_checked_before_allocating),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
