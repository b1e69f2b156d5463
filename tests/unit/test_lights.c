/* SPDX-License-Identifier: Apache-2.0 */
/* lib/shade's light samplers and textured emitters against quadrature, on
 * the degenerate cases of real scenes: 500 emitters, a strip of 1,000
 * triangles, an emissive texture with one lit texel; and the systematic
 * picks, the tree's bounds and the options' size.  Scenes are built in
 * memory. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "lie.h"
#include "shade/internal.h"
#include "fixtures.h"

/* A Lambert floor at y = 0 (albedo 0.5) and an emissive material of
 * radiance L; the floor's material is 0, the light's 1. */
static lie_scene *floor_scene(const char *name, float L, int emissive_tex)
{
    lie_scene *s = lie_scene_new(name);
    assert_non_null(s);
    lie_material floor = lie_material_default();
    floor.base_color[0] = floor.base_color[1] = floor.base_color[2] = 0.5f;
    floor.metallic = 0.0f;
    floor.roughness = 1.0f;
    assert_int_equal(lie_scene_add_material(s, &floor), 0);
    lie_material light = lie_material_default();
    light.base_color[0] = light.base_color[1] = light.base_color[2] = 0.0f;
    light.metallic = 0.0f;
    light.emissive[0] = light.emissive[1] = light.emissive[2] = L;
    light.emissive_tex = emissive_tex;
    assert_int_equal(lie_scene_add_material(s, &light), 1);
    float F = 100.0f;
    float fp[12] = {-F, 0, -F, -F, 0, F, F, 0, F, F, 0, -F};
    uint32_t fi[6] = {0, 1, 2, 0, 2, 3};
    int mesh_f = lie_scene_add_mesh(s, "Floor", fp, NULL, NULL, 4, fi, 2, 0);
    assert_true(lie_scene_add_node(s, "Floor", -1, NULL, mesh_f, -1, -1) >= 0);
    return s;
}

/* A quad facing down (-y) at height h over [x0, x1] x [z0, z1], uv over it
 * (u along x, v along z), as `nq` strips along x (2 nq triangles). */
static void add_quad_m(lie_scene *s, const char *name, float x0, float x1, float z0, float z1, float h, int nq,
                       int material)
{
    float *p = malloc(sizeof(float) * 6 * ((size_t)nq + 1));
    float *uv = malloc(sizeof(float) * 4 * ((size_t)nq + 1));
    uint32_t *ix = malloc(sizeof(uint32_t) * 6 * (size_t)nq);
    assert_true(p && uv && ix);
    for (int i = 0; i <= nq; i++) {
        float t = (float)i / (float)nq, x = x0 + (x1 - x0) * t;
        float q[6] = {x, h, z0, x, h, z1};
        memcpy(p + 6 * i, q, sizeof q);
        float w[4] = {t, 0.0f, t, 1.0f};
        memcpy(uv + 4 * i, w, sizeof w);
    }
    for (int i = 0; i < nq; i++) {
        uint32_t a = (uint32_t)(2 * i), b = a + 1, c = a + 2, d = a + 3;
        /* CCW seen from below: normal -y */
        uint32_t t[6] = {a, c, b, b, c, d};
        memcpy(ix + 6 * i, t, sizeof t);
    }
    int mesh = lie_scene_add_mesh(s, name, p, NULL, uv, (uint32_t)(2 * (nq + 1)), ix, (uint32_t)(2 * nq), material);
    assert_true(mesh >= 0);
    assert_true(lie_scene_add_node(s, name, -1, NULL, mesh, -1, -1) >= 0);
    free(p);
    free(uv);
    free(ix);
}

static void add_quad(lie_scene *s, const char *name, float x0, float x1, float z0, float z1, float h, int nq)
{
    add_quad_m(s, name, x0, x1, z0, z1, h, nq, 1);
}

/* s's one texture, n x n float RGBA texels, all 0, wrapped by `wrap`:
 * its texels to fill in. */
static float *one_texture(lie_scene *s, int n, lie_wrap wrap)
{
    s->textures = calloc(1, sizeof *s->textures);
    assert_non_null(s->textures);
    s->n_textures = 1;
    lie_texture *t = &s->textures[0];
    t->width = t->height = n;
    t->wrap_s = t->wrap_t = wrap;
    t->rgba = calloc((size_t)n * n * 4, sizeof(float));
    assert_non_null(t->rgba);
    return t->rgba;
}

