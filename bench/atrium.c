/* SPDX-License-Identifier: Apache-2.0 */
/* atrium-gen DIR: a Sponza-class bench scene for make bench-build (issue
 * 14's 250k-triangle target), generated, never committed.
 *
 * A two-storey atrium open to the sky: a court with a finely tiled floor,
 * arcades of turned columns and round arches on both long sides, corridors
 * behind them with back walls and ceilings, a balustrade of turned
 * balusters on the upper floor, banners (curtains with folds) hanging in
 * the upper arches, and large vases in the court; about 250,000 triangles,
 * and no light.  Written as DIR/atrium.gltf (+ .bin), with a camera
 * "Camera" looking down the court.  The lights come from an edit file, as
 * a user would add them to a scene that has none: DIR/lights.gltf holds
 * one emissive panel, DIR/lights.yaml adds four copies of it under the open
 * roof (formats/edit.md).
 *
 * Output is a function of the program: no randomness, no time. */
#include "../tests/scenes/gen/gen_gltf.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979f

#define HALF_X 15.0f     /* the court runs x in [-15, 15] */
#define ARCADE_Z 5.0f    /* columns stand at z = +-5 */
#define BACK_Z 8.0f      /* corridor back walls */
#define STOREY 5.0f      /* floor to floor */
#define N_BAYS 12        /* columns per side and storey */
#define BAY (2.0f * HALF_X / (float)N_BAYS)

/* A smooth solid of revolution: radius r(t) for t in [0, 1] over height h,
 * closed by flat caps; k profile steps, segs around. */
static void turned(gen_geom *m, float h, int k, int segs, float (*r)(float t))
{
    float(*prof)[4] = malloc(sizeof *prof * (size_t)(k + 5));
    if (!prof) {
        m->failed = 1;
        return;
    }
    int n = 0;
    float r0 = r(0.0f), r1 = r(1.0f);
    prof[n][0] = 0, prof[n][1] = 0, prof[n][2] = 0, prof[n][3] = -1, n++;
    prof[n][0] = r0, prof[n][1] = 0, prof[n][2] = 0, prof[n][3] = -1, n++;
    for (int i = 0; i <= k; i++) {
        float t = (float)i / (float)k, dt = 1e-3f;
        float ri = r(t), dr = (r(fminf(t + dt, 1.0f)) - r(fmaxf(t - dt, 0.0f))) / (2.0f * dt * h);
        float len = sqrtf(1.0f + dr * dr);
        prof[n][0] = ri, prof[n][1] = t * h, prof[n][2] = 1.0f / len, prof[n][3] = -dr / len, n++;
    }
    prof[n][0] = r1, prof[n][1] = h, prof[n][2] = 0, prof[n][3] = 1, n++;
    prof[n][0] = 0, prof[n][1] = h, prof[n][2] = 0, prof[n][3] = 1, n++;
    gen_geom_lathe(m, (const float(*)[4])prof, n, segs);
    free(prof);
}

/* a column: base torus, entasis, a capital flaring out */
static float column_r(float t)
{
    float r = 0.30f * (1.0f - 0.12f * t) + 0.015f * sinf(40.0f * PI * t) * (t > 0.1f && t < 0.85f);
    if (t < 0.08f)
        r += 0.10f * sinf(PI * t / 0.08f);
    if (t > 0.88f)
        r += 0.16f * (t - 0.88f) / 0.12f;
    return r;
}

static float baluster_r(float t)
{
    return 0.05f + 0.045f * sinf(PI * t) * sinf(PI * t) + 0.02f * (t < 0.1f || t > 0.9f);
}

static float vase_r(float t)
{
    return 0.25f + 0.45f * sinf(PI * (0.15f + 0.7f * t)) - 0.25f * t * t + 0.1f * (t > 0.92f);
}

/* A vertex with its normal. */
static uint32_t vtx(gen_geom *m, float x, float y, float z, float nx, float ny, float nz)
{
    float p[3] = {x, y, z}, n[3] = {nx, ny, nz};
    return gen_geom_vertex(m, p, n, NULL);
}

/* Quad a b c d (in order around it) as two triangles (a, b, c), (a, c, d),
 * or wound the other way round when flip: (a, d, c), (a, c, b). */
