/* SPDX-License-Identifier: Apache-2.0 */
/* lib/shade bitmask: all samples at once (bitmask.h) against testing every
 * sample one by one: the same bits, on random and degenerate forms, and
 * through the LIE oracle on scenes holding the degenerate blockers any
 * shadow method must survive; and its Lambert estimate. */
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

static uint64_t rng_next(uint64_t *x)
{
    *x ^= *x << 13, *x ^= *x >> 7, *x ^= *x << 17;
    return *x;
}
static float rnd(uint64_t *x) { return (float)(rng_next(x) >> 40) / (float)(1u << 24); }

/* A planar pattern of n samples: a Hammersley set over a w x h box, or
 * over a triangle (half the box) when tri. */
static void pattern(lie_light_samples *ls, int n, float w, float h, int tri)
{
    assert_int_equal(lie_light_samples_alloc(ls, n), LIE_OK);
    ls->n = n;
    ls->planar = 1;
    ls->uniform = 1;
    ls->pu[0] = 1.0f, ls->pv[2] = 1.0f, ls->pn[1] = -1.0f, ls->po[1] = 2.0f;
    ls->smin = ls->tmin = INFINITY, ls->smax = ls->tmax = -INFINITY;
    for (int i = 0; i < n; i++) {
        float u = ((float)i + 0.5f) / (float)n, v = lie_radical_inverse2((uint32_t)i);
        if (tri && u + v > 1.0f)
            u = 1.0f - u, v = 1.0f - v;
        ls->s[i] = w * (u - 0.5f), ls->t[i] = h * (v - 0.5f);
        ls->smin = fminf(ls->smin, ls->s[i]), ls->smax = fmaxf(ls->smax, ls->s[i]);
        ls->tmin = fminf(ls->tmin, ls->t[i]), ls->tmax = fmaxf(ls->tmax, ls->t[i]);
        ls->r[i] = ls->g[i] = ls->b[i] = 1.0f / (float)n;
    }
    for (int i = n; i < lie_light_samples_padded(ls); i++)
        ls->s[i] = ls->t[i] = NAN;
}

static int bit(const uint64_t *m, int i) { return (int)((m[i >> 6] >> (i & 63)) & 1u); }

static int in_forms(const float *f, int nf, float s, float t)
{
    int in = 1;
    for (int j = 0; j < nf; j++)
        in &= fmaf(t, f[3 * j + 2], fmaf(s, f[3 * j + 1], f[3 * j])) >= 0.0f;
    return in;
}

/* An edge form through (x0, y0) and (x1, y1), inside to its left. */
static void edge(float *f, float x0, float y0, float x1, float y1)
{
    f[1] = -(y1 - y0), f[2] = x1 - x0;
    f[0] = -(f[1] * x0 + f[2] * y0);
}

/* Random triangles (large, small, outside, thin), edges through samples,
 * axis-aligned edges on sample coordinates, a form that is zero: the
 * mask is exactly what the per-sample test gives. */
