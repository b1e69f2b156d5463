/* SPDX-License-Identifier: Apache-2.0 */
/* ltc-bench (`make ltc-bench`): the accuracy of lib/shade/ltc against the
 * Monte Carlo reference of tests/unit/ltc_mc.h, per roughness and view
 * angle over a fixed set of polygons, and the cost of one polygon in ns.
 * Not a test: it prints tables (for README.md and reports). */
#include <stdio.h>
#include <time.h>

#include "../unit/ltc_mc.h"

#define MC_N 65536

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Per (roughness, view angle): the worst relative error over the polygons
 * holding at least 10% of the lobe (its integral over the hemisphere), and
 * the worst error over all polygons in units of that hemisphere integral
 * (the tails of a lobe, where an LTC is least faithful, hold little). */
static void accuracy(const lie_ltc_table *T, const char *title, float metallic, const float base[3])
{
    static const float rough[] = {0.05f, 0.1f, 0.2f, 0.3f, 0.5f, 0.75f, 1.0f};
    static const float angle[] = {0.0f, 30.0f, 60.0f, 75.0f, 85.0f};
    printf("\n%s.\nEach cell: worst relative error over the polygons holding >= 10%% of the\n"
           "hemisphere integral / worst error over all 5 polygons in units of the\n"
           "hemisphere integral (MC: %d x 3 samples)\n\n| roughness |",
           title, MC_N);
    for (size_t a = 0; a < sizeof angle / sizeof *angle; a++)
        printf(" %g° |", (double)angle[a]);
    printf("\n|---|");
    for (size_t a = 0; a < sizeof angle / sizeof *angle; a++)
        printf("---|");
    printf("\n");
    for (size_t i = 0; i < sizeof rough / sizeof *rough; i++) {
        printf("| %.2f |", (double)rough[i]);
        for (size_t a = 0; a < sizeof angle / sizeof *angle; a++) {
            lie_surface sf = ltc_mc_surface(lie_v3(0, 0, 1), ltc_view(angle[a]), rough[i], metallic, base);
            lie_ltc_shading sh;
            lie_ltc_shading_from_surface(T, &sf, &sh);
            lie_vec3 poly[5][4], sky[4];
            int nv[5], np = 5;
            ltc_polygons(angle[a], poly, nv);
            ltc_sky(sky);
            double hemi[3];
            ltc_mc_polygon(&sf, sky, 4, MC_N, hemi);
            double H = hemi[0] + hemi[1] + hemi[2];
            double worst_rel = 0.0, worst_abs = 0.0;
            for (int p = 0; p < np; p++) {
                double mc[3];
                float l[3];
                ltc_mc_polygon(&sf, poly[p], nv[p], MC_N, mc);
                lie_ltc_polygon(&sh, poly[p], nv[p], l);
                double ref = mc[0] + mc[1] + mc[2], got = (double)l[0] + l[1] + l[2];
                double e = fabs(got - ref);
                if (ref >= 0.1 * H && e / ref > worst_rel)
                    worst_rel = e / ref;
                if (e / H > worst_abs)
                    worst_abs = e / H;
            }
            printf(" %.1f%% / %.1f%% |", 100.0 * worst_rel, 100.0 * worst_abs);
        }
        printf("\n");
    }
}

