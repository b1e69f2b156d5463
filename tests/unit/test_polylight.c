/* SPDX-License-Identifier: Apache-2.0 */
/* lib/shade polylight: Lambert's edge sum and exact back-projected
 * shadows, against closed forms and a fine brute-force quadrature, in the
 * degenerate cases any exact method must survive. */
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

/* Every triangle of the scene, the emitter's own included if asked. */
static int all_blockers(const lie_scene *s, int with_emitter, uint32_t *out)
{
    int m = 0;
    const lie_emitter *em = &s->emitters[0];
    for (uint32_t t = 0; t < s->n_tris; t++)
        if (with_emitter || t - em->first_tri >= em->n_tris)
            out[m++] = t;
    return m;
}

/* Segment o -> p (stopping eps short) against triangle abc, double. */
static int segment_hits(const double o[3], const double p[3], double eps, const lie_vec3 *T)
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

/* The projected solid angle by midpoint quadrature over a g x g grid of
 * the square (side a at height h), with visibility against the blockers. */
static double brute(const lie_scene *s, float a, float h, int two_sided, lie_vec3 o, lie_vec3 n,
                    const uint32_t *bl, int nb, double eps, int g)
{
    double sum = 0.0, cell = (double)a * a / ((double)g * g);
    const double O[3] = {o.x, o.y, o.z};
    for (int i = 0; i < g; i++)
        for (int j = 0; j < g; j++) {
            double p[3] = {-0.5 * a + (i + 0.5) * a / g, h, -0.5 * a + (j + 0.5) * a / g};
            double d[3] = {p[0] - O[0], p[1] - O[1], p[2] - O[2]};
            double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], dl = sqrt(d2);
            double cr = (n.x * d[0] + n.y * d[1] + n.z * d[2]) / dl;
            double ce = d[1] / dl; /* the emitter faces -y */
            if (two_sided)
                ce = fabs(ce);
            if (cr <= 0.0 || ce <= 0.0)
                continue;
            int blocked = 0;
            for (int k = 0; k < nb && !blocked; k++)
                blocked = segment_hits(O, p, eps, &s->tri_p[3 * (size_t)bl[k]]);
            if (!blocked)
                sum += cr * ce / d2 * cell;
        }
    return sum;
}

typedef struct fixture {
    lie_scene *s;
    lie_polylight *L;
    lie_polylight_work w;
    uint32_t bl[64];
    int nb;
} fixture;

static void fixture_make(fixture *f, float a, float h, int two_sided, const float *tris, int n)
{
    memset(f, 0, sizeof *f);
    f->s = square_light_and_blockers(a, h, two_sided, tris, n);
    assert_int_equal(lie_polylight_create(f->s, 0, &f->L), LIE_OK);
    assert_non_null(f->L);
    assert_int_equal(f->L->n_polys, 1); /* two triangles tiling a square: one piece */
    assert_int_equal(lie_polylight_work_init(&f->w, 64), LIE_OK);
    f->nb = all_blockers(f->s, 0, f->bl);
}

static void fixture_free(fixture *f)
{
    lie_polylight_work_free(&f->w);
    lie_polylight_destroy(f->L);
    lie_scene_destroy(f->s);
}

static double exact(fixture *f, lie_vec3 o, lie_vec3 n, const int32_t *solid)
{
    double om = -1.0;
    assert_int_equal(lie_polylight_visible(f->L, o, n, n, f->s->tri_p, solid, f->bl, f->nb, 1e-4f, &f->w, &om), 0);
    return om;
}

