/* SPDX-License-Identifier: Apache-2.0 */
/* lib/shade/ltc: polygon integrals of the glTF BRDF by linearly transformed
 * cosines, against closed forms and against Monte Carlo of lib/shade's own
 * BRDF (tests/unit/ltc_mc.h).
 *
 * Tolerances are what the method gives, measured (`make ltc-bench`), not
 * what the test would like: an LTC is a 4-parameter fit of a lobe, exact
 * only for the cosine; its error lives in the lobe's shape, so it is
 * relative to the polygon's integral where a polygon holds much of the
 * lobe and relative to the lobe's whole (hemisphere) integral H in the
 * tails.  F varies across the lobe at grazing views; the Schlick-weighted
 * part's own LTC (ltc.h) keeps that from adding much. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "ltc_mc.h"

#define MC_N 16384

static const float white[3] = {1.0f, 1.0f, 1.0f}, grey[3] = {0.5f, 0.5f, 0.5f};

static double sum3(const float v[3]) { return (double)v[0] + v[1] + v[2]; }
static double sum3d(const double v[3]) { return v[0] + v[1] + v[2]; }

/* Lambert: the edge sum is exact.  A w x h rectangle at height c with a
 * corner above the point has the closed-form form factor (Howell's
 * catalogue, C-11): F = 1/(2 pi) [X/sqrt(1+X^2) atan(Y/sqrt(1+X^2)) +
 * Y/sqrt(1+Y^2) atan(X/sqrt(1+Y^2))], X = w/c, Y = h/c; the diffuse
 * integral is c_diff F. */
static void test_ltc_lambert_rectangle_matches_closed_form(void **state)
{
    (void)state;
    static const float dims[][3] = {{1, 1, 1}, {0.1f, 3, 2}, {5, 0.5f, 0.25f}, {0.01f, 0.02f, 1}};
    for (size_t i = 0; i < sizeof dims / sizeof *dims; i++) {
        double w = dims[i][0], h = dims[i][1], c = dims[i][2];
        double X = w / c, Y = h / c;
        double F = (X / sqrt(1 + X * X) * atan(Y / sqrt(1 + X * X)) + Y / sqrt(1 + Y * Y) * atan(X / sqrt(1 + Y * Y))) /
                   (2 * M_PI);
        lie_vec3 q[4] = {lie_v3(0, 0, (float)c), lie_v3((float)w, 0, (float)c), lie_v3((float)w, (float)h, (float)c),
                         lie_v3(0, (float)h, (float)c)};
        lie_ltc_shading sh;
        lie_ltc_shading_lambert(lie_v3(0, 0, 1), grey, &sh);
        float out[3];
        lie_ltc_polygon(&sh, q, 4, out);
        assert_float_equal(out[1], 0.5 * F, 2e-4 * F);
        assert_float_equal(lie_ltc_integrate(NULL, q, 4), F, 2e-4 * F);
    }
}

/* |LTC - MC| <= rel * MC + abs * H over every polygon, H the hemisphere
 * integral. */
static void check_against_mc(float metallic, const float *base, const float *rough, int n_rough,
                             const float *angles, int n_angles, double rel, double abs_h)
{
    const lie_ltc_table *T = lie_ltc_table_default();
    for (int i = 0; i < n_rough; i++)
        for (int a = 0; a < n_angles; a++) {
            lie_surface sf = ltc_mc_surface(lie_v3(0, 0, 1), ltc_view(angles[a]), rough[i], metallic, base);
            lie_ltc_shading sh;
            lie_ltc_shading_from_surface(T, &sf, &sh);
            lie_vec3 sky[4], p[5][4];
            int nv[5];
            ltc_sky(sky);
            double hemi[3];
            ltc_mc_polygon(&sf, sky, 4, MC_N, hemi);
            double H = sum3d(hemi);
            ltc_polygons(angles[a], p, nv);
            for (int k = 0; k < 5; k++) {
                double mc[3];
                float got[3];
                ltc_mc_polygon(&sf, p[k], nv[k], MC_N, mc);
                lie_ltc_polygon(&sh, p[k], nv[k], got);
                double ref = sum3d(mc), err = fabs(sum3(got) - ref);
                if (err > rel * ref + abs_h * H)
                    fail_msg("roughness %.2f, view %.0f deg, polygon %d: LTC %.6g, MC %.6g (H %.6g)",
                             (double)rough[i], (double)angles[a], k, sum3(got), ref, H);
            }
        }
}