static void test_bitmask_cone_matches_every_sample(void **state)
{
    (void)state;
    const int sizes[] = {1, 7, 8, 63, 64, 65, 100, 512, 1000, 4096};
    uint64_t x = 0x9e3779b97f4a7c15ull;
    long set = 0, total = 0;
    for (size_t k = 0; k < sizeof sizes / sizeof *sizes; k++)
        for (int tri = 0; tri < 2; tri++) {
            lie_light_samples ls;
            pattern(&ls, sizes[k], 1.5f, 0.7f, tri);
            lie_bitmask *bm = NULL;
            assert_int_equal(lie_bitmask_create(&ls, &bm), LIE_OK);
            assert_non_null(bm);
            assert_int_equal(bm->n, sizes[k]);
            const lie_light_samples *q = &bm->ls;
            /* the same samples, reordered: the sums agree */
            double a = 0.0, b = 0.0;
            for (int i = 0; i < ls.n; i++)
                a += ls.s[i] + 3.0 * ls.t[i], b += q->s[i] + 3.0 * q->t[i];
            assert_true(fabs(a - b) < 1e-6 * ls.n);
            uint64_t mask[80];
            for (int c = 0; c < 300; c++) {
                float f[9];
                const int kind = c % 6;
                float sc = kind == 1 ? 0.05f : kind == 2 ? 3.0f : 1.0f;
                float cx = 2.0f * rnd(&x) - 1.0f, cy = rnd(&x) - 0.5f, px[3], py[3];
                for (int v = 0; v < 3; v++)
                    px[v] = cx + sc * (rnd(&x) - 0.5f), py[v] = cy + sc * (rnd(&x) - 0.5f);
                if (kind == 3) { /* vertices on samples: edges through them */
                    for (int v = 0; v < 3; v++) {
                        int i = (int)(rng_next(&x) % (uint64_t)ls.n);
                        px[v] = ls.s[i], py[v] = ls.t[i];
                    }
                }
                if (kind == 4) { /* a thin sliver */
                    px[2] = px[0] + 1e-4f * (px[1] - px[0]), py[2] = py[0] + 1e-4f * (py[1] - py[0]) + 1e-5f;
                }
                float area = (px[1] - px[0]) * (py[2] - py[0]) - (py[1] - py[0]) * (px[2] - px[0]);
                for (int v = 0; v < 3; v++) {
                    int u = area >= 0.0f ? (v + 1) % 3 : (v + 2) % 3;
                    edge(f + 3 * v, px[v], py[v], px[u], py[u]);
                }
                if (kind == 5) { /* axis-aligned edges on a sample's coordinates, and a zero form */
                    int i = (int)(rng_next(&x) % (uint64_t)ls.n);
                    float g[9] = {-ls.s[i], 1.0f, 0.0f, ls.t[i], 0.0f, -1.0f, 0.0f, 0.0f, 0.0f};
                    memcpy(f, g, sizeof g);
                }
                memset(mask, 0xa5, sizeof mask);
                memset(mask, 0, sizeof *mask * (size_t)bm->n_words);
                lie_bitmask_cone(bm, f, mask);
                for (int i = 0; i < bm->n; i++) {
                    assert_int_equal(bit(mask, i), in_forms(f, 3, q->s[i], q->t[i]));
                    set += bit(mask, i);
                }
                total += bm->n;
                for (int i = bm->n; i < 64 * bm->n_words; i++)
                    assert_int_equal(bit(mask, i), 0); /* no padding bit */
                /* OR-ing keeps what was set */
                uint64_t before[80];
                memcpy(before, mask, sizeof before);
                float g[9];
                edge(g, -1.0f, -1.0f, 1.0f, -1.0f);
                edge(g + 3, 1.0f, -1.0f, 0.0f, 1.0f);
                edge(g + 6, 0.0f, 1.0f, -1.0f, -1.0f);
                lie_bitmask_cone(bm, g, mask);
                for (int i = 0; i < bm->n; i++)
                    assert_int_equal(bit(mask, i), bit(before, i) | in_forms(g, 3, q->s[i], q->t[i]));
            }
            lie_bitmask_destroy(bm);
            lie_light_samples_free(&ls);
        }
    assert_true(set > total / 50 && set < total / 2); /* the cases cover and miss samples */
}

/* A blocker reaching the emitter's plane: blocked where the depth form
 * g >= 0, and the flag where some sample in the cone has g < 0 < g2. */
