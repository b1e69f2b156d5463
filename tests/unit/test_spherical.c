/* SPDX-License-Identifier: Apache-2.0 */
/* lib/shade spherical.c: Arvo's solid-angle sampling of triangles, against
 * quadrature over the triangle and the closed-form solid angle. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>

#include "lie.h"
#include "shade/spherical.h"

/* int over the triangle of f(x) dA, each triangle cut into g^2 similar
 * ones, one point at each centroid; f gets the point relative to o. */
typedef double (*integrand)(const double *d, const double *n, void *ctx);
static double quad(lie_vec3 o, const lie_vec3 p[3], int g, integrand f, void *ctx)
{
    double e1[3] = {(double)p[1].x - p[0].x, (double)p[1].y - p[0].y, (double)p[1].z - p[0].z};
    double e2[3] = {(double)p[2].x - p[0].x, (double)p[2].y - p[0].y, (double)p[2].z - p[0].z};
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    double a2 = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; k++)
        n[k] /= a2;
    const double cell = 0.5 * a2 / ((double)g * g);
    double sum = 0.0;
    for (int i = 0; i < g; i++)
        for (int j = 0; j < g - i; j++)
            for (int up = 0; up < 2 && (up == 0 || i + j < g - 1); up++) {
                double b1 = up ? (i + 2.0 / 3.0) / g : (i + 1.0 / 3.0) / g;
                double b2 = up ? (j + 2.0 / 3.0) / g : (j + 1.0 / 3.0) / g;
                double d[3];
                for (int k = 0; k < 3; k++)
                    d[k] = (&p[0].x)[k] + b1 * e1[k] + b2 * e2[k] - (&o.x)[k];
                sum += f(d, n, ctx) * cell;
            }
    return sum;
}

/* cos' / d^2: the solid angle's density in area measure */
static double solid(const double *d, const double *n, void *ctx)
{
    (void)ctx;
    double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    return fabs(d[0] * n[0] + d[1] * n[1] + d[2] * n[2]) / (d2 * sqrt(d2));
}

/* the sampler's density in area measure, cos' / (d^2 A) */
static double pdf_area(const double *d, const double *n, void *ctx)
{
    return solid(d, n, NULL) / ((const lie_sph_tri *)ctx)->area;
}

/* cos / d^2 cos' for a receiver of normal ctx: the projected solid angle */
static double projected(const double *d, const double *n, void *ctx)
{
    const double *r = ctx;
    double dl = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    double c = (d[0] * r[0] + d[1] * r[1] + d[2] * r[2]) / dl;
    return c > 0.0 ? c * solid(d, n, NULL) : 0.0;
}

static const lie_vec3 TRI[3] = {{-0.7f, 1.0f, -0.4f}, {0.9f, 1.0f, -0.6f}, {0.1f, 1.0f, 0.8f}};

static void test_spherical_pdf_integrates_to_one(void **state)
{
    (void)state;
    const lie_vec3 pts[4] = {lie_v3(0, 0, 0), lie_v3(0.05f, 0.95f, 0.0f), lie_v3(2.0f, 0.5f, 1.0f),
                             lie_v3(0.0f, 1.3f, 0.1f)};
    for (int i = 0; i < 4; i++) {
        lie_sph_tri t;
        assert_int_equal(lie_sph_tri_setup(pts[i], TRI, &t), 1);
        /* Girard's area of the sampler against Van Oosterom & Strackee's */
        double omega = lie_sph_tri_solid_angle(pts[i], TRI);
        assert_true(fabs(t.area - omega) < 1e-9 * omega);
        double one = quad(pts[i], TRI, i == 1 ? 800 : 200, pdf_area, &t);
        assert_true(fabs(one - 1.0) < 2e-3);
    }
}

