/* SPDX-License-Identifier: Apache-2.0 */
/* lib/shade polylight on emitters that are not one convex polygon: a strip
 * of 1,000 triangles, an L-shaped panel with a hole, a panel seen edge-on,
 * an emitter of two planes that shadows itself.  Each against a quadrature
 * over the emitter's triangles (with shadow segments where blockers are),
 * and against the edge sum of every triangle taken alone. */
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

/* A scene of one emitter (triangles et[0..ne), 9 floats each, radiance 1)
 * and blocker triangles bt[0..nb). */
static lie_scene *emitter_scene(const float *et, int ne, int two_sided, const float *bt, int nb)
{
    lie_scene *s = lie_scene_new("polyshape");
    assert_non_null(s);
    int ml = test_material(s, 0.0f, 1.0f, two_sided);
    int mg = test_material(s, 1.0f, 0.0f, 0);
    const float *src[2] = {et, bt};
    const int cnt[2] = {ne, nb}, mat[2] = {ml, mg};
    for (int k = 0; k < 2; k++) {
        if (cnt[k] == 0)
            continue;
        uint32_t *idx = malloc(sizeof *idx * 3 * (size_t)cnt[k]);
        assert_non_null(idx);
        for (int i = 0; i < 3 * cnt[k]; i++)
            idx[i] = (uint32_t)i;
        int mesh = lie_scene_add_mesh(s, k ? "Blockers" : "Light", src[k], NULL, NULL, 3 * cnt[k], idx, cnt[k], mat[k]);
        free(idx);
        assert_true(lie_scene_add_node(s, k ? "Blockers" : "Light", -1, NULL, mesh, -1, -1) >= 0);
    }
    lie_error err;
    assert_int_equal(lie_scene_flatten(s, &err), LIE_OK);
    assert_int_equal(s->n_emitters, 1);
    return s;
}

/* The projected solid angle of the emitter from (o, n): each triangle cut
 * into g^2 similar triangles, one point at each centroid, shadowed by
 * the triangles of the scene: none (shadows 0), those not the emitter's
 * (1), all (2). */
static double quadrature(const lie_scene *s, lie_vec3 o, lie_vec3 n, int g, int shadows, double eps)
{
    const lie_emitter *em = &s->emitters[0];
    const double O[3] = {o.x, o.y, o.z};
    double sum = 0.0;
    for (uint32_t t = em->first_tri; t < em->first_tri + em->n_tris; t++) {
        const lie_vec3 *T = &s->tri_p[3 * (size_t)t];
        const lie_vec3 ng = s->tri_ng[t];
        const double cell = s->tri_area[t] / ((double)g * g);
        for (int i = 0; i < g; i++)
            for (int j = 0; j < g - i; j++)
                for (int up = 0; up < 2 && (up == 0 || i + j < g - 1); up++) {
                    /* the centroid of sub-triangle (i, j), upright or flipped */
                    double b1 = up ? (i + 2.0 / 3.0) / g : (i + 1.0 / 3.0) / g;
                    double b2 = up ? (j + 2.0 / 3.0) / g : (j + 1.0 / 3.0) / g;
                    double b0 = 1.0 - b1 - b2;
                    double p[3] = {b0 * T[0].x + b1 * T[1].x + b2 * T[2].x, b0 * T[0].y + b1 * T[1].y + b2 * T[2].y,
                                   b0 * T[0].z + b1 * T[1].z + b2 * T[2].z};
                    double d[3] = {p[0] - O[0], p[1] - O[1], p[2] - O[2]};
                    double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], dl = sqrt(d2);
                    double cr = (n.x * d[0] + n.y * d[1] + n.z * d[2]) / dl;
                    double ce = -(ng.x * d[0] + ng.y * d[1] + ng.z * d[2]) / dl;
                    if (em->double_sided)
                        ce = fabs(ce);
                    if (cr <= 0.0 || ce <= 0.0)
                        continue;
                    int blocked = 0;
                    for (uint32_t b = 0; shadows && b < s->n_tris && !blocked; b++)
                        if (shadows == 2 || !lie_emitter_owns(em, b))
                            blocked = test_segment_hits(O, p, eps, &s->tri_p[3 * (size_t)b]);
                    if (!blocked)
                        sum += cr * ce / d2 * cell;
                }
    }
    return sum;
}

