/* SPDX-License-Identifier: Apache-2.0 */
/* lib/shade silhouette counting (silhouette.h) against the per-sample
 * test, bit for bit, through the LIE oracle: meshes with shared vertices
 * (a closed sphere, a folded sheet whose facing changes across it, a box),
 * the light's own triangles in the list, a wall hanging from the light's
 * edge, blockers crossing the plane of the point, points in and above the
 * light's plane, one- and two-sided lights. */
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

static int bit(const uint64_t *m, int i) { return (int)((m[i >> 6] >> (i & 63)) & 1u); }

/* the triangles of a mesh as a soup: shared vertices repeated bit for bit */
typedef struct soup {
    float *p;
    int n, cap;
} soup;

static void tri(soup *s, const float *a, const float *b, const float *c)
{
    if (s->n == s->cap) {
        s->cap = s->cap ? 2 * s->cap : 64;
        s->p = realloc(s->p, sizeof(float) * 9 * (size_t)s->cap);
        assert_non_null(s->p);
    }
    float *d = s->p + 9 * (size_t)s->n++;
    memcpy(d, a, 12), memcpy(d + 3, b, 12), memcpy(d + 6, c, 12);
}

/* a grid of (nu + 1) x (nv + 1) points f(u, v), two triangles a cell */
static void grid(soup *s, int nu, int nv, void (*f)(float u, float v, const float *arg, float *out), const float *arg)
{
    for (int i = 0; i < nu; i++)
        for (int j = 0; j < nv; j++) {
            float p[4][3];
            f((float)i / (float)nu, (float)j / (float)nv, arg, p[0]);
            f((float)(i + 1) / (float)nu, (float)j / (float)nv, arg, p[1]);
            f((float)(i + 1) / (float)nu, (float)(j + 1) / (float)nv, arg, p[2]);
            f((float)i / (float)nu, (float)(j + 1) / (float)nv, arg, p[3]);
            tri(s, p[0], p[1], p[2]);
            tri(s, p[0], p[2], p[3]);
        }
}

/* arg: centre x, y, z, radius */
static void sphere(float u, float v, const float *a, float *o)
{
    const float th = 3.14159265f * u, ph = 6.2831853f * (v >= 1.0f ? 0.0f : v);
    o[0] = a[0] + a[3] * sinf(th) * cosf(ph);
    o[1] = a[1] + a[3] * cosf(th);
    o[2] = a[2] + a[3] * sinf(th) * sinf(ph);
}

/* a sheet folded in x (its facing toward points below changes across the
 * folds), tilted so that it crosses the plane of low points */
static void folded(float u, float v, const float *a, float *o)
{
    o[0] = -0.6f + 1.2f * u;
    o[2] = -0.6f + 1.2f * v;
    o[1] = a[0] + 0.25f * sinf(9.0f * u) + a[1] * o[2];
}

static void box(soup *s, float x0, float y0, float z0, float x1, float y1, float z1)
{
    const float c[8][3] = {{x0, y0, z0}, {x1, y0, z0}, {x1, y1, z0}, {x0, y1, z0},
                           {x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}};
    const int f[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {3, 7, 6, 2}, {0, 4, 7, 3}, {1, 2, 6, 5}};
    for (int k = 0; k < 6; k++) {
        tri(s, c[f[k][0]], c[f[k][1]], c[f[k][2]]);
        tri(s, c[f[k][0]], c[f[k][2]], c[f[k][3]]);
    }
}

typedef struct tally {
    long points, counted, samples, fallbacks, edges, tri_edges;
} tally;

/* Every point of a grid below, in and above the light (side 1, at y = 2):
 * the silhouette mask is the per-sample test's, bit for bit. */