/* Specular lobe alone (F = 1): measured worst 5.1% relative on polygons
 * holding >= 10% of H and 1.9% of H anywhere, up to 60 deg. */
static void test_ltc_specular_matches_monte_carlo(void **state)
{
    (void)state;
    static const float rough[] = {0.1f, 0.25f, 0.5f, 0.75f, 1.0f};
    static const float angles[] = {0.0f, 30.0f, 60.0f};
    check_against_mc(1.0f, white, rough, 5, angles, 3, 0.06, 0.02);
}

/* Dielectric (Fresnel-weighted diffuse + specular, the Schlick-weighted
 * part with its own LTC): measured worst 2.3% relative on the bright
 * polygons up to 60 deg, 7.6% at 75 deg (the paper's scalar split alone:
 * 8.2% and 24%, `make ltc-bench`). */
static void test_ltc_dielectric_matches_monte_carlo(void **state)
{
    (void)state;
    static const float rough[] = {0.1f, 0.25f, 0.5f, 0.75f};
    static const float angles[] = {0.0f, 30.0f, 60.0f};
    check_against_mc(0.0f, grey, rough, 4, angles, 3, 0.04, 0.01);
    static const float grazing[] = {75.0f};
    check_against_mc(0.0f, grey, rough, 4, grazing, 1, 0.10, 0.02);
}

/* A coloured metal: f0 differs per channel, so both specular LTCs count. */
static void test_ltc_coloured_metal_matches_monte_carlo(void **state)
{
    (void)state;
    static const float gold[3] = {1.0f, 0.78f, 0.34f};
    static const float rough[] = {0.1f, 0.3f, 0.6f};
    static const float angles[] = {0.0f, 45.0f, 70.0f};
    check_against_mc(1.0f, gold, rough, 3, angles, 3, 0.08, 0.02);
}

/* A polygon covering the hemisphere gives the directional albedo: the
 * fitted distributions' mass below the shading horizon is folded into the
 * norms, so only the norms' own accuracy (16384 samples in the fit) and
 * the table's interpolation remain; grazing views included. */
static void test_ltc_hemisphere_is_directional_albedo(void **state)
{
    (void)state;
    static const float rough[] = {0.05f, 0.2f, 0.45f, 0.7f, 0.95f};
    static const float angles[] = {0.0f, 45.0f, 70.0f, 85.0f};
    const lie_ltc_table *T = lie_ltc_table_default();
    for (int m = 0; m < 2; m++)
        for (size_t i = 0; i < sizeof rough / sizeof *rough; i++)
            for (size_t a = 0; a < sizeof angles / sizeof *angles; a++) {
                lie_surface sf = ltc_mc_surface(lie_v3(0, 0, 1), ltc_view(angles[a]), rough[i], (float)m,
                                                m ? white : grey);
                lie_vec3 sky[4];
                ltc_sky(sky);
                double mc[3];
                ltc_mc_polygon(&sf, sky, 4, MC_N, mc);
                lie_ltc_shading sh;
                lie_ltc_shading_from_surface(T, &sf, &sh);
                float got[3];
                lie_ltc_polygon(&sh, sky, 4, got);
                double ref = sum3d(mc);
                if (fabs(sum3(got) - ref) > 0.01 * ref)
                    fail_msg("metallic %d roughness %.2f view %.0f: LTC %.6g, albedo %.6g", m, (double)rough[i],
                             (double)angles[a], sum3(got), ref);
            }
}

/* Clipping is linear, so a polygon crossing the horizon integrates as its
 * part above; wholly below gives 0. */