/* Lambert's edge sum of each emitter triangle alone, all above o's tangent
 * plane (the caller makes sure), summed: exact, by a route that shares no
 * code with polylight.c. */
static double per_triangle(const lie_scene *s, lie_vec3 o, lie_vec3 n)
{
    const lie_emitter *em = &s->emitters[0];
    double sum = 0.0;
    for (uint32_t t = em->first_tri; t < em->first_tri + em->n_tris; t++) {
        double q[3][3], tri = 0.0;
        for (int k = 0; k < 3; k++) {
            lie_vec3 P = s->tri_p[3 * (size_t)t + (size_t)k];
            q[k][0] = (double)P.x - o.x, q[k][1] = (double)P.y - o.y, q[k][2] = (double)P.z - o.z;
        }
        for (int k = 0; k < 3; k++) {
            const double *a = q[k], *b = q[(k + 1) % 3];
            double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
            double cl = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
            double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
            if (cl > 0.0)
                tri += atan2(cl, dot) * (n.x * c[0] + n.y * c[1] + n.z * c[2]) / cl;
        }
        sum += 0.5 * fabs(tri);
    }
    return sum;
}

static void tri(float *t, float ax, float ay, float az, float bx, float by, float bz, float cx, float cy, float cz)
{
    const float v[9] = {ax, ay, az, bx, by, bz, cx, cy, cz};
    memcpy(t, v, sizeof v);
}

/* The pieces cover the emitter's area exactly once. */
static void assert_pieces_cover(const lie_polylight *L)
{
    double a = 0.0;
    for (int k = 0; k < L->n_polys; k++) {
        const lie_poly2 *p = &L->polys[k];
        assert_true(p->n >= 3 && p->n <= LIE_POLY_MAXV - 4);
        assert_true(lie_poly_area(p) > 0.0); /* counter-clockwise */
        for (int i = 0; i < p->n; i++) { /* convex */
            int j = (i + 1) % p->n, l = (i + 2) % p->n;
            double tn = (p->s[j] - p->s[i]) * (p->t[l] - p->t[j]) - (p->t[j] - p->t[i]) * (p->s[l] - p->s[j]);
            assert_true(tn > -1e-9 * L->area);
        }
        a += lie_poly_area(p);
    }
    assert_true(fabs(a - L->area) < 1e-6 * L->area);
}

static double visible(const lie_scene *s, const lie_polylight *L, lie_polylight_work *w, lie_vec3 o, lie_vec3 n,
                      int with_own)
{
    uint32_t *bl = malloc(sizeof *bl * s->n_tris);
    assert_non_null(bl);
    int nb = 0;
    for (uint32_t t = 0; t < s->n_tris; t++)
        if (with_own || !lie_emitter_owns(&s->emitters[0], t))
            bl[nb++] = t;
    double om = -1.0;
    assert_int_equal(lie_polylight_visible(L, o, n, n, s->tri_p, NULL, bl, nb, 1e-4f, w, &om), 0);
    free(bl);
    return om;
}