/* The light a Lambert floor point at (px, 0, pz) of albedo 0.5 reflects
 * from the down-facing emitters of s, by midpoint quadrature over each of
 * their triangles (k x k cells of the unit square lie_sample_triangle
 * maps, equal in area), the radiance from the emitter interface. */
static double quadrature(const lie_scene *s, float px, float pz, int k)
{
    double sum = 0.0;
    for (int e = 0; e < s->n_emitters; e++) {
        const lie_emitter *em = &s->emitters[e];
        const lie_material *m = lie_scene_material(s, s->tri_material[em->first_tri]);
        for (uint32_t t = em->first_tri; t < em->first_tri + em->n_tris; t++) {
            const lie_vec3 *P = &s->tri_p[3 * (size_t)t];
            double a = s->tri_area[t] / ((double)k * k);
            for (int i = 0; i < k; i++)
                for (int j = 0; j < k; j++) {
                    float b1, b2;
                    lie_sample_triangle(((float)i + 0.5f) / (float)k, ((float)j + 0.5f) / (float)k, &b1, &b2);
                    float b0 = 1.0f - b1 - b2;
                    lie_vec3 q = lie_v3_add(lie_v3_add(lie_v3_scale(P[0], b0), lie_v3_scale(P[1], b1)),
                                            lie_v3_scale(P[2], b2));
                    double L = em->radiance[1];
                    if (m->emissive_tex >= 0) {
                        float tu, tv, rgba[4];
                        lie_scene_slot_uv(s, m, LIE_TEX_EMISSIVE, t, b1, b2, &tu, &tv);
                        lie_texture_sample(&s->textures[m->emissive_tex], tu, tv, rgba);
                        L *= rgba[1];
                    }
                    double dx = q.x - px, dy = q.y, dz = q.z - pz, d2 = dx * dx + dy * dy + dz * dz;
                    double c = dy / sqrt(d2); /* both cosines: the emitter faces -y, the floor +y */
                    sum += L * c * c / d2 * a;
                }
        }
    }
    return 0.5 / M_PI * sum;
}

/* One pixel looking straight down at floor point (px, 0, pz). */
static float render_point_with(const lie_scene *s, float px, float pz, lie_light_sampler_kind k, int n,
                               uint64_t seed, const lie_lights *lights)
{
    lie_error err;
    lie_rt *rt = NULL;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_camera cam;
    memset(&cam, 0, sizeof cam);
    cam.eye = lie_v3(px, 0.05f, pz);
    cam.forward = lie_v3(0, -1, 0);
    cam.up = lie_v3(0, 0, 1);
    cam.yfov = 0.001f;
    lie_render_options o = test_render_options(1, 1, n, 1);
    o.sampler = k;
    o.seed = seed;
    o.lights = lights;
    lie_frame *f = NULL;
    assert_int_equal(lie_render(s, rt, &cam, &o, &f, NULL, &err), LIE_OK);
    float g = f->rgb[1];
    lie_frame_destroy(f);
    lie_rt_destroy(rt);
    return g;
}

static float render_point(const lie_scene *s, float px, float pz, lie_light_sampler_kind k, int n, uint64_t seed)
{
    return render_point_with(s, px, pz, k, n, seed, NULL);
}

static void flatten(lie_scene *s)
{
    lie_error err;
    assert_int_equal(lie_scene_flatten(s, &err), LIE_OK);
}

/* 500 small emitters of random size and radiance in a 25 x 20 grid at
 * one height (so that none shadows another), over the floor: every
 * sampler's estimate is unbiased (the mean over seeds is the quadrature)
 * and the tree's is the least noisy. */