static void test_ltc_horizon_crossing_is_clipped(void **state)
{
    (void)state;
    lie_ltc_shading sh;
    float f0[3] = {0.04f, 0.04f, 0.04f};
    lie_ltc_shading_init(lie_ltc_table_default(), lie_v3(0, 0, 1), ltc_view(40.0f), 0.4f, f0, grey, &sh);
    lie_vec3 cross[4] = {lie_v3(-1, -1, -1), lie_v3(-1, 1, -1), lie_v3(-1, 1, 1), lie_v3(-1, -1, 1)};
    lie_vec3 above[4] = {lie_v3(-1, -1, 0), lie_v3(-1, 1, 0), lie_v3(-1, 1, 1), lie_v3(-1, -1, 1)};
    lie_vec3 below[4] = {lie_v3(-1, -1, -1), lie_v3(-1, 1, -1), lie_v3(-1, 1, -0.01f), lie_v3(-1, -1, -0.01f)};
    float a[3], b[3], c[3];
    lie_ltc_polygon(&sh, cross, 4, a);
    lie_ltc_polygon(&sh, above, 4, b);
    lie_ltc_polygon(&sh, below, 4, c);
    assert_true(a[0] > 0.0f);
    for (int k = 0; k < 3; k++) {
        assert_float_equal(a[k], b[k], 1e-6 * b[k]);
        assert_true(c[k] == 0.0f);
    }
}

/* The result does not depend on the winding, and integrals add: a quad is
 * its two triangles. */
static void test_ltc_winding_and_additivity(void **state)
{
    (void)state;
    lie_ltc_shading sh;
    float f0[3] = {0.9f, 0.6f, 0.3f}, cd[3] = {0, 0, 0};
    lie_ltc_shading_init(lie_ltc_table_default(), lie_v3(0, 0, 1), ltc_view(50.0f), 0.3f, f0, cd, &sh);
    lie_vec3 q[4];
    ltc_square_toward(lie_v3_norm(lie_v3(-0.6f, 0.2f, 0.7f)), 1.5f, 0.6f, q);
    lie_vec3 rev[4] = {q[3], q[2], q[1], q[0]};
    lie_vec3 t1[3] = {q[0], q[1], q[2]}, t2[3] = {q[0], q[2], q[3]};
    float a[3], b[3], c[3], d[3];
    lie_ltc_polygon(&sh, q, 4, a);
    lie_ltc_polygon(&sh, rev, 4, b);
    lie_ltc_polygon(&sh, t1, 3, c);
    lie_ltc_polygon(&sh, t2, 3, d);
    for (int k = 0; k < 3; k++) {
        assert_true(a[k] > 0.0f);
        assert_float_equal(a[k], b[k], 1e-5 * a[k]);
        assert_float_equal(a[k], c[k] + d[k], 1e-4 * a[k]);
    }
}

/* Degenerate input gives 0 or a finite limit, never NaN. */
static void test_ltc_degenerate_polygons(void **state)
{
    (void)state;
    lie_ltc_shading sh;
    float f0[3] = {0.04f, 0.04f, 0.04f};
    lie_ltc_shading_init(lie_ltc_table_default(), lie_v3(0, 0, 1), ltc_view(30.0f), 0.5f, f0, grey, &sh);
    lie_vec3 tri[3] = {lie_v3(0, 0, 1), lie_v3(1, 0, 1), lie_v3(0, 1, 1)};
    float o[3];
    for (int n = 0; n < 3; n++) { /* fewer than 3 vertices */
        lie_ltc_polygon(&sh, tri, n, o);
        assert_true(o[0] == 0.0f && o[1] == 0.0f && o[2] == 0.0f);
    }
    lie_vec3 line[3] = {lie_v3(0, 0, 1), lie_v3(1, 1, 1), lie_v3(2, 2, 1)}; /* zero area */
    lie_ltc_polygon(&sh, line, 3, o);
    assert_true(fabsf(o[0]) < 1e-7f);
    lie_vec3 edge_on[4] = {lie_v3(1, 0, 0.5f), lie_v3(2, 0, 0.5f), lie_v3(2, 0, 2), lie_v3(1, 0, 2)}; /* plane y = 0 */
    lie_ltc_polygon(&sh, edge_on, 4, o);
    assert_true(fabsf(o[0]) < 1e-6f);
    lie_vec3 point[3] = {lie_v3(0.3f, 0.2f, 1), lie_v3(0.3f, 0.2f, 1), lie_v3(0.3f, 0.2f, 1)};
    lie_ltc_polygon(&sh, point, 3, o);
    assert_true(o[0] == 0.0f);
    /* a vertex at the shading point: finite, and the triangle's edges
     * through it have no direction, so it is no more than the whole */
    lie_vec3 at_origin[3] = {lie_v3(0, 0, 0), lie_v3(1, 0, 1), lie_v3(0, 1, 1)};
    lie_ltc_polygon(&sh, at_origin, 3, o);
    assert_true(isfinite(o[0]) && o[0] >= 0.0f);
    /* a repeated vertex changes nothing */
    lie_vec3 dup[4] = {tri[0], tri[1], tri[1], tri[2]};
    float a[3];
    lie_ltc_polygon(&sh, tri, 3, o);
    lie_ltc_polygon(&sh, dup, 4, a);
    assert_float_equal(a[0], o[0], 1e-6 * o[0]);
    /* a tiny polygon: Lambert gives cos(theta) * solid angle / pi */
    lie_ltc_shading lam;
    lie_ltc_shading_lambert(lie_v3(0, 0, 1), white, &lam);
    lie_vec3 tiny[4];
    lie_vec3 dir = lie_v3_norm(lie_v3(0.3f, -0.4f, 0.8f));
    ltc_square_toward(dir, 1.0f, 5e-4f, tiny);
    lie_ltc_polygon(&lam, tiny, 4, o);
    double expect = dir.z * (1e-3 * 1e-3) / M_PI;
    assert_float_equal(o[0], expect, 2e-3 * expect);
}