static void test_spherical_samples_lie_on_the_triangle_uniformly(void **state)
{
    (void)state;
    /* a 64 x 64 grid of strata; each of the triangle's four midpoint
     * sub-triangles gets its share of solid angle */
    const lie_vec3 o = lie_v3(0.2f, 0.7f, 0.1f);
    lie_sph_tri t;
    assert_int_equal(lie_sph_tri_setup(o, TRI, &t), 1);
    lie_vec3 m[3];
    for (int k = 0; k < 3; k++)
        m[k] = lie_v3_scale(lie_v3_add(TRI[k], TRI[(k + 1) % 3]), 0.5f);
    const lie_vec3 sub[4][3] = {{TRI[0], m[0], m[2]}, {m[0], TRI[1], m[1]}, {m[2], m[1], TRI[2]}, {m[0], m[1], m[2]}};
    int count[4] = {0, 0, 0, 0};
    enum { G = 64 };
    for (int i = 0; i < G; i++)
        for (int j = 0; j < G; j++) {
            lie_sph_sample s;
            assert_int_equal(lie_sph_tri_sample(&t, (i + 0.5) / G, (j + 0.5) / G, &s), 1);
            assert_true(s.b1 >= -1e-9 && s.b2 >= -1e-9 && s.b1 + s.b2 <= 1.0 + 1e-9);
            /* the point is where the direction meets the triangle */
            double d[3] = {s.p[0] - o.x, s.p[1] - o.y, s.p[2] - o.z};
            double dl = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (int k = 0; k < 3; k++)
                assert_true(fabs(d[k] / dl - s.dir[k]) < 1e-9);
            assert_true(fabs(s.p[1] - 1.0) < 1e-9);
            /* which sub-triangle: by barycentrics (b0 = 1 - b1 - b2) */
            double b0 = 1.0 - s.b1 - s.b2;
            int q = b0 > 0.5 ? 0 : s.b1 > 0.5 ? 1 : s.b2 > 0.5 ? 2 : 3;
            count[q]++;
        }
    for (int q = 0; q < 4; q++) {
        double share = lie_sph_tri_solid_angle(o, sub[q]) / t.area;
        assert_true(fabs((double)count[q] / (G * G) - share) < 2e-3);
    }
}

static void test_spherical_estimate_matches_quadrature(void **state)
{
    (void)state;
    /* the projected solid angle from points near the triangle and far:
     * the estimate from 64 x 64 stratified samples against the quadrature */
    const lie_vec3 pts[3] = {lie_v3(0.1f, 0.9f, 0.0f), lie_v3(0.0f, 0.8f, -0.3f), lie_v3(0.5f, -1.0f, 0.5f)};
    const double rn[3][3] = {{0.0, 1.0, 0.0}, {0.6, 0.8, 0.0}, {0.0, 1.0, 0.0}};
    enum { G = 64 };
    for (int i = 0; i < 3; i++) {
        double ref = quad(pts[i], TRI, 1000, projected, (void *)rn[i]);
        lie_sph_tri t;
        assert_int_equal(lie_sph_tri_setup(pts[i], TRI, &t), 1);
        double est = 0.0, est_area = 0.0;
        const double *r = rn[i];
        for (int a = 0; a < G; a++)
            for (int b = 0; b < G; b++) {
                double u1 = (a + 0.5) / G, u2 = (b + 0.5) / G;
                lie_sph_sample s;
                assert_int_equal(lie_sph_tri_sample(&t, u1, u2, &s), 1);
                double c = s.dir[0] * r[0] + s.dir[1] * r[1] + s.dir[2] * r[2];
                /* the area form of the estimator, with the sample's 1/pdf */
                double d[3] = {s.p[0] - pts[i].x, s.p[1] - pts[i].y, s.p[2] - pts[i].z};
                double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                double ce = fabs(d[1]) / sqrt(d2);
                est += (c > 0.0 ? c : 0.0) * ce / d2 * s.inv_pdf_area;
                /* uniform by area: the same strata through the square-to-triangle map */
                double su = sqrt(u1), b1 = su * (1.0 - u2), b2 = su * u2;
                double x[3];
                for (int k = 0; k < 3; k++)
                    x[k] = (1.0 - b1 - b2) * (&TRI[0].x)[k] + b1 * (&TRI[1].x)[k] + b2 * (&TRI[2].x)[k] - (&pts[i].x)[k];
                est_area += projected(x, (const double[3]){0.0, 1.0, 0.0}, (void *)r);
            }
        est /= G * G;
        double area = 0.5 * fabs((TRI[1].x - TRI[0].x) * (TRI[2].z - TRI[0].z) - (TRI[1].z - TRI[0].z) * (TRI[2].x - TRI[0].x));
        est_area *= area / (G * G);
        assert_true(fabs(est - ref) < 1e-3 * ref);
        assert_true(fabs(est_area - ref) < 1e-3 * ref); /* both converge */
    }
}