static void test_500_emitters_every_sampler_matches_quadrature(void **state)
{
    (void)state;
    lie_scene *s = floor_scene("500", 1.0f, -1);
    for (int k = 0; k < 4; k++) {
        lie_material m = lie_material_default();
        m.base_color[0] = m.base_color[1] = m.base_color[2] = 0.0f;
        m.metallic = 0.0f;
        m.emissive[0] = m.emissive[1] = m.emissive[2] = 0.5f + 3.0f * (float)k;
        assert_int_equal(lie_scene_add_material(s, &m), 2 + k);
    }
    uint64_t h = 12345;
    for (int i = 0; i < 500; i++) {
        h = lie_hash_u64x4(h, (uint64_t)i, 0, 0);
        float cx = -20.0f + 1.6f * (float)(i % 25) + 0.8f, cz = -20.0f + 2.0f * (float)(i / 25) + 1.0f;
        float r = 0.1f + 0.3f * lie_hash_to_unit(h << 12);
        float x = cx + (0.8f - r) * (2.0f * lie_hash_to_unit(h) - 1.0f), z = cz + (0.8f - r) * (2.0f * lie_hash_to_unit(h << 24) - 1.0f);
        char name[16];
        snprintf(name, sizeof name, "L%d", i);
        add_quad_m(s, name, x - r, x + r, z - r, z + r, 1.5f, 1, 2 + (int)(h >> 62));
    }
    flatten(s);
    assert_int_equal(s->n_emitters, 500);
    const double want = quadrature(s, 0.3f, -0.2f, 16);
    const lie_light_sampler_kind kinds[3] = {LIE_SAMPLER_TREE, LIE_SAMPLER_POWER, LIE_SAMPLER_UNIFORM};
    double spread[3];
    for (int k = 0; k < 3; k++) {
        double sum = 0.0, sq = 0.0;
        const int seeds = 24;
        for (int sd = 0; sd < seeds; sd++) {
            double v = render_point(s, 0.3f, -0.2f, kinds[k], 64, (uint64_t)sd + 1);
            sum += v;
            sq += v * v;
        }
        double mean = sum / seeds, sd_ = sqrt(fmax(sq / seeds - mean * mean, 0.0));
        spread[k] = sd_ / want;
        /* the mean of 24 renders within 4 standard errors, and 3% */
        /* the mean of 24 renders within 4 standard errors, and 2% */
        assert_true(fabs(mean - want) <= fmax(4.0 * sd_ / sqrt((double)seeds), 0.02 * want));
    }
    assert_true(spread[0] < spread[2]); /* the tree beats choosing alike */
    lie_scene_destroy(s);
}

/* One emitter of 1,000 triangles in a long strip just above the floor:
 * no closed form of a few triangles serves it; the budget's samples
 * converge to the quadrature next to it. */
static void test_strip_of_1000_triangles_matches_quadrature(void **state)
{
    (void)state;
    lie_scene *s = floor_scene("strip", 4.0f, -1);
    add_quad(s, "Strip", -10.0f, 10.0f, -0.05f, 0.05f, 0.3f, 500);
    flatten(s);
    assert_int_equal(s->n_emitters, 1);
    assert_int_equal((int)s->emitters[0].n_tris, 1000);
    const double want = quadrature(s, 0.4f, 0.25f, 4);
    double v = render_point(s, 0.4f, 0.25f, LIE_SAMPLER_TREE, 16384, 7);
    assert_true(fabs(v - want) <= 0.02 * want);
    lie_scene_destroy(s);
}

/* An emissive texture black but for one texel: its samples fall on the
 * lit texel (the area sampler's almost never do), and the estimate is the
 * quadrature's. */