static void test_bitmask_depth_forms_match_every_sample(void **state)
{
    (void)state;
    uint64_t x = 0x1234567ull;
    int flagged = 0, cases = 0;
    for (int n = 100; n <= 2100; n += 500) {
        lie_light_samples ls;
        pattern(&ls, n, 1.0f, 1.0f, 0);
        lie_bitmask *bm = NULL;
        assert_int_equal(lie_bitmask_create(&ls, &bm), LIE_OK);
        const lie_light_samples *q = &bm->ls;
        uint64_t mask[40];
        for (int c = 0; c < 300; c++, cases++) {
            float f[15];
            float px[3], py[3];
            for (int v = 0; v < 3; v++)
                px[v] = 1.6f * (rnd(&x) - 0.5f), py[v] = 1.6f * (rnd(&x) - 0.5f);
            float area = (px[1] - px[0]) * (py[2] - py[0]) - (py[1] - py[0]) * (px[2] - px[0]);
            for (int v = 0; v < 3; v++) {
                int u = area >= 0.0f ? (v + 1) % 3 : (v + 2) % 3;
                edge(f + 3 * v, px[v], py[v], px[u], py[u]);
            }
            /* g and g2: two nearby lines, g2 >= g where the hit is
             * between the depth bounds; sometimes one sign throughout */
            float a = rnd(&x) * 6.28f, off = rnd(&x) - 0.5f, gap = c % 3 == 0 ? 0.0f : 0.2f * rnd(&x);
            f[9] = off, f[10] = cosf(a), f[11] = sinf(a);
            f[12] = off + gap, f[13] = f[10], f[14] = f[11];
            if (c % 7 == 0)
                f[9] = 5.0f, f[12] = 6.0f; /* short of the plane everywhere */
            memset(mask, 0, sizeof *mask * (size_t)bm->n_words);
            int unsure = lie_bitmask_cone_depth(bm, f, mask);
            int want_unsure = 0;
            for (int i = 0; i < bm->n; i++) {
                float s = q->s[i], t = q->t[i];
                int in = in_forms(f, 3, s, t);
                float g = fmaf(t, f[11], fmaf(s, f[10], f[9])), g2 = fmaf(t, f[14], fmaf(s, f[13], f[12]));
                assert_int_equal(bit(mask, i), in & (g >= 0.0f));
                want_unsure |= in & (g < 0.0f) & (g2 > 0.0f);
            }
            assert_int_equal(unsure != 0, want_unsure);
            flagged += want_unsure;
        }
        lie_bitmask_destroy(bm);
        lie_light_samples_free(&ls);
    }
    assert_true(flagged > 0 && flagged < cases);
}

/* ---- through the oracle, on scenes ----------------------------------------- */

/* The degenerate blockers of issue 12, one scene:
 *  - a square at y = 1 of half the light's size, two triangles sharing an
 *    edge and two vertices: from points on the axis its shadow's edges lie
 *    on the light's edges;
 *  - a slanted wall crossing the tangent plane of the points below it;
 *  - a triangle touching the light's edge, and one reaching its plane;
 *  - a triangle in the plane x = 0, which points at x = 0 see edge-on
 *    (a projection of zero area);
 *  - a triangle in the light's plane, beside it. */
static const float degenerate[] = {
    -0.25f, 1, -0.25f, 0.25f, 1, -0.25f, 0.25f, 1, 0.25f, /* square, first half */
    -0.25f, 1, -0.25f, 0.25f, 1, 0.25f,  -0.25f, 1, 0.25f, /* second half: shared vertices */
    -0.3f, -0.5f, -2.0f, -0.3f, -0.5f, 2.0f, 0.3f, 0.9f, 2.0f, /* slanted wall */
    0.5f, 2.0f, 0.1f, 0.8f, 1.2f, 0.3f, 0.3f, 1.4f, -0.2f, /* touching the light's edge */
    -0.4f, 2.3f, 0.0f, -0.2f, 1.5f, 0.4f, 0.1f, 1.7f, -0.4f, /* through the light's plane */
    0.0f, 0.8f, -0.3f, 0.0f, 1.6f, 0.2f, 0.0f, 1.2f, 0.4f, /* in the plane x = 0 */
    0.7f, 2.0f, -0.2f, 1.0f, 2.0f, 0.2f, 0.8f, 2.0f, 0.3f, /* in the light's plane, beside it */
};
enum { NDEG = (int)(sizeof degenerate / sizeof *degenerate / 9) };