static void quad(gen_geom *m, uint32_t a, uint32_t b, uint32_t c, uint32_t d, int flip)
{
    if (flip) {
        gen_geom_tri(m, a, d, c);
        gen_geom_tri(m, a, c, b);
    } else {
        gen_geom_tri(m, a, b, c);
        gen_geom_tri(m, a, c, d);
    }
}

/* A quad subdivided into nu x nv cells: corner o, edges eu and ev, normal n. */
static void grid(gen_geom *m, const float o[3], const float eu[3], const float ev[3], int nu, int nv,
                 const float n[3])
{
    uint32_t base = m->n_verts;
    for (int j = 0; j <= nv; j++)
        for (int i = 0; i <= nu; i++) {
            float u = (float)i / (float)nu, v = (float)j / (float)nv;
            vtx(m, o[0] + u * eu[0] + v * ev[0], o[1] + u * eu[1] + v * ev[1], o[2] + u * eu[2] + v * ev[2], n[0],
                n[1], n[2]);
        }
    /* counter-clockwise seen from n: eu x ev must point along n */
    float c[3] = {eu[1] * ev[2] - eu[2] * ev[1], eu[2] * ev[0] - eu[0] * ev[2], eu[0] * ev[1] - eu[1] * ev[0]};
    int flip = c[0] * n[0] + c[1] * n[1] + c[2] * n[2] < 0.0f;
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            uint32_t a = base + (uint32_t)(j * (nu + 1) + i), b = a + 1, d = a + (uint32_t)(nu + 1), e = d + 1;
            quad(m, a, b, e, d, flip);
        }
}

/* A round arch between x0 and x1 springing at height y, in the plane
 * z = zc, `depth` thick and `band` deep: the intrados and both faces. */
static void arch(gen_geom *m, float x0, float x1, float y, float zc, float depth, float band, int segs)
{
    float cx = 0.5f * (x0 + x1), R = 0.5f * (x1 - x0), z0 = zc - 0.5f * depth, z1 = zc + 0.5f * depth;
    for (int i = 0; i < segs; i++) {
        float a0 = PI * (float)i / (float)segs, a1 = PI * (float)(i + 1) / (float)segs;
        float c0 = cosf(a0), s0 = sinf(a0), c1 = cosf(a1), s1 = sinf(a1);
        /* intrados, facing the arch's centre */
        uint32_t p = vtx(m, cx + R * c0, y + R * s0, z0, -c0, -s0, 0);
        uint32_t q = vtx(m, cx + R * c1, y + R * s1, z0, -c1, -s1, 0);
        uint32_t r = vtx(m, cx + R * c1, y + R * s1, z1, -c1, -s1, 0);
        uint32_t t = vtx(m, cx + R * c0, y + R * s0, z1, -c0, -s0, 0);
        quad(m, p, q, r, t, 1);
        for (int side = 0; side < 2; side++) {
            float z = side ? z1 : z0, nz = side ? 1.0f : -1.0f, Ro = R + band;
            uint32_t a = vtx(m, cx + R * c0, y + R * s0, z, 0, 0, nz);
            uint32_t b = vtx(m, cx + R * c1, y + R * s1, z, 0, 0, nz);
            uint32_t c = vtx(m, cx + Ro * c1, y + Ro * s1, z, 0, 0, nz);
            uint32_t d = vtx(m, cx + Ro * c0, y + Ro * s0, z, 0, 0, nz);
            quad(m, a, b, c, d, side);
        }
    }
}

/* A banner hanging from (x, top, z), w wide, h long, with folds; both
 * sides lit (the material is double-sided). */