static void test_polylight_unshadowed_matches_form_factor(void **state)
{
    (void)state;
    fixture f;
    fixture_make(&f, 1.0f, 1.5f, 0, NULL, 0);
    const lie_vec3 up = lie_v3(0, 1, 0);
    /* Omega_perp = pi F */
    double om = lie_polylight_unshadowed(f.L, lie_v3(0, 0, 0), up, up, &f.w);
    assert_true(fabs(om - M_PI * 4.0 * ff_corner(0.5, 0.5, 1.5)) < 1e-6 * om);
    om = lie_polylight_unshadowed(f.L, lie_v3(0.5f, 0, 0.5f), up, up, &f.w);
    assert_true(fabs(om - M_PI * ff_corner(1.0, 1.0, 1.5)) < 1e-6 * om);
    /* a wall point whose tangent plane cuts the light: the part above it only */
    const lie_vec3 side = lie_v3_norm(lie_v3(1.0f, 0.2f, 0.0f));
    om = lie_polylight_unshadowed(f.L, lie_v3(0.1f, 1.2f, 0.2f), side, side, &f.w);
    double b = brute(f.s, 1.0f, 1.5f, 0, lie_v3(0.1f, 1.2f, 0.2f), side, NULL, 0, 0.0, 600);
    assert_true(om > 0.0 && fabs(om - b) < 2e-3 * b);
    fixture_free(&f);
}

/* a square blocker [x0, x1] x [z0, z1] at height y, as two triangles sharing a diagonal */
static void square_blocker(float *t, float x0, float x1, float z0, float z1, float y)
{
    float q[18] = {x0, y, z0, x1, y, z0, x1, y, z1, x0, y, z0, x1, y, z1, x0, y, z1};
    memcpy(t, q, sizeof q);
}

static void test_polylight_blocker_edges_on_emitter_edges(void **state)
{
    (void)state;
    /* Seen from the origin, a square of half the size at half the height
     * casts exactly the emitter; half of it casts exactly half (by
     * symmetry), and its two triangles share an edge and two vertices. */
    float t[18];
    const lie_vec3 o = lie_v3(0, 0, 0), up = lie_v3(0, 1, 0);
    fixture f;
    square_blocker(t, -0.25f, 0.25f, -0.25f, 0.25f, 0.5f);
    fixture_make(&f, 1.0f, 1.0f, 0, t, 2);
    double full = lie_polylight_unshadowed(f.L, o, up, up, &f.w);
    assert_true(exact(&f, o, up, NULL) <= 1e-9 * full);
    fixture_free(&f);
    square_blocker(t, -0.25f, 0.0f, -0.25f, 0.25f, 0.5f);
    fixture_make(&f, 1.0f, 1.0f, 0, t, 2);
    assert_true(fabs(exact(&f, o, up, NULL) - 0.5 * full) <= 1e-9 * full);
    fixture_free(&f);
}

static void test_polylight_blocker_crossing_the_point_plane(void **state)
{
    (void)state;
    /* a slanted wall that starts below the point's tangent plane and rises
     * past it toward the light, beside the point */
    float t[18] = {-0.3f, -0.5f, -2.0f, -0.3f, -0.5f, 2.0f, 0.3f, 0.9f, 2.0f,
                   -0.3f, -0.5f, -2.0f, 0.3f, 0.9f, 2.0f, 0.3f, 0.9f, -2.0f};
    fixture f;
    fixture_make(&f, 1.0f, 1.0f, 0, t, 2);
    const lie_vec3 o = lie_v3(0.2f, 0.0f, 0.1f), up = lie_v3(0, 1, 0);
    double e = exact(&f, o, up, NULL);
    double b = brute(f.s, 1.0f, 1.0f, 0, o, up, f.bl, f.nb, 1e-4, 600);
    double full = lie_polylight_unshadowed(f.L, o, up, up, &f.w);
    assert_true(e > 0.05 * full && e < 0.95 * full);
    assert_true(fabs(e - b) < 3e-3 * full);
    fixture_free(&f);
}