static void test_polyshape_strip_of_1000_triangles(void **state)
{
    (void)state;
    /* three quarters of a ring (r 0.8 to 1) at y = 1, facing down: 500
     * quads, non-convex; a square blocker under part of it */
    enum { SEG = 500 };
    float *et = malloc(sizeof *et * 18 * SEG);
    assert_non_null(et);
    for (int i = 0; i < SEG; i++) {
        double a0 = 1.5 * M_PI * i / SEG, a1 = 1.5 * M_PI * (i + 1) / SEG;
        float x0 = (float)cos(a0), z0 = (float)sin(a0), x1 = (float)cos(a1), z1 = (float)sin(a1);
        /* wound so that the normal points down (-y) */
        tri(et + 18 * i, 0.8f * x0, 1, 0.8f * z0, x0, 1, z0, x1, 1, z1);
        tri(et + 18 * i + 9, 0.8f * x0, 1, 0.8f * z0, x1, 1, z1, 0.8f * x1, 1, 0.8f * z1);
    }
    float bt[18];
    tri(bt, 0.2f, 0.5f, -0.3f, 1.2f, 0.5f, -0.3f, 1.2f, 0.5f, 0.5f);
    tri(bt + 9, 0.2f, 0.5f, -0.3f, 1.2f, 0.5f, 0.5f, 0.2f, 0.5f, 0.5f);
    lie_scene *s = emitter_scene(et, 2 * SEG, 0, bt, 2);
    free(et);
    assert_int_equal(s->emitters[0].n_tris, 2 * SEG);
    lie_polylight *L = NULL;
    assert_int_equal(lie_polylight_create(s, 0, &L), LIE_OK);
    assert_non_null(L);
    assert_int_equal(L->n_parts, 1);
    assert_true(L->n_polys <= SEG); /* each quad one piece: the inner arc turns right, so no two quads make a convex piece */
    assert_pieces_cover(L);
    lie_polylight_work w;
    assert_int_equal(lie_polylight_work_init(&w, 64), LIE_OK);
    const lie_vec3 up = lie_v3(0, 1, 0), tilt = lie_v3_norm(lie_v3(0.3f, 1.0f, 0.2f));
    const lie_vec3 pts[3] = {lie_v3(0, 0, 0), lie_v3(0.5f, 0.2f, 0.6f), lie_v3(-0.9f, 0.95f, 0.05f)};
    for (int i = 0; i < 3; i++) {
        const lie_vec3 n = i == 1 ? tilt : up;
        double om = lie_polylight_unshadowed(L, pts[i], n, n, &w);
        double pt = per_triangle(s, pts[i], n);
        assert_true(om > 0.0 && fabs(om - pt) < 1e-9 * pt);
        if (i < 2) { /* away from the strip, the quadrature converges */
            double q = quadrature(s, pts[i], n, 6, 0, 0.0);
            assert_true(fabs(om - q) < 1e-3 * q);
            double v = visible(s, L, &w, pts[i], n, 0);
            double qv = quadrature(s, pts[i], n, 10, 1, 1e-4);
            assert_true(v < om);
            assert_true(fabs(v - qv) < 2e-3 * om);
        }
    }
    lie_polylight_work_free(&w);
    lie_polylight_destroy(L);
    lie_scene_destroy(s);
}