static void banner(gen_geom *m, float x, float top, float z, float w, float h, float sign, int nu, int nv)
{
    uint32_t base = m->n_verts;
    for (int j = 0; j <= nv; j++)
        for (int i = 0; i <= nu; i++) {
            float u = (float)i / (float)nu, v = (float)j / (float)nv;
            float ph = 2.0f * PI * 5.0f * u, amp = 0.08f * (0.3f + 0.7f * v);
            float px = x - 0.5f * w + u * w, py = top - v * h, pz = z + sign * amp * sinf(ph);
            float dzdx = sign * amp * cosf(ph) * 2.0f * PI * 5.0f / w;
            float len = sqrtf(1.0f + dzdx * dzdx);
            vtx(m, px, py, pz, sign * dzdx / len, 0, -sign / len); /* towards the court */
        }
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            uint32_t a = base + (uint32_t)(j * (nu + 1) + i), b = a + 1, d = a + (uint32_t)(nu + 1), e = d + 1;
            if (sign > 0) { /* (a, b, e) faces -z */
                gen_geom_tri(m, a, b, e);
                gen_geom_tri(m, a, e, d);
            } else {
                gen_geom_tri(m, a, e, b);
                gen_geom_tri(m, a, d, e);
            }
        }
}

static void box(gen_geom *m, float x0, float y0, float z0, float x1, float y1, float z1)
{
    float lo[3] = {x0, y0, z0}, hi[3] = {x1, y1, z1};
    gen_geom_box(m, lo, hi);
}

/* One mesh node at the origin. */
static int add_object(gen_gltf *g, const char *name, const gen_geom *m, int material)
{
    gen_prim prim = {m, material};
    int mesh = gen_gltf_add_mesh(g, name, &prim, 1);
    gen_node nd = GEN_NODE_INIT;
    nd.name = name;
    nd.mesh = mesh;
    return mesh < 0 ? -1 : gen_gltf_add_node(g, &nd);
}

static int material(gen_gltf *g, const char *name, float r, float gr, float b, int two_sided)
{
    gen_material mt = GEN_MATERIAL_INIT;
    mt.name = name;
    mt.base_color[0] = r;
    mt.base_color[1] = gr;
    mt.base_color[2] = b;
    mt.roughness = 0.8f;
    mt.double_sided = two_sided;
    return gen_gltf_add_material(g, &mt);
}