static void test_one_lit_texel_matches_quadrature(void **state)
{
    (void)state;
    lie_scene *s = floor_scene("texel", 1.0f, 0);
    float *rgba = one_texture(s, 64, LIE_WRAP_CLAMP);
    for (int c = 0; c < 4; c++)
        rgba[(37 * 64 + 21) * 4 + c] = 50.0f;
    add_quad(s, "Panel", -1.0f, 1.0f, -1.0f, 1.0f, 1.0f, 1);
    flatten(s);
    assert_int_equal(s->n_emitters, 1);
    lie_texlight *tl = NULL;
    assert_int_equal(lie_texlight_create(s, 0, &tl), LIE_OK);
    assert_non_null(tl);
    /* the samples land where the texture is lit, or in cells next to it
     * whose lookups can reach it (where the bilinear lookup may be 0) */
    int lit = 0;
    double far = 0.0;
    for (int i = 0; i < 1024; i++) {
        lie_emitter_sample q;
        lie_texlight_sample(s, 0, tl, ((float)i + 0.5f) / 1024.0f, lie_radical_inverse2((uint32_t)i), &q);
        lit += q.le[1] > 0.0f;
        assert_true(q.inv_pdf > 0.0f);
        /* in texels from the lit one's centre */
        far = fmax(far, fmax(fabs((q.p.x + 1.0) * 32.0 - 21.5), fabs((q.p.z + 1.0) * 32.0 - 37.5)));
    }
    /* within a few texels of the lit one, the rest of the 64 x 64 take
     * none; a quarter or more where the light is (sampling by area, one in
     * a thousand: the 2 x 2 texels a bilinear lookup of it reaches) */
    assert_true(far <= 5.0);
    assert_true(lit >= 256);
    lie_texlight_destroy(tl);
    const double want = quadrature(s, 0.2f, 0.3f, 256);
    double v = render_point(s, 0.2f, 0.3f, LIE_SAMPLER_TREE, 4096, 3);
    assert_true(fabs(v - want) <= 0.01 * want);
    lie_scene_destroy(s);
}

/* Lights prepared without the textured emitters' distributions
 * (lie_lights_create_untextured, a viewer's first images): the emitter's
 * samples spread by area carry its texture's light, so the estimate is
 * still the quadrature's; they fit the scene, and not after an edit. */
static void test_untextured_lights_are_unbiased(void **state)
{
    (void)state;
    lie_scene *s = floor_scene("untextured", 1.0f, 0);
    float *rgba = one_texture(s, 16, LIE_WRAP_CLAMP);
    for (int i = 0; i < 256; i++)
        for (int c = 0; c < 4; c++)
            rgba[i * 4 + c] = (i / 16 + i % 16) % 3 == 0 ? 3.0f : 0.0f;
    add_quad(s, "Panel", -1.0f, 1.0f, -1.0f, 1.0f, 1.0f, 1);
    flatten(s);
    assert_int_equal(s->n_emitters, 1);
    lie_error err;
    lie_render_options o = test_render_options(1, 1, 4096, 1);
    lie_lights *l = NULL;
    assert_int_equal(lie_lights_create_untextured(s, &o, &l, &err), LIE_OK);
    assert_true(lie_lights_fit(l, s));
    const double want = quadrature(s, 0.2f, 0.3f, 256);
    double v = render_point_with(s, 0.2f, 0.3f, LIE_SAMPLER_TREE, 4096, 3, l);
    assert_true(want > 0.0);
    assert_true(fabs(v - want) <= 0.02 * want);
    s->hash ^= 1; /* as after an edit */
    assert_false(lie_lights_fit(l, s));
    lie_lights_destroy(l);
    lie_scene_destroy(s);
}

/* Systematic picks: the counts add up to n, each is floor or ceil of
 * n w / total, and a weight of 0 takes none. */
static void test_systematic_picks_follow_the_weights(void **state)
{
    (void)state;
    const float w[6] = {0.5f, 0.0f, 2.0f, 0.25f, 7.0f, 0.25f};
    const int ids[6] = {10, 11, 12, 13, 14, 15};
    lie_light_pick out[6];
    for (int n = 1; n <= 40; n += 13)
        for (double u = 0.0; u < 1.0; u += 0.0625) {
            int k = lie_light_pick_weights(w, ids, 6, 10.0, n, u, out), total = 0;
            for (int i = 0; i < k; i++) {
                int j = out[i].emitter - 10;
                assert_true(w[j] > 0.0f);
                double expect = n * w[j] / 10.0;
                assert_true(out[i].count >= (int)floor(expect) && out[i].count <= (int)ceil(expect));
                assert_float_equal(out[i].pmf, w[j] / 10.0f, 1e-6f);
                total += out[i].count;
            }
            assert_int_equal(total, n);
        }
}

/* The tree's importance bounds what a light can give: zero only behind
 * a one-sided emitter or beyond a spot's cone. */