/* A pixel's budget: 16 samples, 3 hundredths from the triangle, over 64
 * Cranley-Patterson rotations of a 4 x 4 grid: the RMS error of the
 * solid-angle estimate is a fraction of the area estimate's. */
static void test_spherical_beats_area_sampling_near_the_triangle(void **state)
{
    (void)state;
    const lie_vec3 o = lie_v3(0.1f, 0.97f, 0.0f);
    const double r[3] = {0.0, 1.0, 0.0}, en[3] = {0.0, 1.0, 0.0};
    const double ref = quad(o, TRI, 2000, projected, (void *)r);
    lie_sph_tri t;
    assert_int_equal(lie_sph_tri_setup(o, TRI, &t), 1);
    const double area = 0.5 * fabs((TRI[1].x - TRI[0].x) * (TRI[2].z - TRI[0].z) - (TRI[1].z - TRI[0].z) * (TRI[2].x - TRI[0].x));
    double se = 0.0, se_area = 0.0;
    enum { G = 4, R = 64 };
    for (int k = 0; k < R; k++) {
        uint64_t h = lie_hash_u64x4(11, (uint64_t)k, 0, 0);
        double su = lie_hash_to_unit(h), sv = lie_hash_to_unit(h << 24);
        double est = 0.0, est_area = 0.0;
        for (int a = 0; a < G; a++)
            for (int b = 0; b < G; b++) {
                double u1 = fmod((a + 0.5) / G + su, 1.0), u2 = fmod((b + 0.5) / G + sv, 1.0);
                lie_sph_sample s;
                assert_int_equal(lie_sph_tri_sample(&t, u1, u2, &s), 1);
                double c = s.dir[0] * r[0] + s.dir[1] * r[1] + s.dir[2] * r[2];
                est += (c > 0.0 ? c : 0.0) * t.area;
                double q = sqrt(u1), b1 = q * (1.0 - u2), b2 = q * u2, x[3];
                for (int m = 0; m < 3; m++)
                    x[m] = (1.0 - b1 - b2) * (&TRI[0].x)[m] + b1 * (&TRI[1].x)[m] + b2 * (&TRI[2].x)[m] - (&o.x)[m];
                est_area += projected(x, en, (void *)r) * area;
            }
        se += (est / (G * G) - ref) * (est / (G * G) - ref);
        se_area += (est_area / (G * G) - ref) * (est_area / (G * G) - ref);
    }
    const double rms = sqrt(se / R), rms_area = sqrt(se_area / R);
    assert_true(rms < 0.05 * ref);
    assert_true(rms < 0.1 * rms_area);
}

static void test_spherical_refuses_what_it_cannot_condition(void **state)
{
    (void)state;
    lie_sph_tri t;
    /* o in the triangle's plane */
    assert_int_equal(lie_sph_tri_setup(lie_v3(3.0f, 1.0f, 0.0f), TRI, &t), 0);
    /* far away: a tiny solid angle, area sampling is as good */
    assert_int_equal(lie_sph_tri_setup(lie_v3(0.0f, -200.0f, 0.0f), TRI, &t), 0);
    /* a degenerate triangle */
    const lie_vec3 line[3] = {{0, 1, 0}, {1, 1, 0}, {2, 1, 0}};
    assert_int_equal(lie_sph_tri_setup(lie_v3(0, 0, 0), line, &t), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_spherical_pdf_integrates_to_one),
        cmocka_unit_test(test_spherical_samples_lie_on_the_triangle_uniformly),
        cmocka_unit_test(test_spherical_estimate_matches_quadrature),
        cmocka_unit_test(test_spherical_beats_area_sampling_near_the_triangle),
        cmocka_unit_test(test_spherical_refuses_what_it_cannot_condition),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