static int write_atrium(const char *dir, char *err, size_t n_err)
{
    gen_gltf *g = gen_gltf_create();
    if (!g)
        return snprintf(err, n_err, "out of memory"), -1;
    int stone = material(g, "Stone", 0.62f, 0.57f, 0.50f, 0);
    int floor_m = material(g, "Floor", 0.45f, 0.40f, 0.34f, 0);
    int cloth[2] = {material(g, "ClothRed", 0.55f, 0.08f, 0.06f, 1), material(g, "ClothBlue", 0.08f, 0.15f, 0.5f, 1)};
    int clay = material(g, "Clay", 0.6f, 0.3f, 0.18f, 0);

    gen_geom m;
    /* the court's floor and the corridors' floors, tiled finely */
    gen_geom_init(&m);
    {
        float o[3] = {-HALF_X, 0, -BACK_Z}, eu[3] = {2 * HALF_X, 0, 0}, ev[3] = {0, 0, 2 * BACK_Z}, n[3] = {0, 1, 0};
        grid(&m, o, eu, ev, 120, 64, n);
    }
    add_object(g, "Floor", &m, floor_m);
    gen_geom_free(&m);

    /* walls: corridor backs, the two ends, and the upper floors' slabs */
    gen_geom_init(&m);
    for (int s = -1; s <= 1; s += 2) {
        float o[3] = {-HALF_X, 0, s * BACK_Z}, eu[3] = {2 * HALF_X, 0, 0}, ev[3] = {0, 2 * STOREY, 0};
        float n[3] = {0, 0, (float)-s};
        grid(&m, o, eu, ev, 60, 20, n);
        float oe[3] = {s * HALF_X, 0, -BACK_Z}, eue[3] = {0, 0, 2 * BACK_Z}, eve[3] = {0, 2 * STOREY, 0};
        float ne[3] = {(float)-s, 0, 0};
        grid(&m, oe, eue, eve, 32, 20, ne);
        for (int st = 1; st <= 2; st++) { /* slabs over each corridor, their fronts over the arches */
            float y = st * STOREY;
            if (s > 0)
                box(&m, -HALF_X, y - 0.4f, ARCADE_Z - 0.35f, HALF_X, y, BACK_Z);
            else
                box(&m, -HALF_X, y - 0.4f, -BACK_Z, HALF_X, y, -ARCADE_Z + 0.35f);
        }
    }
    add_object(g, "Walls", &m, stone);
    gen_geom_free(&m);

    /* arcades: columns and arches on both sides, two storeys */
    gen_geom_init(&m);
    for (int s = -1; s <= 1; s += 2)
        for (int st = 0; st < 2; st++) {
            float y0 = st * STOREY, col_h = 3.4f;
            for (int i = 0; i <= N_BAYS; i++) {
                gen_geom c;
                gen_geom_init(&c);
                turned(&c, col_h, 24, 32, column_r);
                float x = -HALF_X + BAY * (float)i;
                for (uint32_t v = 0; v < c.n_verts; v++) {
                    c.pos[3 * v] += x;
                    c.pos[3 * v + 1] += y0;
                    c.pos[3 * v + 2] += s * ARCADE_Z;
                }
                for (uint32_t v = 0; v < c.n_verts; v++)
                    gen_geom_vertex(&m, &c.pos[3 * v], &c.nrm[3 * v], NULL);
                uint32_t base = m.n_verts - c.n_verts;
                for (uint32_t t = 0; t < c.n_idx; t += 3)
                    gen_geom_tri(&m, base + c.idx[t], base + c.idx[t + 1], base + c.idx[t + 2]);
                gen_geom_free(&c);
                if (i < N_BAYS)
                    arch(&m, x, x + BAY, y0 + col_h, s * ARCADE_Z, 0.6f, 0.35f, 32);
            }
        }
    add_object(g, "Arcades", &m, stone);
    gen_geom_free(&m);

    /* the upper floor's balustrade: turned balusters under a rail */
    gen_geom_init(&m);
    {
        gen_geom b;
        gen_geom_init(&b);
        turned(&b, 0.8f, 10, 12, baluster_r);
        for (int s = -1; s <= 1; s += 2) {
            for (int i = 0; i < 2 * N_BAYS * 4; i++) {
                float x = -HALF_X + 0.15f + (2.0f * HALF_X - 0.3f) * (float)i / (float)(2 * N_BAYS * 4 - 1);
                uint32_t base = m.n_verts;
                for (uint32_t v = 0; v < b.n_verts; v++) {
                    float p[3] = {b.pos[3 * v] + x, b.pos[3 * v + 1] + STOREY, b.pos[3 * v + 2] + s * (ARCADE_Z - 0.1f)};
                    gen_geom_vertex(&m, p, &b.nrm[3 * v], NULL);
                }
                for (uint32_t t = 0; t < b.n_idx; t += 3)
                    gen_geom_tri(&m, base + b.idx[t], base + b.idx[t + 1], base + b.idx[t + 2]);
            }
            box(&m, -HALF_X, STOREY + 0.8f, s * (ARCADE_Z - 0.1f) - 0.12f, HALF_X, STOREY + 0.95f,
                s * (ARCADE_Z - 0.1f) + 0.12f);
        }
        gen_geom_free(&b);
    }
    add_object(g, "Balustrade", &m, stone);
    gen_geom_free(&m);

    /* banners in every other upper arch */
    for (int c = 0; c < 2; c++) {
        gen_geom_init(&m);
        for (int s = -1; s <= 1; s += 2)
            for (int i = c; i < N_BAYS; i += 2) {
                float x = -HALF_X + BAY * ((float)i + 0.5f);
                banner(&m, x, 2 * STOREY - 0.8f, s * (ARCADE_Z - 0.6f), 1.6f, 3.0f, (float)s, 28, 40);
            }
        add_object(g, c ? "BannersBlue" : "BannersRed", &m, cloth[c]);
        gen_geom_free(&m);
    }

    /* vases in the court */
    gen_geom_init(&m);
    {
        gen_geom v;
        gen_geom_init(&v);
        turned(&v, 1.6f, 40, 48, vase_r);
        for (int i = 0; i < 8; i++) {
            float x = -10.5f + 3.0f * (float)i, z = (i % 2 ? 1.0f : -1.0f) * 2.5f;
            uint32_t base = m.n_verts;
            for (uint32_t k = 0; k < v.n_verts; k++) {
                float p[3] = {v.pos[3 * k] + x, v.pos[3 * k + 1], v.pos[3 * k + 2] + z};
                gen_geom_vertex(&m, p, &v.nrm[3 * k], NULL);
            }
            for (uint32_t t = 0; t < v.n_idx; t += 3)
                gen_geom_tri(&m, base + v.idx[t], base + v.idx[t + 1], base + v.idx[t + 2]);
        }
        gen_geom_free(&v);
    }
    add_object(g, "Vases", &m, clay);
    gen_geom_free(&m);

    /* the camera: from one end of the court, down its length */
    int cam = gen_gltf_add_camera(g, "Camera", 1.0f, 1.0f, 0.05f, 100.0f);
    gen_node nd = GEN_NODE_INIT;
    nd.name = "Camera";
    nd.camera = cam;
    nd.translation[0] = -13.5f;
    nd.translation[1] = 1.7f;
    nd.translation[2] = 0.0f;
    /* a camera looks down -Z: turn -90 degrees about Y to look down +X, then up a little */
    float yaw = -0.5f * PI * 0.5f, pitch = 0.08f;
    float qy[4] = {0, sinf(yaw), 0, cosf(yaw)}, qx[4] = {sinf(pitch), 0, 0, cosf(pitch)};
    nd.rotation[0] = qy[3] * qx[0] + qy[0] * qx[3] + qy[1] * qx[2] - qy[2] * qx[1];
    nd.rotation[1] = qy[3] * qx[1] - qy[0] * qx[2] + qy[1] * qx[3] + qy[2] * qx[0];
    nd.rotation[2] = qy[3] * qx[2] + qy[0] * qx[1] - qy[1] * qx[0] + qy[2] * qx[3];
    nd.rotation[3] = qy[3] * qx[3] - qy[0] * qx[0] - qy[1] * qx[1] - qy[2] * qx[2];
    gen_gltf_add_node(g, &nd);

    printf("atrium: %u triangles\n", gen_gltf_triangles(g));
    int rc = gen_gltf_write(g, dir, "atrium", err, n_err);
    gen_gltf_destroy(g);
    return rc;
}