static void test_polylight_blocker_touching_the_emitter(void **state)
{
    (void)state;
    /* a vertical fin from y = 0.4 up to the emitter's plane, across it */
    float t[18] = {0.1f, 0.4f, -1.0f, 0.1f, 0.4f, 1.0f, 0.1f, 1.0f, 1.0f,
                   0.1f, 0.4f, -1.0f, 0.1f, 1.0f, 1.0f, 0.1f, 1.0f, -1.0f};
    fixture f;
    fixture_make(&f, 1.0f, 1.0f, 0, t, 2);
    const lie_vec3 up = lie_v3(0, 1, 0);
    const lie_vec3 pts[3] = {lie_v3(-0.3f, 0, 0.1f), lie_v3(0.4f, 0, -0.2f), lie_v3(0.1f, 0, 0)};
    for (int i = 0; i < 3; i++) {
        double e = exact(&f, pts[i], up, NULL);
        double b = brute(f.s, 1.0f, 1.0f, 0, pts[i], up, f.bl, f.nb, 1e-4, 600);
        double full = lie_polylight_unshadowed(f.L, pts[i], up, up, &f.w);
        assert_true(fabs(e - b) < 3e-3 * full);
    }
    fixture_free(&f);
}

static void test_polylight_zero_area_projections_cast_nothing(void **state)
{
    (void)state;
    /* a triangle in a plane through the point, and a degenerate one
     * (collinear vertices, a repeated vertex) */
    float t[27] = {0.0f, 0.2f, -0.3f, 0.0f, 0.8f, 0.3f, 0.0f, 0.6f, -0.2f,
                   -0.2f, 0.5f, -0.2f, 0.0f, 0.5f, 0.0f, 0.2f, 0.5f, 0.2f,
                   -0.2f, 0.5f, 0.1f, -0.2f, 0.5f, 0.1f, 0.2f, 0.6f, 0.1f};
    fixture f;
    fixture_make(&f, 1.0f, 1.0f, 0, t, 3);
    const lie_vec3 o = lie_v3(0, 0, 0), up = lie_v3(0, 1, 0);
    double full = lie_polylight_unshadowed(f.L, o, up, up, &f.w);
    assert_true(fabs(exact(&f, o, up, NULL) - full) <= 1e-12 * full);
    fixture_free(&f);
}

static void test_polylight_emitter_edge_on_and_two_sided(void **state)
{
    (void)state;
    fixture f;
    fixture_make(&f, 1.0f, 1.0f, 0, NULL, 0);
    const lie_vec3 side = lie_v3(-1, 0, 0), up = lie_v3(0, 1, 0), down = lie_v3(0, -1, 0);
    /* in the emitter's plane: nothing */
    assert_true(lie_polylight_unshadowed(f.L, lie_v3(2.0f, 1.0f, 0.0f), side, side, &f.w) == 0.0);
    double om = 1.0;
    assert_int_equal(lie_polylight_visible(f.L, lie_v3(2.0f, 1.0f, 0.0f), side, side, f.s->tri_p, NULL, f.bl, 0,
                                           1e-4f, &f.w, &om), 0);
    assert_true(om == 0.0);
    /* behind a one-sided emitter: nothing */
    assert_true(lie_polylight_unshadowed(f.L, lie_v3(0.0f, 2.0f, 0.0f), down, down, &f.w) == 0.0);
    double below = lie_polylight_unshadowed(f.L, lie_v3(0.1f, 0.0f, 0.2f), up, up, &f.w);
    fixture_free(&f);
    /* two-sided: the mirror image of the point below sees the same */
    fixture_make(&f, 1.0f, 1.0f, 1, NULL, 0);
    double above = lie_polylight_unshadowed(f.L, lie_v3(0.1f, 2.0f, 0.2f), down, down, &f.w);
    assert_true(fabs(above - below) < 1e-6 * below);
    fixture_free(&f);
}

static void test_polylight_own_triangles_are_not_blockers(void **state)
{
    (void)state;
    fixture f;
    fixture_make(&f, 1.0f, 1.0f, 0, NULL, 0);
    f.nb = all_blockers(f.s, 1, f.bl);
    assert_int_equal(f.nb, 2);
    const lie_vec3 o = lie_v3(0.3f, 0, -0.1f), up = lie_v3(0, 1, 0);
    assert_true(exact(&f, o, up, NULL) == lie_polylight_unshadowed(f.L, o, up, up, &f.w));
    fixture_free(&f);
}

