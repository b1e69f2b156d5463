/* SPDX-License-Identifier: Apache-2.0 */
/* Views in lib/lie (§4.3.3): pixel keys name the patch that holds a hit,
 * counts per patch add up, the hits' order does not matter, the pixel rule
 * refines what many pixels see, and adding views to an env equals
 * building for all of them. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lie.h"

/* The key's top digits are the path lie_patch_descend takes. */
static void test_key_digits_follow_the_patch_descent(void **state)
{
    (void)state;
    const float pts[][2] = {{0.1f, 0.1f}, {0.7f, 0.1f}, {0.1f, 0.8f}, {0.3f, 0.3f}, {0.26f, 0.49f}, {0.0f, 0.0f}};
    for (size_t i = 0; i < sizeof pts / sizeof pts[0]; i++) {
        uint32_t key = lie_pixels_key(pts[i][0], pts[i][1]);
        float b1 = pts[i][0], b2 = pts[i][1];
        for (int k = 0; k < LIE_PIXEL_LEVELS; k++)
            assert_int_equal((key >> (2 * (LIE_PIXEL_LEVELS - 1 - k))) & 3u, (uint32_t)lie_patch_descend(&b1, &b2));
    }
}

/* Hits of a patch are the sum of its children's; the order of the hits
 * given does not change the result. */
static void test_counts_add_up_and_ignore_order(void **state)
{
    (void)state;
    enum { N = 2000 };
    uint64_t *a = malloc(sizeof *a * N), *b = malloc(sizeof *b * N);
    assert_non_null(a);
    assert_non_null(b);
    uint64_t x = 88172645463325252ull;
    for (int i = 0; i < N; i++) {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        float u = (float)(x & 0xffff) / 65536.0f, v = (float)((x >> 16) & 0xffff) / 65536.0f;
        if (u + v > 1.0f) {
            u = 1.0f - u;
            v = 1.0f - v;
        }
        a[i] = (uint64_t)(x >> 40 & 3) << 32 | lie_pixels_key(u, v);
        b[N - 1 - i] = a[i];
    }
    lie_pixels *p = NULL, *q = NULL;
    lie_error err;
    assert_int_equal(lie_pixels_create(4, 4, a, N, &p, &err), LIE_OK);
    assert_int_equal(lie_pixels_create(4, 4, b, N, &q, &err), LIE_OK);
    assert_memory_equal(p->first, q->first, sizeof *p->first * 5);
    assert_memory_equal(p->key, q->key, sizeof *p->key * N);
    uint64_t total = 0;
    for (uint32_t t = 0; t < 4; t++) {
        assert_int_equal(lie_pixels_tri_hash(p, t), lie_pixels_tri_hash(q, t));
        lie_patch_path root = lie_patch_root();
        uint64_t h = lie_pixels_hits(p, t, root), sum = 0;
        total += h;
        for (int k = 0; k < 4; k++) {
            lie_patch_path c = lie_patch_child(root, k);
            uint64_t hc = lie_pixels_hits(p, t, c), sum2 = 0;
            sum += hc;
            for (int j = 0; j < 4; j++)
                sum2 += lie_pixels_hits(p, t, lie_patch_child(c, j));
            assert_int_equal(sum2, hc);
        }
        assert_int_equal(sum, h);
    }
    assert_int_equal(total, N);
    /* a hit on a triangle the scene does not have is refused */
    a[0] = (uint64_t)9 << 32;
    lie_pixels *bad = NULL;
    assert_int_equal(lie_pixels_create(4, 4, a, N, &bad, &err), LIE_ERR_ARG);
    assert_null(bad);
    lie_pixels_destroy(p);
    lie_pixels_destroy(q);
    free(a);
    free(b);
}

/* Pixels of cornell's whole image, from the scene's first camera, at a
 * size: 2 x 2 rays a pixel. */
static lie_pixels *cornell_pixels(const lie_scene *s, const lie_rt *rt, const lie_camera *cams, int n, int size)
{
    lie_pixels *px = NULL;
    lie_error err;
    assert_int_equal(lie_camera_pixels(s, rt, cams, n, size, size, 2, &px, &err), LIE_OK);
    return px;
}

static int same_env(const lie_env *a, const lie_env *b)
{
    size_t units = (size_t)a->n_tris * (size_t)a->n_clusters;
    return a->n_nodes == b->n_nodes && a->n_pool == b->n_pool &&
           memcmp(a->root, b->root, sizeof *a->root * units) == 0 &&
           memcmp(a->nodes, b->nodes, sizeof *a->nodes * a->n_nodes) == 0 &&
           (a->n_pool == 0 || memcmp(a->pool, b->pool, sizeof *a->pool * a->n_pool) == 0);
}

