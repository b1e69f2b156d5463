/* SPDX-License-Identifier: Apache-2.0 */
/* bench-light-classes SCENE CAMERA [K [STEP [PATCH [CLUSTERS]]]]: what the best
 * LIE could save, measured from the scene itself (an oracle: no cache).
 *
 * For the pixels of a 256 x 256 view (every STEP-th, default 4) it takes
 * the point the camera sees and every triangle of every area emitter, and
 * measures with K shadow rays per triangle (default 16, stratified, Embree)
 * the share v_t of the triangle's light that reaches the point; U_t is the
 * triangle's unshadowed light there (Lambert's closed form,
 * lie_triangle_unshadowed, times its mean emission over the K points, so
 * emissive textures count).  Light L = sum U_t v_t.
 *
 * A LIE unit (a patch and an emitter, or a part of one) that is wholly
 * visible is shaded in closed form, an occluded one costs nothing; only
 * partial units take samples.  With light samples chosen in proportion to
 * U (better than any light tree) and one shadow ray each, a sample's
 * variance is L (U - L) when every unit is sampled (full visibility) and
 * L_P (U_P - L_P) when only the partial units P are (the LIE: visible units
 * exact, occluded ones dropped).  Per pixel their ratio is how many fewer
 * samples the LIE needs for the same noise; the table gives, over the
 * lit pixels, the p99 of the relative variance var / L^2 (the error
 * metric of bench/quality.sh is a p99 per pixel) for:
 *   full       every unit sampled;
 *   emitter    units of whole emitters (the paper's; what lie-build
 *              builds), classified at the point itself (a patch of zero
 *              size);
 *   triangle   units of single emitter triangles, at the point itself: the
 *              finest LIE there can be (patches of zero size);
 *   emitter-patch  the same on a square patch around the point, PATCH
 *              pixels wide at the point's distance (default 8; a patch
 *              that is not square to the view is larger);
 *   cluster, cluster-patch  units of an emitter's clusters (lie-build
 *              --emitter-clusters CLUSTERS, default 16, the most there can
 *              be), at the point and on the patch;
 *   tri-patch  units of single triangles on that patch.
 * and the shares of the light from partial units.  This ignores what each
 * answer costs (closed forms, lists): it bounds the LIE's gain at equal
 * quality from above; docs/measurements.md, "What the LIE can save on
 * real scenes", has the figures. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lie.h"
#include "rt/rt.h"
#include "shade/polylight.h"

enum { UNIT_EMITTER, UNIT_EMITTER_PATCH, UNIT_CLUSTER, UNIT_CLUSTER_PATCH, UNIT_TRI, UNIT_TRI_PATCH, N_UNITS };
static const char *const unit_name[N_UNITS] = {"emitter", "emitter-patch", "cluster", "cluster-patch", "triangle", "tri-patch"};

typedef struct job {
    const lie_scene *s;
    const lie_rt *rt;
    lie_view v;
    int size, step, k, cols;
    float patch, pixel;
    /* per sampled pixel, -1 where nothing lit is seen */
    float *rel_full, *rel[N_UNITS];
    double *light, *partial[N_UNITS];
} job;

static uint64_t mix(uint64_t x)
{
    x ^= x >> 33, x *= 0xff51afd7ed558ccdull, x ^= x >> 33, x *= 0xc4ceb9fe1a85ec53ull;
    return x ^ (x >> 33);
}
static float rnd(uint64_t *st)
{
    *st = mix(*st + 0x9e3779b97f4a7c15ull);
    return (float)(*st >> 40) * (1.0f / 16777216.0f);
}

static float luminance(const float c[3]) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

/* the emission of triangle t at barycentrics (b1, b2), its texture applied */
static float emission(const lie_scene *s, const lie_emitter *em, uint32_t t, float b1, float b2)
{
    const lie_material *m = lie_scene_material(s, s->tri_material[t]);
    float le = luminance(em->radiance);
    if (m->emissive_tex >= 0 && m->emissive_tex < s->n_textures) {
        float rgba[4], u, v;
        lie_scene_slot_uv(s, m, LIE_TEX_EMISSIVE, t, b1, b2, &u, &v);
        lie_texture_sample(&s->textures[m->emissive_tex], u, v, rgba);
        le *= luminance(rgba);
    }
    return le;
}

typedef struct acc {
    double U, L; /* unshadowed, shadowed */
} acc;
static void acc_add(acc *a, double U, double L) { a->U += U, a->L += L; }