typedef struct tally {
    long pairs, fallbacks, samples, off_embree;
} tally;

static void oracle_case(int two_sided, int n, tally *tl)
{
    oracle_fixture fx;
    oracle_fixture_init(&fx, square_light_and_blockers(1.0f, 2.0f, two_sided, degenerate, NDEG), n);
    const lie_vis_oracle *orc = fx.orc;
    const lie_bitmask *bm = fx.bm;
    lie_rt *rt = fx.rt;
    /* every triangle, the light's own two included */
    uint32_t blockers[NDEG + 2];
    for (int k = 0; k < NDEG + 2; k++)
        blockers[k] = (uint32_t)k;
    uint32_t *occ = malloc(sizeof *occ * (size_t)(n + 16));
    float *dx = malloc(sizeof(float) * 3 * (size_t)(n + 16)), *dy = dx + n + 16, *dz = dy + n + 16;
    uint64_t mask[64];
    enum { STRIDE = 32 };
    static float work[LIE_BLOCKER_WORK * STRIDE];
    static uint32_t kind[STRIDE];
    assert_non_null(occ);
    assert_non_null(dx);
    /* points on a grid through the axis (x = 0, z = 0), below the light,
     * in its plane (edge-on), and above it (its back) */
    const float heights[6] = {1e-4f, 0.7f, 1.5f, 1.97f, 2.0f, 2.6f};
    for (int gy = 0; gy < 6; gy++)
        for (int gx = 0; gx < 9; gx++)
            for (int gz = 0; gz < 9; gz++) {
                lie_vec3 o = lie_v3(-1.2f + 0.3f * (float)gx, heights[gy], -1.2f + 0.3f * (float)gz);
                const float eps = 1e-4f;
                lie_shadow_query qm = {o, eps, &bm->ls, n, 0, dx, dy, dz, work, kind, STRIDE};
                int ok = orc->occluded_mask(orc->ctx, blockers, NDEG + 2, &qm, bm, mask);
                lie_shadow_query qs = {o, eps, &bm->ls, n, 0, dx, dy, dz, work, kind, STRIDE};
                orc->occluded(orc->ctx, blockers, NDEG + 2, &qs, occ);
                tl->pairs++;
                if (!ok) {
                    tl->fallbacks++;
                    continue;
                }
                lie_shadow_query_segments(&qs);
                for (int i = 0; i < n; i++) {
                    assert_int_equal(bit(mask, i), occ[i] != 0); /* the same bits as the per-sample path */
                    int emb = lie_rt_occluded(rt, o, lie_v3(dx[i], dy[i], dz[i]), 0.0f, 1.0f);
                    tl->off_embree += emb != bit(mask, i);
                    tl->samples++;
                }
            }
    free(occ);
    free(dx);
    oracle_fixture_free(&fx);
}

static void test_bitmask_oracle_degenerate_blockers(void **state)
{
    (void)state;
    for (int two_sided = 0; two_sided < 2; two_sided++)
        for (int n = 64; n <= 1024; n *= 4) {
            tally tl = {0, 0, 0, 0};
            oracle_case(two_sided, n, &tl);
            print_message("bitmask oracle, %s, %d samples: %ld points, %ld answered in 3D, %ld samples, "
                          "%ld off Embree\n",
                          two_sided ? "two-sided" : "one-sided", n, tl.pairs, tl.fallbacks, tl.samples,
                          tl.off_embree);
            assert_true(tl.fallbacks < tl.pairs / 2);
            assert_true(tl.off_embree * 1000 <= tl.samples);
        }
}

/* The Lambert estimate: nothing blocked is the closed form; everything,
 * nothing; otherwise the closed form less the blocked samples' part (few
 * blocked) or the visible samples' part (most). */