/* lie_ltc_shading_from_surface picks Lambert for Lambert surfaces and
 * passes roughness = sqrt(alpha) otherwise. */
static void test_ltc_setup_from_surface(void **state)
{
    (void)state;
    const lie_ltc_table *T = lie_ltc_table_default();
    lie_surface lam = ltc_mc_surface(lie_v3(0, 0, 1), ltc_view(20.0f), 1.0f, 0.0f, grey);
    lie_ltc_shading a, b;
    lie_ltc_shading_from_surface(T, &lam, &a);
    lie_ltc_shading_lambert(lie_v3(0, 0, 1), lam.diffuse, &b);
    assert_memory_equal(&a, &b, sizeof a);
    lie_surface ggx = ltc_mc_surface(lie_v3(0, 0, 1), ltc_view(20.0f), 0.6f, 0.3f, grey);
    lie_ltc_shading_from_surface(T, &ggx, &a);
    lie_ltc_shading_init(T, ggx.n, ggx.wo, sqrtf(ggx.alpha), ggx.f0, ggx.diffuse, &b);
    assert_memory_equal(&a, &b, sizeof a);
    assert_int_equal(a.has_spec, 1);
}

/* The compiled tables: the size ltc-fit writes, finite, positive norms,
 * Fresnel fractions in [0, 1]. */
static void test_ltc_table_is_sane(void **state)
{
    (void)state;
    const lie_ltc_table *T = lie_ltc_table_default();
    assert_int_equal(T->n_rough, 64);
    assert_int_equal(T->n_cos, 64);
    assert_non_null(T->ggx_fresnel);
    int g = T->n_rough * T->n_cos;
    for (int i = 0; i < 2 * g + T->n_cos; i++) {
        const lie_ltc_bin *b = i < g ? &T->ggx[i] : i < 2 * g ? &T->ggx_fresnel[i - g] : &T->diffuse[i - 2 * g];
        assert_true(isfinite(b->m00) && isfinite(b->m02) && isfinite(b->m20) && isfinite(b->m22));
        assert_true(b->norm > 0.0f && isfinite(b->norm));
        assert_true(b->fresnel >= 0.0f && b->fresnel <= 1.0f);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ltc_lambert_rectangle_matches_closed_form),
        cmocka_unit_test(test_ltc_specular_matches_monte_carlo),
        cmocka_unit_test(test_ltc_dielectric_matches_monte_carlo),
        cmocka_unit_test(test_ltc_coloured_metal_matches_monte_carlo),
        cmocka_unit_test(test_ltc_hemisphere_is_directional_albedo),
        cmocka_unit_test(test_ltc_horizon_crossing_is_clipped),
        cmocka_unit_test(test_ltc_winding_and_additivity),
        cmocka_unit_test(test_ltc_degenerate_polygons),
        cmocka_unit_test(test_ltc_setup_from_surface),
        cmocka_unit_test(test_ltc_table_is_sane),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