static void test_polyshape_l_shape_with_a_hole(void **state)
{
    (void)state;
    /* a 4 x 4 grid of cells 0.25 wide at y = 1, two-sided: the corner 2 x 2
     * block cut away (an L) and cell (1, 1) cut out (a hole) */
    float et[22 * 9];
    int ne = 0;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            if ((i >= 2 && j >= 2) || (i == 1 && j == 1))
                continue;
            float x0 = -0.5f + 0.25f * (float)i, x1 = x0 + 0.25f, z0 = -0.5f + 0.25f * (float)j, z1 = z0 + 0.25f;
            tri(et + 9 * ne++, x0, 1, z0, x1, 1, z0, x1, 1, z1);
            tri(et + 9 * ne++, x0, 1, z0, x1, 1, z1, x0, 1, z1);
        }
    assert_int_equal(ne, 22);
    /* random blockers between the floor and the panel */
    enum { NB = 8 };
    float bt[9 * NB];
    uint64_t h = 777;
    for (int i = 0; i < 9 * NB; i++) {
        h = lie_hash_u64x4(h, (uint64_t)i, 3, 5);
        float u = (float)lie_hash_to_unit(h);
        bt[i] = (i % 3 == 1) ? 0.2f + 0.6f * u : -0.6f + 1.2f * u;
    }
    lie_scene *s = emitter_scene(et, ne, 1, bt, NB);
    lie_polylight *L = NULL;
    assert_int_equal(lie_polylight_create(s, 0, &L), LIE_OK);
    assert_non_null(L);
    assert_int_equal(L->n_parts, 1);
    assert_true(L->n_polys > 1 && L->n_polys <= 8);
    assert_pieces_cover(L);
    assert_true(fabs(L->area - 11 * 0.0625) < 1e-6);
    lie_polylight_work w;
    assert_int_equal(lie_polylight_work_init(&w, 64), LIE_OK);
    const lie_vec3 up = lie_v3(0, 1, 0), down = lie_v3(0, -1, 0);
    /* under the hole, under the cut corner, beside; and above (two-sided) */
    const lie_vec3 pts[4] = {lie_v3(-0.125f, 0.7f, -0.125f), lie_v3(0.25f, 0.0f, 0.25f), lie_v3(0.9f, 0.1f, -0.3f),
                             lie_v3(-0.2f, 1.6f, 0.1f)};
    for (int i = 0; i < 4; i++) {
        const lie_vec3 n = i == 3 ? down : up;
        double om = lie_polylight_unshadowed(L, pts[i], n, n, &w);
        double pt = per_triangle(s, pts[i], n);
        double q = quadrature(s, pts[i], n, 48, 0, 0.0);
        assert_true(om > 0.0 && fabs(om - pt) < 1e-9 * pt);
        assert_true(fabs(om - q) < 2e-3 * q);
        double v = visible(s, L, &w, pts[i], n, 1);
        double qv = quadrature(s, pts[i], n, 48, 1, 1e-4);
        assert_true(fabs(v - qv) < 3e-3 * om);
    }
    lie_polylight_work_free(&w);
    lie_polylight_destroy(L);
    lie_scene_destroy(s);
}

static void test_polyshape_planar_emitter_seen_edge_on(void **state)
{
    (void)state;
    /* the L of the previous test, one-sided and two-sided, from points in
     * its plane (nothing) and grazing it from just below */
    float et[6 * 9];
    tri(et, -0.5f, 1, -0.5f, 0.5f, 1, -0.5f, 0.5f, 1, 0.0f);
    tri(et + 9, -0.5f, 1, -0.5f, 0.5f, 1, 0.0f, -0.5f, 1, 0.0f);
    tri(et + 18, -0.5f, 1, 0.0f, 0.0f, 1, 0.0f, 0.0f, 1, 0.5f);
    tri(et + 27, -0.5f, 1, 0.0f, 0.0f, 1, 0.5f, -0.5f, 1, 0.5f);
    for (int two = 0; two < 2; two++) {
        lie_scene *s = emitter_scene(et, 4, two, NULL, 0);
        lie_polylight *L = NULL;
        assert_int_equal(lie_polylight_create(s, 0, &L), LIE_OK);
        assert_non_null(L);
        assert_pieces_cover(L);
        lie_polylight_work w;
        assert_int_equal(lie_polylight_work_init(&w, 8), LIE_OK);
        const lie_vec3 side = lie_v3(-1, 0, 0), tilt = lie_v3_norm(lie_v3(-1.0f, 0.5f, 0.2f));
        /* in the plane: the emitter is a line */
        assert_true(lie_polylight_unshadowed(L, lie_v3(1.5f, 1.0f, 0.2f), side, side, &w) == 0.0);
        assert_true(visible(s, L, &w, lie_v3(1.5f, 1.0f, 0.2f), side, 1) == 0.0);
        /* grazing, 1e-3 below the plane, looking at it sideways */
        const lie_vec3 o = lie_v3(1.5f, 0.999f, 0.2f);
        double om = lie_polylight_unshadowed(L, o, tilt, tilt, &w);
        double q = quadrature(s, o, tilt, 64, 0, 0.0);
        assert_true(om > 0.0 && fabs(om - q) < 5e-3 * q);
        assert_true(fabs(visible(s, L, &w, o, tilt, 1) - om) <= 1e-12 * om);
        /* and from above: only a two-sided emitter is seen */
        const lie_vec3 oa = lie_v3(1.5f, 1.001f, 0.2f), na = lie_v3_norm(lie_v3(-1.0f, -0.5f, 0.2f));
        double above = lie_polylight_unshadowed(L, oa, na, na, &w);
        assert_true(two ? fabs(above - quadrature(s, oa, na, 64, 0, 0.0)) < 5e-3 * above : above == 0.0);
        lie_polylight_work_free(&w);
        lie_polylight_destroy(L);
        lie_scene_destroy(s);
    }
}