static void pixel(void *ctx, size_t item, int worker)
{
    (void)worker;
    job *j = ctx;
    const lie_scene *s = j->s;
    int px = (int)(item % (size_t)j->cols) * j->step + j->step / 2;
    int py = (int)(item / (size_t)j->cols) * j->step + j->step / 2;
    j->rel_full[item] = -1.0f;
    lie_vec3 org, dir;
    lie_view_ray(&j->v, px + 0.5f, py + 0.5f, j->size, j->size, &org, &dir);
    lie_hit h;
    if (!lie_rt_intersect(j->rt, org, dir, 0.0f, INFINITY, 1, &h) || h.tri == LIE_NO_HIT ||
        s->tri_emitter[h.tri] >= 0)
        return;
    lie_vec3 ng = s->tri_ng[h.tri];
    if (ng.x * dir.x + ng.y * dir.y + ng.z * dir.z > 0.0f)
        ng = lie_v3_scale(ng, -1.0f);
    lie_vec3 p = lie_v3_add(org, lie_v3_scale(dir, h.t));
    /* the patch's frame */
    lie_vec3 t1 = fabsf(ng.x) < 0.9f ? lie_v3(0.0f, ng.z, -ng.y) : lie_v3(-ng.z, 0.0f, ng.x);
    t1 = lie_v3_norm(t1);
    lie_vec3 t2 = lie_v3_cross(ng, t1);
    float side = j->patch * h.t * j->pixel; /* PATCH pixels' footprint, square to the view */
    uint64_t st = mix(item * 7919u + 17u);

    acc all = {0, 0}, part[N_UNITS];
    memset(part, 0, sizeof part);
    for (int e = 0; e < s->n_emitters; e++) {
        const lie_emitter *em = &s->emitters[e];
        if (em->type != LIE_EMITTER_AREA)
            continue;
        acc whole = {0, 0}, cl[LIE_CLUSTER_MAX];
        int whole_seen = 0, whole_blocked = 0, whole_pseen = 0, whole_pblocked = 0;
        int cl_seen[LIE_CLUSTER_MAX][4]; /* seen, blocked at the point; the same on the patch */
        memset(cl, 0, sizeof cl);
        memset(cl_seen, 0, sizeof cl_seen);
        for (uint32_t k = 0; k < em->n_tris; k++) {
            uint32_t t = em->first_tri + k;
            const lie_vec3 *P = s->tri_p + 3 * (size_t)t;
            double U = lie_triangle_unshadowed(P, em->double_sided, p, ng, ng);
            if (!(U > 0.0))
                continue;
            double e_sum = 0.0, e_seen = 0.0;
            int seen = 0, blocked = 0, pseen = 0, pblocked = 0;
            for (int i = 0; i < j->k; i++) {
                float su = sqrtf((i + rnd(&st)) / j->k), u2 = rnd(&st);
                float b1 = su * (1.0f - u2), b2 = su * u2; /* area-uniform */
                lie_vec3 q = lie_v3_add(lie_v3_scale(P[0], 1.0f - b1 - b2),
                                        lie_v3_add(lie_v3_scale(P[1], b1), lie_v3_scale(P[2], b2)));
                float le = emission(s, em, t, b1, b2);
                lie_vec3 so, sd;
                float tn, tf;
                int vis = 0;
                if (lie_shadow_segment(p, ng, q, &so, &sd, &tn, &tf))
                    vis = !lie_rt_occluded(j->rt, so, sd, tn, tf);
                e_sum += le;
                e_seen += vis ? le : 0.0;
                if (le > 0.0f)
                    vis ? seen++ : blocked++;
                /* the same emitter point from elsewhere on the patch */
                float du = (rnd(&st) - 0.5f) * side, dv = (rnd(&st) - 0.5f) * side;
                lie_vec3 a = lie_v3_add(p, lie_v3_add(lie_v3_scale(t1, du), lie_v3_scale(t2, dv)));
                if (lie_shadow_segment(a, ng, q, &so, &sd, &tn, &tf) && le > 0.0f)
                    lie_rt_occluded(j->rt, so, sd, tn, tf) ? pblocked++ : pseen++;
            }
            if (!(e_sum > 0.0))
                continue;
            U *= e_sum / j->k;
            double L = U * (e_seen / e_sum);
            acc_add(&all, U, L);
            acc_add(&whole, U, L);
            whole_seen += seen, whole_blocked += blocked;
            whole_pseen += pseen, whole_pblocked += pblocked;
            int ci = s->tri_cluster[t] - em->first_cluster;
            acc_add(&cl[ci], U, L);
            cl_seen[ci][0] += seen, cl_seen[ci][1] += blocked, cl_seen[ci][2] += pseen, cl_seen[ci][3] += pblocked;
            if (seen && blocked)
                acc_add(&part[UNIT_TRI], U, L);
            if ((seen || pseen) && (blocked || pblocked))
                acc_add(&part[UNIT_TRI_PATCH], U, L);
        }
        if (whole_seen && whole_blocked)
            acc_add(&part[UNIT_EMITTER], whole.U, whole.L);
        if ((whole_seen || whole_pseen) && (whole_blocked || whole_pblocked))
            acc_add(&part[UNIT_EMITTER_PATCH], whole.U, whole.L);
        for (int ci = 0; ci < em->n_clusters; ci++) {
            const int *q = cl_seen[ci];
            if (q[0] && q[1])
                acc_add(&part[UNIT_CLUSTER], cl[ci].U, cl[ci].L);
            if ((q[0] || q[2]) && (q[1] || q[3]))
                acc_add(&part[UNIT_CLUSTER_PATCH], cl[ci].U, cl[ci].L);
        }
    }
    if (!(all.L > 0.0))
        return;
    double L2 = all.L * all.L;
    j->light[item] = all.L;
    j->rel_full[item] = (float)(all.L * (all.U - all.L) / L2);
    for (int u = 0; u < N_UNITS; u++) {
        j->rel[u][item] = (float)(part[u].L * (part[u].U - part[u].L) / L2);
        j->partial[u][item] = part[u].L;
    }
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

static float p99(float *v, int n)
{
    if (n == 0)
        return 0.0f;
    qsort(v, (size_t)n, sizeof *v, cmp_float);
    return v[(int)floor(0.99 * (n - 1))];
}

int main(int argc, char **argv)
{
    if (argc < 3 || argc > 7) {
        fprintf(stderr, "usage: bench-light-classes SCENE CAMERA [K [STEP [PATCH [CLUSTERS]]]]\n");
        return 2;
    }
    job j;
    memset(&j, 0, sizeof j);
    j.size = 256;
    j.k = argc > 3 ? atoi(argv[3]) : 16;
    j.step = argc > 4 ? atoi(argv[4]) : 4;
    j.patch = argc > 5 ? (float)atof(argv[5]) : 8.0f;
    if (j.k < 2 || j.k > 4096 || j.step < 1 || j.step > 256 || !(j.patch >= 0.0f)) {
        fprintf(stderr, "bench-light-classes: K 2..4096, STEP 1..256, PATCH >= 0\n");
        return 2;
    }
    lie_error err;
    memset(&err, 0, sizeof err);
    lie_scene *s = NULL;
    lie_rt *rt = NULL;
    lie_camera cam;
    lie_scene_options so = lie_scene_options_default();
    so.emitter_clusters = argc > 6 ? atoi(argv[6]) : LIE_CLUSTER_MAX;
    if (lie_scene_load(argv[1], &so, &s, &err) != LIE_OK || lie_rt_create(s, &rt, &err) != LIE_OK ||
        lie_camera_parse(s, argv[2], &cam, &err) != LIE_OK) {
        fprintf(stderr, "bench-light-classes: %s: %s\n", err.file[0] ? err.file : argv[1], err.msg);
        lie_rt_destroy(rt);
        lie_scene_destroy(s);
        return 1;
    }
    j.s = s, j.rt = rt;
    j.v = lie_view_make(&cam, j.size, j.size);
    j.pixel = 2.0f * j.v.half_h / (float)j.size;
    j.cols = (j.size + j.step - 1) / j.step;
    size_t n = (size_t)j.cols * (size_t)j.cols;
    j.rel_full = calloc(n, sizeof(float));
    j.light = calloc(n, sizeof(double));
    int ok = j.rel_full && j.light;
    for (int u = 0; u < N_UNITS; u++) {
        j.rel[u] = calloc(n, sizeof(float));
        j.partial[u] = calloc(n, sizeof(double));
        ok = ok && j.rel[u] && j.partial[u];
    }
    if (!ok || lie_parallel_for(n, 2, pixel, &j, NULL, NULL) != LIE_OK) {
        fprintf(stderr, "bench-light-classes: out of memory\n");
        return 1;
    }
    /* gather the lit pixels */
    int m = 0;
    double light = 0.0, partial[N_UNITS] = {0};
    for (size_t i = 0; i < n; i++) {
        if (j.rel_full[i] < 0.0f)
            continue;
        j.rel_full[m] = j.rel_full[i];
        for (int u = 0; u < N_UNITS; u++) {
            j.rel[u][m] = j.rel[u][i];
            partial[u] += j.partial[u][i];
        }
        light += j.light[i];
        m++;
    }
    /* a JSON line, then the same in words (bench/light-bound.sh prints it);
     * no partial light at all: the LIE needs no samples (null) */
    float full = p99(j.rel_full, m), r[N_UNITS];
    for (int u = 0; u < N_UNITS; u++)
        r[u] = p99(j.rel[u], m);
    printf("{\"scene\":\"%s\",\"pixels\":%d,\"k\":%d,\"patch\":%g,\"p99_rel_var_full\":%.4g", argv[1], m, j.k,
           (double)j.patch, (double)full);
    for (int u = 0; u < N_UNITS; u++) {
        printf(",\"%s\":{\"partial_light\":%.4f,\"p99_rel_var\":%.4g,\"samples_saved\":", unit_name[u],
               light > 0.0 ? partial[u] / light : 0.0, (double)r[u]);
        r[u] > 0.0f ? printf("%.4g}", (double)(full / r[u])) : printf("null}");
    }
    printf("}\n");
    if (m == 0)
        printf("no area emitter lights a pixel\n");
    for (int u = 0; m > 0 && u < N_UNITS; u++) {
        if (r[u] > 0.0f)
            printf("%s%s %.3g (%.0f%%)", u ? ", " : "", unit_name[u], (double)(full / r[u]), 100.0 * partial[u] / light);
        else
            printf("%s%s all (0%%)", u ? ", " : "", unit_name[u]);
    }
    if (m > 0)
        printf("\n");
    free(j.rel_full);
    free(j.light);
    for (int u = 0; u < N_UNITS; u++) {
        free(j.rel[u]);
        free(j.partial[u]);
    }
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
    return 0;
}