/* The light the edit file adds: a 2 x 1.5 emissive panel facing down. */
static int write_lights(const char *dir, char *err, size_t n_err)
{
    gen_gltf *g = gen_gltf_create();
    if (!g)
        return snprintf(err, n_err, "out of memory"), -1;
    gen_material mt = GEN_MATERIAL_INIT;
    mt.name = "PanelLight";
    mt.base_color[0] = mt.base_color[1] = mt.base_color[2] = 0.0f;
    mt.emissive[0] = 1.0f;
    mt.emissive[1] = 0.9f;
    mt.emissive[2] = 0.75f;
    mt.emissive_strength = 40.0f;
    int mat = gen_gltf_add_material(g, &mt);
    gen_geom m;
    gen_geom_init(&m);
    float q[4][3] = {{-1.0f, 0, -0.75f}, {1.0f, 0, -0.75f}, {1.0f, 0, 0.75f}, {-1.0f, 0, 0.75f}}, down[3] = {0, -1, 0};
    gen_geom_quad_facing(&m, q, down);
    add_object(g, "Panel", &m, mat);
    gen_geom_free(&m);
    int rc = gen_gltf_write(g, dir, "lights", err, n_err);
    gen_gltf_destroy(g);
    if (rc != 0)
        return rc;
    char path[4096];
    snprintf(path, sizeof path, "%s/lights.yaml", dir);
    FILE *fp = fopen(path, "w");
    if (!fp)
        return snprintf(err, n_err, "lights.yaml: cannot write"), -1;
    fputs("# four area lights under the atrium's open roof (bench/atrium.c)\n", fp);
    for (int i = 0; i < 4; i++)
        fprintf(fp, "- add: {file: lights.gltf, node: Panel, as: Panel%d, transform: {translation: [%g, 9.5, 0]}}\n",
                i + 1, -10.5 + 7.0 * i);
    return fclose(fp) == 0 ? 0 : (snprintf(err, n_err, "lights.yaml: write failed"), -1);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: atrium-gen DIR\n");
        return 2;
    }
    char err[512];
    if (write_atrium(argv[1], err, sizeof err) != 0 || write_lights(argv[1], err, sizeof err) != 0) {
        fprintf(stderr, "atrium-gen: %s\n", err);
        return 1;
    }
    return 0;
}