static void test_polyshape_bent_emitter_shadows_itself(void **state)
{
    (void)state;
    /* a two-sided roof of two planes (a ridge along z at y = 1.4, eaves
     * at y = 1, x = +-0.5), 8 triangles each side; from a point beside it
     * and low, the near slope hides part of the far one */
    float et[16 * 9];
    int ne = 0;
    for (int k = 0; k < 4; k++) {
        float z0 = -0.5f + 0.25f * (float)k, z1 = z0 + 0.25f;
        tri(et + 9 * ne++, -0.5f, 1, z0, 0, 1.4f, z0, 0, 1.4f, z1);
        tri(et + 9 * ne++, -0.5f, 1, z0, 0, 1.4f, z1, -0.5f, 1, z1);
        tri(et + 9 * ne++, 0, 1.4f, z0, 0.5f, 1, z0, 0.5f, 1, z1);
        tri(et + 9 * ne++, 0, 1.4f, z0, 0.5f, 1, z1, 0, 1.4f, z1);
    }
    lie_scene *s = emitter_scene(et, ne, 1, NULL, 0);
    assert_false(s->emitters[0].planar);
    lie_polylight *L = NULL;
    assert_int_equal(lie_polylight_create(s, 0, &L), LIE_OK);
    assert_non_null(L);
    assert_int_equal(L->n_parts, 2);
    assert_int_equal(L->n_polys, 2); /* each slope tiles a rectangle */
    assert_pieces_cover(L);
    lie_polylight_work w;
    assert_int_equal(lie_polylight_work_init(&w, 64), LIE_OK);
    const lie_vec3 n = lie_v3_norm(lie_v3(-1.0f, 0.4f, 0.1f));
    const lie_vec3 o = lie_v3(1.2f, 1.1f, 0.1f);
    double un = lie_polylight_unshadowed(L, o, n, n, &w);
    double pt = per_triangle(s, o, n);
    assert_true(fabs(un - pt) < 1e-9 * pt);
    /* its own triangles listed as blockers: the near slope shadows the far */
    double v = visible(s, L, &w, o, n, 1);
    double q = quadrature(s, o, n, 48, 2, 1e-4);
    assert_true(v < 0.9 * un);
    assert_true(fabs(v - q) < 3e-3 * un);
    /* the same triangle lists without them: nothing hides anything */
    assert_true(fabs(visible(s, L, &w, o, n, 0) - un) <= 1e-12 * un);
    lie_polylight_work_free(&w);
    lie_polylight_destroy(L);
    lie_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_polyshape_strip_of_1000_triangles),
        cmocka_unit_test(test_polyshape_l_shape_with_a_hole),
        cmocka_unit_test(test_polyshape_planar_emitter_seen_edge_on),
        cmocka_unit_test(test_polyshape_bent_emitter_shadows_itself),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