static void test_light_bounds_cull_only_what_cannot_reach(void **state)
{
    (void)state;
    lie_scene *s = floor_scene("bounds", 1.0f, -1);
    add_quad(s, "Panel", -1.0f, 1.0f, -1.0f, 1.0f, 2.0f, 4);
    flatten(s);
    lie_light_bounds *b = NULL;
    assert_int_equal(lie_light_bounds_all(s, NULL, &b), LIE_OK);
    lie_vec3 up = lie_v3(0, 1, 0);
    assert_true(lie_light_importance(&b[0], lie_v3(0.3f, 0.0f, 0.1f), &up) > 0.0f); /* below it */
    assert_true(lie_light_importance(&b[0], lie_v3(5.0f, 1.99f, 0.0f), NULL) > 0.0f); /* level, beside it */
    /* behind it, outside its box's sphere (within, any direction may see it) */
    assert_float_equal(lie_light_importance(&b[0], lie_v3(0.0f, 4.0f, 0.0f), NULL), 0.0f, 0.0f);
    lie_vec3 down = lie_v3(0, -1, 0);
    assert_float_equal(lie_light_importance(&b[0], lie_v3(0.0f, 0.0f, 0.0f), &down), 0.0f, 0.0f); /* facing away */
    free(b);
    lie_scene_destroy(s);
}

/* Options of an older, smaller struct get the defaults for what they
 * lack; a size no default made is refused. */