static void cost(void)
{
    enum { NP = 1024, REPS = 2000 };
    static lie_vec3 tri[NP][3], quad[NP][4];
    for (int i = 0; i < NP; i++) {
        float u = lie_hash_to_unit(lie_hash_u64x4((uint64_t)i, 1, 0, 0));
        float v = lie_hash_to_unit(lie_hash_u64x4((uint64_t)i, 2, 0, 0));
        lie_vec3 c = lie_v3_norm(lie_v3(2.0f * u - 1.0f, 2.0f * v - 1.0f, 1.0f));
        ltc_square_toward(c, 2.0f, 0.3f + 0.5f * u, quad[i]);
        tri[i][0] = quad[i][0];
        tri[i][1] = quad[i][1];
        tri[i][2] = quad[i][2];
    }
    const lie_ltc_table *T = lie_ltc_table_default();
    float base[3] = {0.8f, 0.6f, 0.4f};
    lie_vec3 n = lie_v3(0, 0, 1), wo = lie_v3_norm(lie_v3(0.5f, 0.0f, 1.0f));
    lie_surface ggx = ltc_mc_surface(n, wo, 0.4f, 0.0f, base);
    lie_surface lam = ltc_mc_surface(n, wo, 1.0f, 0.0f, base);
    printf("\nCost per call, ns (%d polygons x %d repetitions, one thread):\n\n"
           "| call | ns |\n|---|---|\n",
           NP, REPS);
    volatile float sink = 0.0f;
    lie_ltc_table paper = *T;
    paper.ggx_fresnel = NULL;
    lie_surface metal = ltc_mc_surface(n, wo, 0.4f, 1.0f, (const float[3]){1.0f, 1.0f, 1.0f});
    struct {
        const char *name;
        const lie_ltc_table *t;
        const lie_surface *sf;
        int verts;
    } cases[] = {{"lie_ltc_polygon, dielectric GGX (3 LTCs), triangle", T, &ggx, 3},
                 {"lie_ltc_polygon, dielectric GGX (3 LTCs), quad", T, &ggx, 4},
                 {"the same with the paper's Fresnel split (2 LTCs), quad", &paper, &ggx, 4},
                 {"lie_ltc_polygon, white metal (f0 = 1: 2 LTCs), quad", T, &metal, 4},
                 {"lie_ltc_polygon, Lambert (edge sum), triangle", T, &lam, 3},
                 {"lie_ltc_polygon, Lambert (edge sum), quad", T, &lam, 4}};
    for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
        lie_ltc_shading sh;
        lie_ltc_shading_from_surface(cases[c].t, cases[c].sf, &sh);
        float acc = 0.0f;
        double t0 = now();
        for (int r = 0; r < REPS; r++)
            for (int i = 0; i < NP; i++) {
                float o[3];
                lie_ltc_polygon(&sh, cases[c].verts == 3 ? tri[i] : quad[i], cases[c].verts, o);
                acc += o[0];
            }
        double t1 = now();
        sink += acc;
        printf("| %s | %.1f |\n", cases[c].name, 1e9 * (t1 - t0) / ((double)NP * REPS));
    }
    float acc = 0.0f;
    double t0 = now();
    for (int r = 0; r < REPS; r++)
        for (int i = 0; i < NP; i++) {
            lie_ltc_shading sh;
            lie_vec3 w = lie_v3_norm(lie_v3(quad[i][0].x, quad[i][0].y, 2.0f));
            lie_ltc_shading_init(T, n, w, 0.4f, ggx.f0, ggx.diffuse, &sh);
            acc += sh.spec_w[0];
        }
    double t1 = now();
    sink += acc;
    printf("| lie_ltc_shading_init (per shading point) | %.1f |\n", 1e9 * (t1 - t0) / ((double)NP * REPS));
    (void)sink;
}

int main(void)
{
    float white[3] = {1.0f, 1.0f, 1.0f}, grey[3] = {0.5f, 0.5f, 0.5f};
    const lie_ltc_table *T = lie_ltc_table_default();
    lie_ltc_table paper = *T; /* the LTC paper's scalar Fresnel split alone */
    paper.ggx_fresnel = NULL;
    accuracy(T, "Specular only (metallic 1, base colour 1: F = 1, no diffuse)", 1.0f, white);
    accuracy(T, "Dielectric (metallic 0, base colour 0.5: Fresnel-weighted diffuse + specular)", 0.0f, grey);
    accuracy(&paper, "The same dielectric with the paper's scalar Fresnel split (no ggx_fresnel table)", 0.0f, grey);
    float gold[3] = {1.0f, 0.78f, 0.34f};
    accuracy(T, "Gold-like metal (metallic 1, base colour 1, 0.78, 0.34)", 1.0f, gold);
    cost();
    return 0;
}