static void test_bitmask_lambert_estimate(void **state)
{
    (void)state;
    const int n = 1000;
    lie_light_samples ls;
    pattern(&ls, n, 1.0f, 1.0f, 0);
    lie_bitmask *bm = NULL;
    assert_int_equal(lie_bitmask_create(&ls, &bm), LIE_OK);
    const lie_vec3 o = lie_v3(0.1f, 0.0f, 0.2f), up = lie_v3(0, 1, 0);
    lie_planar_lambert P;
    assert_true(lie_planar_lambert_setup(&bm->ls, o, up, up, 0, &P));
    uint64_t mask[16];
    memset(mask, 0, sizeof mask);
    const double omega = 0.5, area = 1.0;
    assert_true(lie_bitmask_lambert(bm, &P, mask, omega, area) == omega);
    for (int w = 0; w < bm->n_words; w++)
        mask[w] = ~0ull;
    mask[bm->n_words - 1] = bm->last;
    assert_true(lie_bitmask_all(bm, mask));
    assert_true(lie_bitmask_lambert(bm, &P, mask, omega, area) == 0.0);
    uint64_t x = 77;
    for (int frac = 1; frac < 10; frac += 3) {
        memset(mask, 0, sizeof mask);
        double gb = 0.0, gv = 0.0;
        int nb = 0;
        for (int i = 0; i < n; i++) {
            double g = lie_planar_lambert_g(P, bm->ls.s[i], bm->ls.t[i]);
            if (rng_next(&x) % 10 < (uint64_t)frac) {
                mask[i >> 6] |= 1ull << (i & 63);
                gb += g, nb++;
            } else {
                gv += g;
            }
        }
        double want = 2 * nb <= n ? omega - area / n * gb : area / n * gv;
        double got = lie_bitmask_lambert(bm, &P, mask, omega, area);
        assert_true(fabs(got - want) <= 1e-5 * omega);
        assert_false(lie_bitmask_all(bm, mask));
    }
    lie_bitmask_destroy(bm);
    lie_light_samples_free(&ls);
}

/* The order is a function of the pattern: created twice, the same; and
 * each group of 8 lies in a box much smaller than the pattern's. */
static void test_bitmask_order_is_deterministic_and_compact(void **state)
{
    (void)state;
    lie_light_samples ls;
    pattern(&ls, 4096, 1.0f, 1.0f, 0);
    lie_bitmask *a = NULL, *b = NULL;
    assert_int_equal(lie_bitmask_create(&ls, &a), LIE_OK);
    assert_int_equal(lie_bitmask_create(&ls, &b), LIE_OK);
    assert_memory_equal(a->ls.s, b->ls.s, sizeof(float) * 4096);
    assert_memory_equal(a->ls.t, b->ls.t, sizeof(float) * 4096);
    assert_int_equal(a->levels, 3); /* 512 groups of 8, 64 of 64, 8 of 512 */
    double sum = 0.0;
    const size_t st = a->box_stride[1];
    for (int g = 0; g < a->n_groups[1]; g++)
        sum += (double)(a->box[1][st + g] - a->box[1][g]) * (a->box[1][3 * st + g] - a->box[1][2 * st + g]);
    assert_true(sum / a->n_groups[1] < 4.0 * 8.0 / 4096.0); /* about the area 8 samples cover */
    lie_bitmask_destroy(a);
    lie_bitmask_destroy(b);
    lie_light_samples ls2 = ls;
    ls2.planar = 0;
    assert_int_equal(lie_bitmask_create(&ls2, &a), LIE_OK);
    assert_null(a); /* not planar: no bitmask */
    lie_light_samples_free(&ls);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bitmask_cone_matches_every_sample),
        cmocka_unit_test(test_bitmask_depth_forms_match_every_sample),
        cmocka_unit_test(test_bitmask_oracle_degenerate_blockers),
        cmocka_unit_test(test_bitmask_lambert_estimate),
        cmocka_unit_test(test_bitmask_order_is_deterministic_and_compact),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