/* a closed box [lo, hi], outward faces, 12 triangles into t (108 floats) */
static void box_blocker(float *t, const float lo[3], const float hi[3])
{
    float v[8][3];
    for (int i = 0; i < 8; i++) {
        v[i][0] = i & 1 ? hi[0] : lo[0];
        v[i][1] = i & 2 ? hi[1] : lo[1];
        v[i][2] = i & 4 ? hi[2] : lo[2];
    }
    static const int f[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                                 {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    for (int k = 0; k < 12; k++)
        for (int c = 0; c < 3; c++)
            memcpy(&t[9 * k + 3 * c], v[f[k][c]], sizeof v[0]);
}

static void test_polylight_convex_solid_casts_its_faces_shadow(void **state)
{
    (void)state;
    /* a box standing on the point's plane beside it, and a floating one:
     * one shadow from the solid's hull equals the faces' shadows one by
     * one, and the quadrature */
    float t[216];
    const float lo1[3] = {0.05f, -0.01f, -0.2f}, hi1[3] = {0.3f, 0.6f, 0.1f};
    const float lo2[3] = {-0.4f, 0.5f, -0.3f}, hi2[3] = {-0.2f, 0.7f, 0.0f};
    box_blocker(t, lo1, hi1);
    box_blocker(t + 108, lo2, hi2);
    fixture f;
    fixture_make(&f, 1.0f, 1.0f, 0, t, 24);
    int32_t *solid = lie_solids_find(f.s);
    assert_non_null(solid);
    const lie_vec3 up = lie_v3(0, 1, 0);
    const lie_vec3 pts[3] = {lie_v3(0, 0, 0), lie_v3(-0.1f, 0, 0.3f), lie_v3(0.4f, 0, -0.4f)};
    for (int i = 0; i < 3; i++) {
        double a = exact(&f, pts[i], up, solid), b = exact(&f, pts[i], up, NULL);
        double q = brute(f.s, 1.0f, 1.0f, 0, pts[i], up, f.bl, f.nb, 1e-4, 500);
        double full = lie_polylight_unshadowed(f.L, pts[i], up, up, &f.w);
        assert_true(a < 0.99 * full);
        assert_true(fabs(a - b) < 1e-9 * full);
        assert_true(fabs(a - q) < 3e-3 * full);
    }
    free(solid);
    fixture_free(&f);
}

static void test_polylight_random_blockers_match_quadrature(void **state)
{
    (void)state;
    /* overlapping triangles between the point and the light, some crossing
     * the light's plane or the point's */
    enum { NT = 10 };
    float t[9 * NT];
    uint64_t h = 12345;
    for (int i = 0; i < 9 * NT; i++) {
        h = lie_hash_u64x4(h, (uint64_t)i, 7, 9);
        float u = (float)lie_hash_to_unit(h);
        t[i] = (i % 3 == 1) ? -0.1f + 1.2f * u : -0.7f + 1.4f * u;
    }
    fixture f;
    fixture_make(&f, 1.0f, 1.0f, 0, t, NT);
    const lie_vec3 n = lie_v3_norm(lie_v3(0.2f, 1.0f, -0.1f));
    for (int i = 0; i < 4; i++) {
        lie_vec3 o = lie_v3(-0.3f + 0.2f * (float)i, 0.0f, 0.1f * (float)i - 0.2f);
        double e = exact(&f, o, n, NULL);
        double b = brute(f.s, 1.0f, 1.0f, 0, o, n, f.bl, f.nb, 1e-4, 600);
        double full = lie_polylight_unshadowed(f.L, o, n, n, &f.w);
        assert_true(fabs(e - b) < 3e-3 * full);
    }
    fixture_free(&f);
}

/* A glossy floor under the square, one pixel, no shadows: the LTC over the
 * emitter's clipped polygon (--light-samples exact) against 16k samples. */
static void test_polylight_glossy_receiver_uses_ltc(void **state)
{
    (void)state;
    lie_scene *s = lie_scene_new("glossy");
    lie_material light = lie_material_default();
    light.base_color[0] = light.base_color[1] = light.base_color[2] = 0.0f;
    light.emissive[0] = light.emissive[1] = light.emissive[2] = 4.0f;
    int ml = lie_scene_add_material(s, &light);
    lie_material floor = lie_material_default();
    floor.metallic = 0.5f;
    floor.roughness = 0.5f;
    int mf = lie_scene_add_material(s, &floor);
    float lp[12] = {-0.5f, 1, -0.5f, 0.5f, 1, -0.5f, 0.5f, 1, 0.5f, -0.5f, 1, 0.5f};
    float fp[12] = {-50, 0, -50, -50, 0, 50, 50, 0, 50, 50, 0, -50};
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    lie_scene_add_node(s, "Light", -1, NULL, lie_scene_add_mesh(s, "Light", lp, NULL, NULL, 4, idx, 2, ml), -1, -1);
    lie_scene_add_node(s, "Floor", -1, NULL, lie_scene_add_mesh(s, "Floor", fp, NULL, NULL, 4, idx, 2, mf), -1, -1);
    lie_error err;
    assert_int_equal(lie_scene_flatten(s, &err), LIE_OK);
    lie_rt *rt = NULL;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_camera cam;
    memset(&cam, 0, sizeof cam);
    cam.eye = lie_v3(0.8f, 0.6f, 0.3f);
    cam.forward = lie_v3_norm(lie_v3_sub(lie_v3(0.3f, 0.0f, 0.1f), cam.eye));
    cam.up = lie_v3_norm(lie_v3_cross(lie_v3_cross(cam.forward, lie_v3(0, 1, 0)), cam.forward));
    cam.yfov = 0.01f;
    float px[2][3];
    for (int k = 0; k < 2; k++) {
        lie_render_options o = test_render_options(1, 1, LIE_LIGHT_SAMPLES_DEFAULT, 1);
        o.visibility = LIE_VIS_NONE;
        o.exact = k ? LIE_EXACT_ONLY : LIE_EXACT_OFF;
        o.light_samples = k ? 16 : 16384;
        o.pattern = LIE_PATTERN_ROTATED;
        lie_frame *f = NULL;
        lie_render_stats st;
        assert_int_equal(lie_render(s, rt, &cam, &o, &f, &st, &err), LIE_OK);
        memcpy(px[k], f->rgb, sizeof px[k]);
        lie_frame_destroy(f);
        if (k)
            assert_true(st.pairs_analytic == 1 && st.light_samples == 0); /* no samples taken */
    }
    for (int c = 0; c < 3; c++)
        assert_true(px[0][c] > 0.0f && fabsf(px[1][c] - px[0][c]) <= 0.05f * px[0][c]);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_polylight_unshadowed_matches_form_factor),
        cmocka_unit_test(test_polylight_blocker_edges_on_emitter_edges),
        cmocka_unit_test(test_polylight_blocker_crossing_the_point_plane),
        cmocka_unit_test(test_polylight_blocker_touching_the_emitter),
        cmocka_unit_test(test_polylight_zero_area_projections_cast_nothing),
        cmocka_unit_test(test_polylight_emitter_edge_on_and_two_sided),
        cmocka_unit_test(test_polylight_own_triangles_are_not_blockers),
        cmocka_unit_test(test_polylight_convex_solid_casts_its_faces_shadow),
        cmocka_unit_test(test_polylight_random_blockers_match_quadrature),
        cmocka_unit_test(test_polylight_glossy_receiver_uses_ltc),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