static void check_scene(const soup *b, int two_sided, int n, tally *tl)
{
    oracle_fixture fx;
    oracle_fixture_init(&fx, square_light_and_blockers(1.0f, 2.0f, two_sided, b->p, b->n), n);
    const lie_vis_oracle *orc = fx.orc;
    const lie_bitmask *bm = fx.bm;
    assert_non_null(orc->occluded_sil);
    /* every triangle, the light's own two (0 and 1) included */
    const int nb = (int)fx.s->n_tris;
    uint32_t *blockers = malloc(sizeof *blockers * (size_t)nb);
    for (int k = 0; k < nb; k++)
        blockers[k] = (uint32_t)k;
    const size_t stride = ((size_t)nb + 16) & ~(size_t)15;
    float *work = malloc(sizeof(float) * LIE_BLOCKER_WORK * stride);
    uint32_t *kind = malloc(sizeof *kind * stride);
    uint32_t *occ = malloc(sizeof *occ * (size_t)(n + 16));
    float *dx = malloc(sizeof(float) * 3 * (size_t)(n + 16)), *dy = dx + n + 16, *dz = dy + n + 16;
    uint64_t *mask = malloc(sizeof *mask * (size_t)bm->n_words), *mref = malloc(sizeof *mref * (size_t)bm->n_words);
    lie_sil_work sw;
    assert_int_equal(lie_sil_work_init(&sw, nb), LIE_OK);
    assert_true(blockers && work && kind && occ && dx && mask && mref);
    const float heights[5] = {1e-4f, 0.6f, 1.3f, 2.0f, 2.5f};
    for (int gy = 0; gy < 5; gy++)
        for (int gx = 0; gx < 7; gx++)
            for (int gz = 0; gz < 7; gz++) {
                const lie_vec3 o = lie_v3(-1.05f + 0.35f * (float)gx, heights[gy], -1.05f + 0.35f * (float)gz);
                const float eps = 1e-4f;
                lie_shadow_query qs = {o, eps, &bm->ls, n, 0, dx, dy, dz, work, kind, stride, &sw};
                const int ok = orc->occluded_sil(orc->ctx, blockers, nb, &qs, bm, mask);
                const int counted = sw.counted ? sw.n_tris : 0, edges = sw.counted ? sw.n_edges : 0;
                lie_shadow_query qm = {o, eps, &bm->ls, n, 0, dx, dy, dz, work, kind, stride, NULL};
                const int okm = orc->occluded_mask(orc->ctx, blockers, nb, &qm, bm, mref);
                assert_int_equal(ok, okm); /* both answer, or both leave it to 3D tests */
                lie_shadow_query qo = {o, eps, &bm->ls, n, 0, dx, dy, dz, work, kind, stride, NULL};
                orc->occluded(orc->ctx, blockers, nb, &qo, occ);
                tl->points++;
                if (!ok)
                    continue;
                tl->counted += counted > 0;
                tl->edges += edges;
                tl->tri_edges += 3 * counted;
                for (int i = 0; i < n; i++) {
                    assert_int_equal(bit(mask, i), occ[i] != 0); /* the per-sample test's bits */
                    assert_int_equal(bit(mask, i), bit(mref, i));
                }
                for (int i = n; i < 64 * bm->n_words; i++)
                    assert_int_equal(bit(mask, i), 0);
                tl->samples += n;
            }
    lie_sil_work_free(&sw);
    free(mask);
    free(mref);
    free(occ);
    free(dx);
    free(work);
    free(kind);
    free(blockers);
    oracle_fixture_free(&fx);
}

static void run(const char *what, const soup *b, int min_counted)
{
    for (int two_sided = 0; two_sided < 2; two_sided++)
        for (int n = 64; n <= 1024; n *= 4) {
            tally tl = {0, 0, 0, 0, 0, 0};
            check_scene(b, two_sided, n, &tl);
            print_message("silhouette, %s, %s, %d samples: %ld points, %ld counted, %ld samples equal, "
                          "%ld silhouette edges of %ld\n",
                          what, two_sided ? "two-sided" : "one-sided", n, tl.points, tl.counted, tl.samples, tl.edges,
                          tl.tri_edges);
            assert_true(tl.counted >= min_counted);
            assert_true(tl.samples > 0);
        }
}

/* A closed sphere of shared vertices: from outside, its far half and its
 * near half meet at the silhouette; every interior edge is dropped. */
static void test_silhouette_sphere_matches_every_sample(void **state)
{
    (void)state;
    soup b = {0};
    const float a[4] = {0.1f, 1.1f, -0.05f, 0.3f};
    grid(&b, 8, 12, sphere, a);
    tally tl = {0, 0, 0, 0, 0, 0};
    check_scene(&b, 0, 256, &tl);
    assert_true(tl.counted > 50);
    assert_true(tl.edges * 2 < tl.tri_edges); /* most edges interior: dropped */
    run("sphere", &b, 50);
    free(b.p);
}

/* A folded sheet (facing changes across it) tilted through the plane of
 * the low points, a box sharing vertices between faces, the degenerate
 * blockers: a wall hanging from the light's edge, a quad in the light's
 * plane beside it, a triangle seen edge-on. */
static void test_silhouette_folds_boxes_and_degenerate_blockers(void **state)
{
    (void)state;
    soup b = {0};
    const float a[2] = {0.9f, 0.4f};
    grid(&b, 10, 6, folded, a);
    box(&b, 0.3f, 1.4f, 0.2f, 0.6f, 1.7f, 0.45f);
    const float wall[4][3] = {{0.5f, 2.0f, -0.5f}, {0.5f, 2.0f, 0.5f}, {0.5f, 1.5f, 0.5f}, {0.5f, 1.5f, -0.5f}};
    tri(&b, wall[0], wall[1], wall[2]);
    tri(&b, wall[0], wall[2], wall[3]);
    const float beside[4][3] = {{0.5f, 2.0f, -0.5f}, {0.9f, 2.0f, -0.5f}, {0.9f, 2.0f, 0.5f}, {0.5f, 2.0f, 0.5f}};
    tri(&b, beside[0], beside[1], beside[2]);
    tri(&b, beside[0], beside[2], beside[3]);
    const float edge_on[3][3] = {{0.0f, 0.8f, -0.3f}, {0.0f, 1.6f, 0.2f}, {0.0f, 1.2f, 0.4f}};
    tri(&b, edge_on[0], edge_on[1], edge_on[2]);
    run("folds, a box and degenerate blockers", &b, 20);
    free(b.p);
}