static void test_render_options_of_an_older_size(void **state)
{
    (void)state;
    lie_scene *s = floor_scene("opts", 1.0f, -1);
    add_quad(s, "Panel", -1.0f, 1.0f, -1.0f, 1.0f, 2.0f, 1);
    flatten(s);
    lie_error err;
    lie_rt *rt = NULL;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_camera cam = lie_scene_default_camera(s);
    lie_render_options o = test_render_options(8, 8, 16, 1), old = o;
    old.size = offsetof(lie_render_options, sampler); /* before the light samplers */
    old.sampler = LIE_SAMPLER_PER_EMITTER;            /* past its size: not read */
    lie_frame *a = NULL, *b = NULL;
    assert_int_equal(lie_render(s, rt, &cam, &o, &a, NULL, &err), LIE_OK);
    assert_int_equal(lie_render(s, rt, &cam, &old, &b, NULL, &err), LIE_OK);
    assert_memory_equal(a->rgb, b->rgb, sizeof(float) * 3 * 64);
    o.size = 0;
    lie_frame *c = NULL;
    assert_int_equal(lie_render(s, rt, &cam, &o, &c, NULL, &err), LIE_ERR_ARG);
    assert_null(c);
    lie_frame_destroy(a);
    lie_frame_destroy(b);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

/* Point lights take one sample each at every point, apart from the
 * budget, while there are no more of them than samples: with a panel
 * beside them, two seeds differ only by the panel's share, so the point
 * lights' light is the same in both (the panel off: identical images);
 * with more point lights than samples, they are chosen by the sampler and
 * the mean over seeds is still their sum. */
static void add_point(lie_scene *s, const char *name, float x, float y, float z, float I)
{
    lie_light_def l;
    memset(&l, 0, sizeof l);
    l.type = LIE_LIGHT_POINT;
    l.color[0] = l.color[1] = l.color[2] = 1.0f;
    l.intensity = I;
    int li = lie_scene_add_light_def(s, &l);
    double t[3] = {x, y, z}, q[4] = {0, 0, 0, 1}, sc[3] = {1, 1, 1};
    lie_mat4 m = lie_mat4_from_trs(t, q, sc);
    assert_true(lie_scene_add_node(s, name, -1, &m, -1, -1, li) >= 0);
}

static void test_point_lights_apart_from_the_budget(void **state)
{
    (void)state;
    /* the exact light of point lights of intensity I at height h, offset
     * d along x from the floor point: 0.5/pi * I cos / r^2 */
    const float I[3] = {2.0f, 5.0f, 9.0f}, X[3] = {0.5f, -1.0f, 2.0f};
    double want = 0.0;
    for (int k = 0; k < 3; k++) {
        double r2 = X[k] * X[k] + 4.0, c = 2.0 / sqrt(r2);
        want += 0.5 / M_PI * I[k] * c / r2;
    }
    lie_scene *s = floor_scene("points", 0.0f, -1); /* a black panel: no light of its own */
    add_quad(s, "Panel", 3.0f, 4.0f, -0.5f, 0.5f, 2.0f, 1);
    for (int k = 0; k < 3; k++) {
        char name[16];
        snprintf(name, sizeof name, "P%d", k);
        add_point(s, name, X[k], 2.0f, 0.0f, I[k]);
    }
    flatten(s);
    /* 3 point lights, a budget of 4: each its own sample, whatever the seed */
    float a = render_point(s, 0.0f, 0.0f, LIE_SAMPLER_TREE, 4, 1), b = render_point(s, 0.0f, 0.0f, LIE_SAMPLER_TREE, 4, 2);
    assert_true(a == b);
    assert_true(fabs(a - want) <= 1e-4 * want);
    /* a budget of 2: the sampler shares it among the 3, unbiased */
    double sum = 0.0;
    const int seeds = 64;
    int differ = 0;
    for (int sd = 0; sd < seeds; sd++) {
        float v = render_point(s, 0.0f, 0.0f, LIE_SAMPLER_TREE, 2, (uint64_t)sd + 1);
        differ += v != a;
        sum += v;
    }
    assert_true(differ > 0);
    assert_true(fabs(sum / seeds - want) <= 0.03 * want);
    lie_scene_destroy(s);
}

/* A scene's lights prepared once (lie_lights_create) give the images
 * that frames preparing their own give, for a budgeted sampler with a
 * textured emitter, with closed forms on and off; prepared for another
 * scene state (its hash changed since), they are not used. */
static void test_prepared_lights_give_the_same_image(void **state)
{
    (void)state;
    lie_scene *s = floor_scene("prepared", 2.0f, 0);
    float *rgba = one_texture(s, 8, LIE_WRAP_REPEAT);
    for (int i = 0; i < 64; i += 3)
        for (int c = 0; c < 4; c++)
            rgba[i * 4 + c] = (float)(i % 5);
    add_quad(s, "Panel", -1.0f, 1.0f, -1.0f, 1.0f, 1.5f, 4);
    flatten(s);
    lie_error err;
    lie_rt *rt = NULL;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_camera cam = lie_scene_default_camera(s);
    const int budgets[2] = {4, 256};
    for (int b = 0; b < 2; b++) {
        lie_render_options o = test_render_options(16, 16, budgets[b], 2);
        lie_lights *l = NULL;
        assert_int_equal(lie_lights_create(s, &o, &l, &err), LIE_OK);
        assert_true(lie_lights_fit(l, s));
        lie_frame *a = NULL, *c = NULL, *d = NULL;
        assert_int_equal(lie_render(s, rt, &cam, &o, &a, NULL, &err), LIE_OK);
        o.lights = l;
        assert_int_equal(lie_render(s, rt, &cam, &o, &c, NULL, &err), LIE_OK);
        assert_memory_equal(a->rgb, c->rgb, sizeof(float) * 3 * 256);
        s->hash ^= 1; /* as after an edit */
        assert_false(lie_lights_fit(l, s));
        assert_int_equal(lie_render(s, rt, &cam, &o, &d, NULL, &err), LIE_OK);
        assert_memory_equal(a->rgb, d->rgb, sizeof(float) * 3 * 256);
        s->hash ^= 1;
        double sum = 0.0;
        for (int i = 0; i < 3 * 256; i++)
            sum += a->rgb[i];
        assert_true(sum > 0.0); /* the panel lights the floor */
        lie_frame_destroy(a);
        lie_frame_destroy(c);
        lie_frame_destroy(d);
        lie_lights_destroy(l);
    }
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_500_emitters_every_sampler_matches_quadrature),
        cmocka_unit_test(test_strip_of_1000_triangles_matches_quadrature),
        cmocka_unit_test(test_one_lit_texel_matches_quadrature),
        cmocka_unit_test(test_systematic_picks_follow_the_weights),
        cmocka_unit_test(test_light_bounds_cull_only_what_cannot_reach),
        cmocka_unit_test(test_render_options_of_an_older_size),
        cmocka_unit_test(test_point_lights_apart_from_the_budget),
        cmocka_unit_test(test_prepared_lights_give_the_same_image),
        cmocka_unit_test(test_untextured_lights_are_unbiased),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