/* More pixels never make fewer nodes (the rule is monotone, which --into
 * relies on); adding a view gives the env of one build for both. */
static void test_more_pixels_refine_and_adding_a_view_equals_one_build(void **state)
{
    (void)state;
    lie_scene *s = NULL;
    lie_rt *rt = NULL;
    lie_error err;
    assert_int_equal(lie_scene_load(TEST_SCENES "/cornell.gltf", NULL, &s, &err), LIE_OK);
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_camera cams[2];
    assert_int_equal(lie_camera_parse(s, "0", &cams[0], &err), LIE_OK);
    assert_int_equal(lie_camera_parse(s, "eye=0.1,0.45,0.1,target=0.4,0,0.45", &cams[1], &err), LIE_OK);
    lie_build_params p = lie_build_params_default();
    p.samples = 16;
    p.max_samples = 64;
    p.min_patch = 1e-3f;
    p.max_blockers = 1;
    p.frames = 1;
    lie_pixels *small = cornell_pixels(s, rt, cams, 1, 24), *big = cornell_pixels(s, rt, cams, 1, 160);
    lie_env *es = NULL, *eb = NULL;
    lie_build_stats st;
    assert_int_equal(lie_env_build_views(s, rt, &p, small, NULL, &es, &st, &err), LIE_OK);
    uint64_t pixel_stops = st.splits_pixels;
    assert_true(pixel_stops > 0);
    assert_int_equal(lie_env_build_views(s, rt, &p, big, NULL, &eb, &st, &err), LIE_OK);
    assert_true(eb->n_nodes > es->n_nodes);
    lie_env_destroy(es);
    lie_env_destroy(eb);
    lie_pixels_destroy(small);
    lie_pixels_destroy(big);

    lie_pixels *a = cornell_pixels(s, rt, cams, 1, 48), *ab = cornell_pixels(s, rt, cams, 2, 48);
    lie_env *ea = NULL, *eab = NULL;
    assert_int_equal(lie_env_build_views(s, rt, &p, a, NULL, &ea, &st, &err), LIE_OK);
    assert_int_equal(lie_env_build_views(s, rt, &p, ab, NULL, &eab, &st, &err), LIE_OK);
    lie_add_stats as;
    assert_int_equal(lie_env_add_views(ea, s, rt, a, ab, 2, &st, &as, &err), LIE_OK);
    assert_true(same_env(ea, eab));
    assert_true(as.units_kept > 0);
    assert_int_equal(as.units_kept + as.units_refined + as.units_new, (uint64_t)s->n_tris * (uint64_t)s->n_clusters);
    /* views that lose pixels are refused */
    assert_int_equal(lie_env_add_views(ea, s, rt, ab, a, 2, &st, &as, &err), LIE_ERR_ARG);
    lie_env_destroy(ea);
    lie_env_destroy(eab);
    lie_pixels_destroy(a);
    lie_pixels_destroy(ab);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

/* Hits spread over triangle tri: n of them, at points inside it. */
static size_t put_hits(uint64_t *h, size_t at, uint32_t tri, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        float u = (float)((i * 37) % 97) / 200.0f, v = (float)((i * 53) % 89) / 200.0f;
        h[at + i] = (uint64_t)tri << 32 | lie_pixels_key(u, v);
    }
    return at + n;
}

/* Hits enough for the cost model to build a unit of this share: pixels x
 * light_samples x share x ns_ray over the frames at least the first round
 * of segments (lie_unit_pays), with 4 hits a pixel. */
static double pays_from(const lie_build_params *p, double share)
{
    return 4.0 * (double)p->samples * (double)p->ns_segment /
           ((double)p->frames * (double)p->light_samples * share * (double)p->ns_ray);
}

/* A unit that cannot pay for its build is left unbuilt: a frame's light
 * samples are shared among the emitters by their unshadowed light, so
 * over 10 frames the dimmer emitter's share of a small triangle's pixels
 * saves fewer shadow rays than its unit's first round of segments costs,
 * where the brighter one's pays.  Shares are fractions of the light at
 * the triangle, and a unit its emitter cannot reach (unlit) costs nothing
 * and is always built.  With --frames 0 every seen unit is built.  Adding
 * the pixels that make the dimmer unit pay builds it, as one build for all
 * the pixels does. */