/* Fans of triangles whose shared centre lies exactly on the segment from
 * the point to a light sample (the midpoint, exact in float): the sample
 * sees the fan's interior vertex, where the per-sample test's edge forms
 * all vanish.  Half the fans are flat (the centre interior to the mesh),
 * half are cones (the centre a tip the silhouette passes near). */
static void test_silhouette_vertices_through_samples(void **state)
{
    (void)state;
    const int n = 256;
    lie_scene *probe = square_light_and_blockers(1.0f, 2.0f, 0, NULL, 0);
    lie_light_samples ls;
    assert_int_equal(lie_light_samples_alloc(&ls, n), LIE_OK);
    lie_light_samples_generate(probe, 0, n, 0.37f, 0.71f, &ls);
    soup b = {0};
    const float o[3] = {0.0f, 0.5f, 0.0f};
    for (int f = 0; f < 12; f++) {
        const int i = (37 * f + 5) % n;
        const float c[3] = {0.5f * (o[0] + ls.x[i]), 0.5f * (o[1] + ls.y[i]), 0.5f * (o[2] + ls.z[i])};
        float ring[2][6][3]; /* two rings: the centre and the first ring's points are interior */
        for (int r = 0; r < 2; r++)
            for (int k = 0; k < 6; k++) {
                const float a = 1.0471976f * ((float)k + 0.5f * (float)r);
                ring[r][k][0] = c[0] + 0.015f * (float)(r + 1) * cosf(a);
                ring[r][k][1] = c[1] + (f & 1 ? -0.01f * (float)(r + 1) : 0.0f);
                ring[r][k][2] = c[2] + 0.015f * (float)(r + 1) * sinf(a);
            }
        for (int k = 0; k < 6; k++) {
            tri(&b, c, ring[0][(k + 1) % 6], ring[0][k]);
            tri(&b, ring[0][k], ring[0][(k + 1) % 6], ring[1][k]);
            tri(&b, ring[0][(k + 1) % 6], ring[1][(k + 1) % 6], ring[1][k]);
        }
    }
    lie_light_samples_free(&ls);
    lie_scene_destroy(probe);
    oracle_fixture fx;
    oracle_fixture_init(&fx, square_light_and_blockers(1.0f, 2.0f, 0, b.p, b.n), n);
    const int nb = (int)fx.s->n_tris;
    uint32_t *blockers = malloc(sizeof *blockers * (size_t)nb);
    const size_t stride = ((size_t)nb + 16) & ~(size_t)15;
    float *work = malloc(sizeof(float) * LIE_BLOCKER_WORK * stride);
    uint32_t *kind = malloc(sizeof *kind * stride), *occ = malloc(sizeof *occ * (size_t)(n + 16));
    float *dx = malloc(sizeof(float) * 3 * (size_t)(n + 16)), *dy = dx + n + 16, *dz = dy + n + 16;
    uint64_t mask[8];
    lie_sil_work sw;
    assert_int_equal(lie_sil_work_init(&sw, nb), LIE_OK);
    assert_true(blockers && work && kind && occ && dx);
    for (int k = 0; k < nb; k++)
        blockers[k] = (uint32_t)k;
    long counted = 0, checked = 0;
    /* the point itself, and the point nudged by an ulp or so */
    for (int v = 0; v < 3; v++) {
        const lie_vec3 P = lie_v3(o[0] + (float)v * 1e-7f, o[1], o[2] - (float)v * 1e-7f);
        lie_shadow_query qs = {P, 1e-4f, &fx.bm->ls, n, 0, dx, dy, dz, work, kind, stride, &sw};
        const int ok = fx.orc->occluded_sil(fx.orc->ctx, blockers, nb, &qs, fx.bm, mask);
        assert_true(ok);
        counted += sw.counted;
        lie_shadow_query qo = {P, 1e-4f, &fx.bm->ls, n, 0, dx, dy, dz, work, kind, stride, NULL};
        fx.orc->occluded(fx.orc->ctx, blockers, nb, &qo, occ);
        for (int i = 0; i < n; i++, checked++)
            assert_int_equal(bit(mask, i), occ[i] != 0);
    }
    print_message("silhouette, fans through samples: %ld of 3 points counted, %ld samples equal\n", counted, checked);
    assert_true(counted > 0);
    lie_sil_work_free(&sw);
    free(blockers);
    free(work);
    free(kind);
    free(occ);
    free(dx);
    oracle_fixture_free(&fx);
    free(b.p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_silhouette_sphere_matches_every_sample),
        cmocka_unit_test(test_silhouette_folds_boxes_and_degenerate_blockers),
        cmocka_unit_test(test_silhouette_vertices_through_samples),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