static void test_units_that_cannot_pay_are_left_unbuilt(void **state)
{
    (void)state;
    lie_scene *s = NULL;
    lie_rt *rt = NULL;
    lie_error err;
    assert_int_equal(lie_scene_load("tests/data/gltf/bent_light.gltf", NULL, &s, &err), LIE_OK);
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    assert_int_equal(s->n_clusters, 2);
    lie_build_params p = lie_build_params_default();
    p.frames = 10;
    /* a triangle both emitters light, one far more than the other */
    float far = lie_pair_ray_far(s);
    double share[2], best = 0.0;
    uint32_t a = UINT32_MAX;
    int dim = 0, unlit = 0;
    for (uint32_t t = 0; t < s->n_tris; t++) {
        if (s->tri_emitter[t] >= 0)
            continue;
        lie_unit_shares(s, t, far, share);
        for (int c = 0; c < 2; c++) {
            assert_true(share[c] == -1.0 || (share[c] >= 0.0 && share[c] <= 1.0));
            unlit += share[c] < 0.0;
        }
        if (share[0] > 0.0 && share[1] > 0.0)
            assert_true(fabs(share[0] + share[1] - 1.0) < 1e-9);
        double r = share[0] > 0.0 && share[1] > 0.0 ? (share[0] < share[1] ? share[1] / share[0] : share[0] / share[1]) : 0.0;
        if (r > best) {
            best = r;
            a = t;
            dim = share[0] < share[1] ? 0 : 1;
        }
    }
    assert_true(a != UINT32_MAX && best > 4.0);
    assert_true(unlit > 0); /* the spot's cone leaves triangles out */
    lie_unit_shares(s, a, far, share);
    /* pixels between the two thresholds, then enough for both */
    double lo = pays_from(&p, share[1 - dim]), hi = pays_from(&p, share[dim]);
    size_t few = (size_t)ceil(2.0 * lo), many = (size_t)ceil(hi) + 4;
    assert_true((double)few < hi);
    uint64_t *h = malloc(sizeof *h * (many + 1));
    assert_non_null(h);
    size_t n = put_hits(h, 0, a, (int)few);
    lie_pixels *px = NULL, *more = NULL;
    assert_int_equal(lie_pixels_create(s->n_tris, 4, h, n, &px, &err), LIE_OK);
    n = put_hits(h, 0, a, (int)many);
    assert_int_equal(lie_pixels_create(s->n_tris, 4, h, n, &more, &err), LIE_OK);
    lie_build_stats st;
    memset(&st, 0, sizeof st);
    lie_env *e = NULL, *e0 = NULL, *em = NULL;
    assert_int_equal(lie_env_build_views(s, rt, &p, px, NULL, &e, &st, &err), LIE_OK);
    const size_t nc = (size_t)s->n_clusters;
#define ROOT_CLS(env, t, c) ((env)->nodes[(env)->root[(size_t)(t) * nc + (size_t)(c)]].cls)
    assert_int_equal(ROOT_CLS(e, a, dim), LIE_CLASS_NONE);
    assert_int_not_equal(ROOT_CLS(e, a, 1 - dim), LIE_CLASS_NONE);
    assert_int_equal(st.units_unpaid, 1);
    assert_int_equal(st.units_unseen, (uint64_t)s->n_tris * nc - 2);
    p.frames = 0;
    assert_int_equal(lie_env_build_views(s, rt, &p, px, NULL, &e0, &st, &err), LIE_OK);
    assert_int_not_equal(ROOT_CLS(e0, a, dim), LIE_CLASS_NONE);
    p.frames = 10;
    assert_int_equal(lie_env_build_views(s, rt, &p, more, NULL, &em, &st, &err), LIE_OK);
    assert_int_not_equal(ROOT_CLS(em, a, dim), LIE_CLASS_NONE);
    lie_add_stats as;
    assert_int_equal(lie_env_add_views(e, s, rt, px, more, 2, &st, &as, &err), LIE_OK);
    assert_true(as.units_new >= 1);
    assert_true(same_env(e, em));
#undef ROOT_CLS
    lie_env_destroy(e);
    lie_env_destroy(e0);
    lie_env_destroy(em);
    lie_pixels_destroy(px);
    lie_pixels_destroy(more);
    free(h);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_key_digits_follow_the_patch_descent),
        cmocka_unit_test(test_counts_add_up_and_ignore_order),
        cmocka_unit_test(test_more_pixels_refine_and_adding_a_view_equals_one_build),
        cmocka_unit_test(test_units_that_cannot_pay_are_left_unbuilt),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
