/* SPDX-License-Identifier: Apache-2.0 */
/* gen_scenes: write the bundled test scenes (tests/scenes/README.md).
 *
 *   gen_scenes OUTDIR [--only NAME] [--detail N] [--seed N] [-q]
 *
 * museum1..3 are the paper's Models 1-3 (§6.2, Figures 8, 9, 11), cornell
 * is the Cornell box with its published dimensions.  Conventions: +Y up,
 * metres, counter-clockwise = front; rooms face inward, solids outward;
 * area lights are one-sided emissive rectangles facing down.  The defaults
 * produce the committed files byte for byte. */
#include "gen_gltf.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GEN_VERSION "1.0"
#define PI 3.14159265358979323846
#define DEG (PI / 180.0)
#define LIGHT_GAP 0.005f      /* museum lights hang this far below the ceiling */
#define CORNELL_GAP 0.002f
#define SCENE_SEED_DEFAULT 1u
#define DETAIL_DEFAULT 1
#define DETAIL_MAX 8

typedef struct scene {
    gen_gltf *g;
    uint64_t rng;       /* splitmix64 state: decorative variation only */
    int detail;         /* multiplies the tessellation of curved shapes */
} scene;

static uint64_t rng_next(scene *s)
{
    uint64_t z = (s->rng += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* Uniform in [lo, hi). */
static double rng_range(scene *s, double lo, double hi)
{
    return lo + (hi - lo) * (double)(rng_next(s) >> 11) * 0x1.0p-53;
}

/* ---- small helpers ---------------------------------------------------- */

static void quat_y(float q[4], double angle)
{
    q[0] = 0.0f;
    q[1] = (float)sin(angle / 2);
    q[2] = 0.0f;
    q[3] = (float)cos(angle / 2);
}

/* Rotation taking the camera's -Z to (target - eye), keeping +Y up. */
static void quat_look_at(float q[4], const double eye[3], const double target[3])
{
    double z[3] = {eye[0] - target[0], eye[1] - target[1], eye[2] - target[2]};
    double l = sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2]);
    for (int i = 0; i < 3; i++)
        z[i] /= l;
    double x[3] = {z[2], 0.0, -z[0]}; /* up x z */
    l = sqrt(x[0] * x[0] + x[2] * x[2]);
    x[0] /= l;
    x[2] /= l;
    double y[3] = {z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2],
                   z[0] * x[1] - z[1] * x[0]};
    /* Matrix with columns x, y, z to quaternion (Shoemake). */
    double m00 = x[0], m11 = y[1], m22 = z[2], tr = m00 + m11 + m22, w, a, b, c;
    if (tr > 0) {
        double sq = sqrt(tr + 1.0) * 2;
        w = sq / 4;
        a = (y[2] - z[1]) / sq;
        b = (z[0] - x[2]) / sq;
        c = (x[1] - y[0]) / sq;
    } else if (m00 > m11 && m00 > m22) {
        double sq = sqrt(1.0 + m00 - m11 - m22) * 2;
        w = (y[2] - z[1]) / sq;
        a = sq / 4;
        b = (y[0] + x[1]) / sq;
        c = (z[0] + x[2]) / sq;
    } else if (m11 > m22) {
        double sq = sqrt(1.0 + m11 - m00 - m22) * 2;
        w = (z[0] - x[2]) / sq;
        a = (y[0] + x[1]) / sq;
        b = sq / 4;
        c = (z[1] + y[2]) / sq;
    } else {
        double sq = sqrt(1.0 + m22 - m00 - m11) * 2;
        w = (x[1] - y[0]) / sq;
        a = (z[0] + x[2]) / sq;
        b = (z[1] + y[2]) / sq;
        c = sq / 4;
    }
    q[0] = (float)a;
    q[1] = (float)b;
    q[2] = (float)c;
    q[3] = (float)w;
}

static int add_node(scene *s, const char *name, int parent, int mesh,
                    float tx, float ty, float tz, const float *q)
{
    gen_node n = GEN_NODE_INIT;
    n.name = name;
    n.parent = parent;
    n.mesh = mesh;
    n.translation[0] = tx;
    n.translation[1] = ty;
    n.translation[2] = tz;
    if (q)
        memcpy(n.rotation, q, sizeof n.rotation);
    return gen_gltf_add_node(s->g, &n);
}

/* A one-primitive mesh; frees the geometry. */
static int add_mesh(scene *s, const char *name, gen_geom *m, int material)
{
    gen_prim p = {m, material};
    int i = gen_gltf_add_mesh(s->g, name, &p, 1);
    gen_geom_free(m);
    return i;
}

static int box_mesh(scene *s, const char *name, float x0, float y0, float z0,
                    float x1, float y1, float z1, int material)
{
    gen_geom m;
    gen_geom_init(&m);
    gen_geom_box(&m, (float[3]){x0, y0, z0}, (float[3]){x1, y1, z1});
    return add_mesh(s, name, &m, material);
}

static void box(gen_geom *m, float x0, float y0, float z0, float x1, float y1,
                float z1)
{
    gen_geom_box(m, (float[3]){x0, y0, z0}, (float[3]){x1, y1, z1});
}

static int diffuse(scene *s, const char *name, float r, float g, float b)
{
    gen_material m = GEN_MATERIAL_INIT;
    m.name = name;
    m.base_color[0] = r;
    m.base_color[1] = g;
    m.base_color[2] = b;
    return gen_gltf_add_material(s->g, &m);
}

/* An emitter: black, one-sided, emissiveFactor x strength = radiance. */
static int emitter(scene *s, const char *name, float r, float g, float b,
                   float strength)
{
    gen_material m = GEN_MATERIAL_INIT;
    m.name = name;
    m.base_color[0] = m.base_color[1] = m.base_color[2] = 0.0f;
    m.emissive[0] = r;
    m.emissive[1] = g;
    m.emissive[2] = b;
    m.emissive_strength = strength;
    return gen_gltf_add_material(s->g, &m);
}

/* A w x d rectangle in the y = 0 plane, centred, facing down. */
static int light_mesh(scene *s, const char *name, float w, float d, int material)
{
    gen_geom m;
    gen_geom_init(&m);
    float p[4][3] = {{-w / 2, 0, -d / 2}, {w / 2, 0, -d / 2},
                     {w / 2, 0, d / 2}, {-w / 2, 0, d / 2}};
    gen_geom_quad_facing(&m, (const float (*)[3])p, (float[3]){0, -1, 0});
    return add_mesh(s, name, &m, material);
}

static int add_camera(scene *s, const char *name, const double eye[3],
                      const double target[3], double yfov_deg)
{
    int cam = gen_gltf_add_camera(s->g, name, (float)(yfov_deg * DEG), 1.0f,
                                  0.05f, 100.0f);
    gen_node n = GEN_NODE_INIT;
    n.name = name;
    n.camera = cam;
    for (int i = 0; i < 3; i++)
        n.translation[i] = (float)eye[i];
    quat_look_at(n.rotation, eye, target);
    return gen_gltf_add_node(s->g, &n);
}

/* ---- museum parts ----------------------------------------------------- */

typedef struct museum_kit {
    /* materials */
    int wall, floor, ceiling, wood, table_top, chair, pedestal, frame;
    int canvas[3], sculpt[3], light;
    /* meshes shared by several nodes */
    int table_top_mesh, table_leg, chair_seat, chair_back, chair_leg;
    int pedestal_mesh, sculpt_mesh[4], picture[3], light_mesh;
} museum_kit;

/* The room: x in [-sx/2, sx/2], y in [0, sy], z in [-sz/2, sz/2], every
 * face pointing inward; the floor carries uvs repeating every 2 m. */
static void room_add(scene *s, const museum_kit *k, float sx, float sy, float sz)
{
    float x0 = -sx / 2, x1 = sx / 2, z0 = -sz / 2, z1 = sz / 2;
    int room = add_node(s, "Room", -1, -1, 0, 0, 0, NULL);
    gen_geom m;

    gen_geom_init(&m);
    float fp[4][3] = {{x0, 0, z1}, {x1, 0, z1}, {x1, 0, z0}, {x0, 0, z0}};
    float fuv[4][2];
    for (int i = 0; i < 4; i++) {
        fuv[i][0] = fp[i][0] / 2.0f;
        fuv[i][1] = fp[i][2] / 2.0f;
    }
    gen_geom_quad(&m, (const float (*)[3])fp, (const float (*)[2])fuv);
    add_node(s, "Floor", room, add_mesh(s, "Floor", &m, k->floor), 0, 0, 0, NULL);

    static const struct {
        const char *name;
        float want[3];
    } faces[5] = {{"Ceiling", {0, -1, 0}}, {"WallNorth", {0, 0, 1}},
                  {"WallSouth", {0, 0, -1}}, {"WallEast", {-1, 0, 0}},
                  {"WallWest", {1, 0, 0}}};
    float c[5][4][3] = {
        {{x0, sy, z0}, {x1, sy, z0}, {x1, sy, z1}, {x0, sy, z1}},
        {{x0, 0, z0}, {x1, 0, z0}, {x1, sy, z0}, {x0, sy, z0}},
        {{x0, 0, z1}, {x1, 0, z1}, {x1, sy, z1}, {x0, sy, z1}},
        {{x1, 0, z0}, {x1, 0, z1}, {x1, sy, z1}, {x1, sy, z0}},
        {{x0, 0, z0}, {x0, 0, z1}, {x0, sy, z1}, {x0, sy, z0}},
    };
    for (int f = 0; f < 5; f++) {
        gen_geom_init(&m);
        gen_geom_quad_facing(&m, (const float (*)[3])c[f], faces[f].want);
        int mesh = add_mesh(s, faces[f].name, &m, f ? k->wall : k->ceiling);
        add_node(s, faces[f].name, room, mesh, 0, 0, 0, NULL);
    }
}

static void kit_meshes(scene *s, museum_kit *k, float light_w, float light_d)
{
    gen_geom m;
    int seg = 48 * s->detail, rings = 24 * s->detail;

    /* Table: 1.8 x 1.0 top, upper face at 0.75 m; legs 6 cm square. */
    k->table_top_mesh = box_mesh(s, "TableTop", -0.9f, -0.025f, -0.5f, 0.9f,
                                 0.025f, 0.5f, k->table_top);
    k->table_leg = box_mesh(s, "TableLeg", -0.03f, 0, -0.03f, 0.03f, 0.7f,
                            0.03f, k->wood);

    /* Chair: the sitter faces -Z, the back is at +Z.  Seat at 0.45 m. */
    k->chair_seat = box_mesh(s, "ChairSeat", -0.22f, 0.43f, -0.22f, 0.22f,
                             0.47f, 0.22f, k->chair);
    k->chair_leg = box_mesh(s, "ChairLeg", -0.02f, 0, -0.02f, 0.02f, 0.43f,
                            0.02f, k->chair);
    gen_geom_init(&m);
    box(&m, -0.22f, 0.47f, 0.18f, -0.18f, 1.0f, 0.22f);   /* posts */
    box(&m, 0.18f, 0.47f, 0.18f, 0.22f, 1.0f, 0.22f);
    box(&m, -0.18f, 0.92f, 0.185f, 0.18f, 0.99f, 0.215f); /* rails */
    box(&m, -0.18f, 0.55f, 0.185f, 0.18f, 0.59f, 0.215f);
    for (int i = 0; i < 4; i++) {                          /* slats */
        float x = -0.18f + 0.044f * (float)(i + 1) + 0.035f * (float)i;
        box(&m, x, 0.59f, 0.19f, x + 0.035f, 0.92f, 0.21f);
    }
    k->chair_back = add_mesh(s, "ChairBack", &m, k->chair);

    k->pedestal_mesh = box_mesh(s, "Pedestal", -0.25f, 0, -0.25f, 0.25f, 1.0f,
                                0.25f, k->pedestal);

    /* Sculptures, each standing on y = 0. */
    float prof[24 * DETAIL_MAX + 8][4];
    int n = 0;
    for (int i = 0; i <= rings; i++) {               /* sphere, r = 0.22 */
        double t = PI * i / rings;
        prof[n][0] = (float)(0.22 * sin(t));
        prof[n][1] = (float)(0.22 - 0.22 * cos(t));
        prof[n][2] = (float)sin(t);
        prof[n++][3] = (float)-cos(t);
    }
    prof[0][0] = prof[n - 1][0] = 0.0f;
    gen_geom_init(&m);
    gen_geom_lathe(&m, (const float (*)[4])prof, n, seg);
    k->sculpt_mesh[0] = add_mesh(s, "SculptureSphere", &m, k->sculpt[0]);

    n = 0;                                           /* torus about Y */
    for (int i = 0; i <= rings; i++) {
        double t = 2 * PI * (i % rings) / rings;
        prof[n][0] = (float)(0.18 + 0.06 * cos(t));
        prof[n][1] = (float)(0.06 * sin(t));
        prof[n][2] = (float)cos(t);
        prof[n++][3] = (float)sin(t);
    }
    gen_geom_init(&m);
    gen_geom_lathe(&m, (const float (*)[4])prof, n, seg);
    k->sculpt_mesh[1] = add_mesh(s, "SculptureTorus", &m, k->sculpt[1]);

    /* Vase: r(t) = 0.045 + 0.12 sin^2(0.85 pi t), 0.55 m tall, closed. */
    n = 0;
    prof[n][0] = 0, prof[n][1] = 0, prof[n][2] = 0, prof[n++][3] = -1;
    prof[n][0] = 0.045f, prof[n][1] = 0, prof[n][2] = 0, prof[n++][3] = -1;
    for (int i = 0; i <= rings; i++) {
        double t = (double)i / rings, a = 0.85 * PI * t;
        double r = 0.045 + 0.12 * sin(a) * sin(a);
        double dr = 0.12 * 2 * sin(a) * cos(a) * 0.85 * PI, dy = 0.55;
        prof[n][0] = (float)r;
        prof[n][1] = (float)(0.55 * t);
        prof[n][2] = (float)dy;
        prof[n++][3] = (float)-dr;
    }
    prof[n][0] = prof[n - 1][0], prof[n][1] = 0.55f, prof[n][2] = 0, prof[n++][3] = 1;
    prof[n][0] = 0, prof[n][1] = 0.55f, prof[n][2] = 0, prof[n++][3] = 1;
    gen_geom_init(&m);
    gen_geom_lathe(&m, (const float (*)[4])prof, n, seg);
    k->sculpt_mesh[2] = add_mesh(s, "SculptureVase", &m, k->sculpt[2]);

    /* Spire: a drum and a cone on a rounded collar. */
    n = 0;
    static const float spire[][4] = {
        {0, 0, 0, -1},          {0.14f, 0, 0, -1},      {0.14f, 0, 1, 0},
        {0.14f, 0.06f, 1, 0},   {0.14f, 0.06f, 0, 1},   {0.07f, 0.06f, 0, 1},
        {0.07f, 0.06f, 1, 0.117f}, {0, 0.66f, 1, 0.117f}};
    memcpy(prof, spire, sizeof spire);
    gen_geom_init(&m);
    gen_geom_lathe(&m, (const float (*)[4])prof, 8, seg);
    k->sculpt_mesh[3] = add_mesh(s, "SculptureSpire", &m, k->sculpt[0]);

    /* Pictures: frame and canvas facing local +Z, back at z = 0. */
    static const float size[3][2] = {{1.2f, 0.9f}, {0.8f, 1.0f}, {1.6f, 0.7f}};
    for (int p = 0; p < 3; p++) {
        float w = size[p][0] / 2, h = size[p][1] / 2, b = 0.07f, d = 0.05f;
        gen_geom fr, cv;
        gen_geom_init(&fr);
        gen_geom_init(&cv);
        box(&fr, -w, -h, 0, -w + b, h, d);
        box(&fr, w - b, -h, 0, w, h, d);
        box(&fr, -w + b, h - b, 0, w - b, h, d);
        box(&fr, -w + b, -h, 0, w - b, -h + b, d);
        float q[4][3] = {{-w + b, -h + b, 0.02f}, {w - b, -h + b, 0.02f},
                         {w - b, h - b, 0.02f}, {-w + b, h - b, 0.02f}};
        gen_geom_quad(&cv, (const float (*)[3])q, NULL);
        char name[32];
        snprintf(name, sizeof name, "Picture%c", 'A' + p);
        gen_prim prims[2] = {{&fr, k->frame}, {&cv, k->canvas[p]}};
        k->picture[p] = gen_gltf_add_mesh(s->g, name, prims, 2);
        gen_geom_free(&fr);
        gen_geom_free(&cv);
    }
    k->light_mesh = light_mesh(s, "LightQuad", light_w, light_d, k->light);
}

static void kit_materials(scene *s, museum_kit *k, int glossy, float strength,
                          int floor_texture)
{
    k->wall = diffuse(s, "Wall", 0.72f, 0.68f, 0.60f);
    k->ceiling = diffuse(s, "Ceiling", 0.85f, 0.85f, 0.85f);
    k->wood = diffuse(s, "Wood", 0.45f, 0.28f, 0.15f);
    k->chair = diffuse(s, "ChairWood", 0.36f, 0.22f, 0.12f);
    k->pedestal = diffuse(s, "Marble", 0.80f, 0.80f, 0.77f);
    k->frame = diffuse(s, "Frame", 0.30f, 0.22f, 0.10f);
    k->sculpt[0] = diffuse(s, "Bronze", 0.55f, 0.40f, 0.22f);
    k->sculpt[1] = diffuse(s, "Stone", 0.55f, 0.56f, 0.58f);
    k->sculpt[2] = diffuse(s, "Terracotta", 0.62f, 0.30f, 0.18f);
    static const float pal[6][3] = {{0.60f, 0.12f, 0.10f}, {0.12f, 0.25f, 0.55f},
                                    {0.20f, 0.45f, 0.20f}, {0.70f, 0.55f, 0.15f},
                                    {0.35f, 0.20f, 0.45f}, {0.15f, 0.40f, 0.45f}};
    uint64_t first = rng_next(s) % 6;
    for (int i = 0; i < 3; i++) {
        const float *c = pal[(first + (uint64_t)i) % 6];
        char name[32];
        snprintf(name, sizeof name, "Canvas%c", 'A' + i);
        k->canvas[i] = diffuse(s, name, c[0], c[1], c[2]);
    }
    k->light = emitter(s, "Light", 1, 1, 1, strength);
    if (!glossy) {
        k->floor = diffuse(s, "FloorWood", 0.50f, 0.36f, 0.22f);
        k->table_top = k->wood;
        return;
    }
    gen_material m = GEN_MATERIAL_INIT;
    m.name = "FloorParquet";
    m.roughness = 0.3f;
    m.base_color_texture = floor_texture;
    k->floor = gen_gltf_add_material(s->g, &m);
    m = (gen_material)GEN_MATERIAL_INIT;
    m.name = "Mirror";
    m.base_color[0] = m.base_color[1] = m.base_color[2] = 0.95f;
    m.metallic = 1.0f;
    m.roughness = 0.0f;
    k->table_top = gen_gltf_add_material(s->g, &m);
}

/* A table with four chairs around it, one on each side.  `pre` prefixes
 * every node name; chairs face the table, jittered by the seed. */
static void dining_add(scene *s, const museum_kit *k, const char *pre,
                       float x, float z)
{
    char nm[64];
    snprintf(nm, sizeof nm, "%sTable", pre);
    int table = add_node(s, nm, -1, -1, x, 0, z, NULL);
    snprintf(nm, sizeof nm, "%sTableTop", pre);
    add_node(s, nm, table, k->table_top_mesh, 0, 0.725f, 0, NULL);
    for (int i = 0; i < 4; i++) {
        snprintf(nm, sizeof nm, "%sTableLeg%d", pre, i + 1);
        add_node(s, nm, table, k->table_leg, i & 1 ? 0.8f : -0.8f, 0,
                 i & 2 ? 0.42f : -0.42f, NULL);
    }
    static const float place[4][2] = {{0, 0.85f}, {1.3f, 0}, {0, -0.85f}, {-1.3f, 0}};
    for (int c = 0; c < 4; c++) {
        float px = place[c][0] + (float)rng_range(s, -0.05, 0.05);
        float pz = place[c][1] + (float)rng_range(s, -0.05, 0.05);
        /* Local -Z towards the table centre, plus up to 12 degrees. */
        float q[4];
        quat_y(q, atan2(px, pz) + rng_range(s, -12, 12) * DEG);
        snprintf(nm, sizeof nm, "%sChair%d", pre, c + 1);
        int chair = add_node(s, nm, -1, -1, x + px, 0, z + pz, q);
        snprintf(nm, sizeof nm, "%sChairSeat%d", pre, c + 1);
        add_node(s, nm, chair, k->chair_seat, 0, 0, 0, NULL);
        snprintf(nm, sizeof nm, "%sChairBack%d", pre, c + 1);
        add_node(s, nm, chair, k->chair_back, 0, 0, 0, NULL);
        for (int l = 0; l < 4; l++) {
            snprintf(nm, sizeof nm, "%sChairLeg%d_%d", pre, c + 1, l + 1);
            add_node(s, nm, chair, k->chair_leg, l & 1 ? 0.19f : -0.19f, 0,
                     l & 2 ? 0.19f : -0.19f, NULL);
        }
    }
}

/* A pedestal at (x, z) with sculpture `kind` on top. */
static void pedestal_add(scene *s, const museum_kit *k, int idx, float x,
                         float z, int kind)
{
    char nm[32];
    float q[4];
    quat_y(q, rng_range(s, 0, 90) * DEG);
    snprintf(nm, sizeof nm, "Pedestal%d", idx);
    int ped = add_node(s, nm, -1, k->pedestal_mesh, x, 0, z, q);
    snprintf(nm, sizeof nm, "Sculpture%d", idx);
    if (kind == 1) {      /* the torus stands upright: 90 degrees about X */
        float r[4] = {(float)sin(PI / 4), 0, 0, (float)cos(PI / 4)};
        add_node(s, nm, ped, k->sculpt_mesh[1], 0, 1.24f, 0, r);
    } else {
        add_node(s, nm, ped, k->sculpt_mesh[kind], 0, 1.0f, 0, NULL);
    }
}

/* A picture on a wall, placed by a `matrix`: wall 0..3 = north, east,
 * south, west; `along` runs left to right seen from inside; centre at
 * height y.  sx, sz: room size. */
static void picture_add(scene *s, const museum_kit *k, int idx, int wall,
                        float along, float y, int kind, float sx, float sz)
{
    /* Rotation about Y taking local +Z into the room: cos and sin of
     * 0, -90, 180 and 90 degrees, exact. */
    static const float cs[4][2] = {{1, 0}, {0, -1}, {-1, 0}, {0, 1}};
    float c = cs[wall][0], sn = cs[wall][1];
    float off = 0.002f, px, pz;
    switch (wall) {
    case 0: px = along, pz = -sz / 2 + off; break;
    case 1: px = sx / 2 - off, pz = along; break;
    case 2: px = -along, pz = sz / 2 - off; break;
    default: px = -sx / 2 + off, pz = -along; break;
    }
    gen_node n = GEN_NODE_INIT;
    char nm[32];
    snprintf(nm, sizeof nm, "Picture%d", idx);
    n.name = nm;
    n.mesh = k->picture[kind];
    n.use_matrix = 1;
    float m[16] = {c, 0, -sn, 0, 0, 1, 0, 0, sn, 0, c, 0, px, y, pz, 1};
    memcpy(n.matrix, m, sizeof m);
    gen_gltf_add_node(s->g, &n);
}

/* ---- the scenes ------------------------------------------------------- */

/* Models 1 and 2 (§6.2, Figure 8): one table, four chairs, a cube. */
static void museum_small(scene *s, int model2, int floor_texture)
{
    museum_kit k;
    /* Floor radiance under the light ~ 0.7/pi * S * A / h^2 = 0.51. */
    kit_materials(s, &k, model2, 14.0f, floor_texture);
    kit_meshes(s, &k, 2.0f, 1.0f);
    room_add(s, &k, 10.0f, 3.5f, 8.0f);
    add_node(s, "Light", -1, k.light_mesh, 0, 3.5f - LIGHT_GAP, 0, NULL);
    dining_add(s, &k, "", 0, 0);
    int red = diffuse(s, "CubeRed", 0.70f, 0.07f, 0.05f);
    int cube = box_mesh(s, "Cube", -0.2f, -0.2f, -0.2f, 0.2f, 0.2f, 0.2f, red);
    add_node(s, "Cube", -1, cube, 1.2f, 0.2f, 1.3f, NULL);

    int first = (int)(rng_next(s) % 4);
    static const float ped[4][2] = {{-3.0f, -3.3f}, {2.6f, -3.3f},
                                    {-4.3f, 0.3f}, {-4.3f, 2.9f}};
    for (int i = 0; i < 4; i++)
        pedestal_add(s, &k, i + 1, ped[i][0], ped[i][1], (first + i) % 4);
    picture_add(s, &k, 1, 0, -1.2f, 1.8f, 0, 10, 8);
    picture_add(s, &k, 2, 0, 1.2f, 1.8f, 1, 10, 8);
    picture_add(s, &k, 3, 3, -1.6f, 1.7f, 2, 10, 8);
    picture_add(s, &k, 4, 3, 1.6f, 1.8f, 1, 10, 8);
    picture_add(s, &k, 5, 1, 0.0f, 1.8f, 2, 10, 8);
    picture_add(s, &k, 6, 2, 0.0f, 1.8f, 0, 10, 8);

    add_camera(s, "Camera", (double[3]){3.5, 1.6, 2.9},
               (double[3]){-0.6, 0.45, -0.5}, 50.0);
}

/* Model 3 (§6.2, Figure 9): a larger hall, six lights, four dining
 * groups, columns, pedestals and a movable box. */
static void museum_large(scene *s)
{
    museum_kit k;
    kit_materials(s, &k, 0, 16.0f, -1);
    kit_meshes(s, &k, 2.0f, 1.0f);
    const float sx = 20.0f, sy = 4.0f, sz = 14.0f;
    room_add(s, &k, sx, sy, sz);
    for (int i = 0; i < 6; i++) {
        char nm[16];
        snprintf(nm, sizeof nm, "Light%d", i + 1);
        add_node(s, nm, -1, k.light_mesh, -6.0f + 6.0f * (float)(i % 3),
                 sy - LIGHT_GAP, i < 3 ? -3.5f : 3.5f, NULL);
    }
    static const float groups[4][2] = {{-6, -3.5f}, {6, -3.5f}, {-6, 3.5f}, {6, 3.5f}};
    for (int i = 0; i < 4; i++) {
        char pre[8];
        snprintf(pre, sizeof pre, "G%d", i + 1);
        dining_add(s, &k, pre, groups[i][0], groups[i][1]);
    }

    /* Columns floor to ceiling between the lights. */
    gen_geom m;
    gen_geom_init(&m);
    const float col[6][4] = {{0, 0, 0, -1}, {0.25f, 0, 0, -1}, {0.25f, 0, 1, 0},
                             {0.25f, 4.0f, 1, 0}, {0.25f, 4.0f, 0, 1}, {0, 4.0f, 0, 1}};
    gen_geom_lathe(&m, col, 6, 48 * s->detail);
    int column = add_mesh(s, "Column", &m, k.pedestal);
    for (int i = 0; i < 4; i++) {
        char nm[16];
        snprintf(nm, sizeof nm, "Column%d", i + 1);
        add_node(s, nm, -1, column, i & 1 ? 3.0f : -3.0f, 0, i & 2 ? 3.5f : -3.5f, NULL);
    }

    int brown = diffuse(s, "BoxBrown", 0.45f, 0.28f, 0.14f);
    int bx = box_mesh(s, "Box", -0.3f, -0.3f, -0.3f, 0.3f, 0.3f, 0.3f, brown);
    add_node(s, "Box", -1, bx, 1.5f, 0.3f, 1.2f, NULL);

    static const float ped[10][2] = {
        {-9.2f, -6.2f}, {-3.0f, -6.2f}, {3.0f, -6.2f}, {9.2f, -6.2f},
        {-9.2f, 0.0f}, {0.0f, 0.0f}, {9.2f, 0.0f},
        {-9.2f, 6.2f}, {-1.5f, 6.2f}, {9.2f, 6.2f}};
    int first = (int)(rng_next(s) % 4);
    for (int i = 0; i < 10; i++)
        pedestal_add(s, &k, i + 1, ped[i][0], ped[i][1], (first + i) % 4);
    int pic = 1;
    for (int w = 0; w < 4; w++) {
        float len = (w & 1) ? sz : sx;
        int n = (w & 1) ? 2 : 4;
        for (int i = 0; i < n; i++, pic++) {
            float along = -len / 2 + len * ((float)i + 0.5f) / (float)n;
            picture_add(s, &k, pic, w, along, 1.9f, pic % 3, sx, sz);
        }
    }
    add_camera(s, "Camera", (double[3]){9.7, 2.4, 6.7},
               (double[3]){-2.0, 0.4, -1.0}, 60.0);
}

/* The Cornell box, published data in mm (www.graphics.cornell.edu/online/
 * box/data.html), converted to metres.  Open towards the camera (-Z). */
static const float cornell_walls[5][4][3] = {
    {{552.8f, 0, 0}, {0, 0, 0}, {0, 0, 559.2f}, {549.6f, 0, 559.2f}},
    {{556.0f, 548.8f, 0}, {556.0f, 548.8f, 559.2f}, {0, 548.8f, 559.2f}, {0, 548.8f, 0}},
    {{549.6f, 0, 559.2f}, {0, 0, 559.2f}, {0, 548.8f, 559.2f}, {556.0f, 548.8f, 559.2f}},
    {{0, 0, 559.2f}, {0, 0, 0}, {0, 548.8f, 0}, {0, 548.8f, 559.2f}},
    {{552.8f, 0, 0}, {549.6f, 0, 559.2f}, {556.0f, 548.8f, 559.2f}, {556.0f, 548.8f, 0}},
};

/* Top faces of the blocks; the sides drop these corners to y = 0. */
static const float cornell_short_top[4][3] = {
    {130.0f, 165.0f, 65.0f}, {82.0f, 165.0f, 225.0f},
    {240.0f, 165.0f, 272.0f}, {290.0f, 165.0f, 114.0f}};
static const float cornell_tall_top[4][3] = {
    {423.0f, 330.0f, 247.0f}, {265.0f, 330.0f, 296.0f},
    {314.0f, 330.0f, 456.0f}, {472.0f, 330.0f, 406.0f}};

/* A block from its top quad: top, four sides and a bottom, all outward. */
static int cornell_block(scene *s, const char *name, const float top[4][3],
                         int material)
{
    float c[3] = {0, 0, 0};
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 3; k++)
            c[k] += top[i][k] * 0.001f / 4;
    c[1] /= 2;
    gen_geom m;
    gen_geom_init(&m);
    float f[4][3], want[3];
    for (int face = 0; face < 6; face++) {
        for (int i = 0; i < 4; i++) {
            int a = face < 2 ? i : (face - 2 + (i == 1 || i == 2)) % 4;
            int low = face == 1 || (face >= 2 && i < 2);
            for (int k = 0; k < 3; k++)
                f[i][k] = top[a][k] * 0.001f;
            if (low)
                f[i][1] = 0.0f;
        }
        for (int k = 0; k < 3; k++)
            want[k] = (f[0][k] + f[1][k] + f[2][k] + f[3][k]) / 4 - c[k];
        gen_geom_quad_facing(&m, (const float (*)[3])f, want);
    }
    return add_mesh(s, name, &m, material);
}

static void cornell(scene *s)
{
    int white = diffuse(s, "White", 0.725f, 0.71f, 0.68f);
    int red = diffuse(s, "Red", 0.63f, 0.065f, 0.05f);
    int green = diffuse(s, "Green", 0.14f, 0.45f, 0.091f);
    /* Radiance (17, 12, 4) = factor x strength with the factor <= 1. */
    int light = emitter(s, "Light", 1.0f, 12.0f / 17.0f, 4.0f / 17.0f, 17.0f);

    static const char *const names[5] = {"Floor", "Ceiling", "BackWall",
                                         "RightWall", "LeftWall"};
    static const float inward[5][3] = {{0, 1, 0}, {0, -1, 0}, {0, 0, -1},
                                       {1, 0, 0}, {-1, 0, 0}};
    const int mats[5] = {white, white, white, green, red};
    for (int w = 0; w < 5; w++) {
        float q[4][3];
        for (int i = 0; i < 4; i++)
            for (int k = 0; k < 3; k++)
                q[i][k] = cornell_walls[w][i][k] * 0.001f;
        gen_geom m;
        gen_geom_init(&m);
        gen_geom_quad_facing(&m, (const float (*)[3])q, inward[w]);
        add_node(s, names[w], -1, add_mesh(s, names[w], &m, mats[w]), 0, 0, 0, NULL);
    }
    add_node(s, "ShortBlock", -1,
             cornell_block(s, "ShortBlock", cornell_short_top, white), 0, 0, 0, NULL);
    add_node(s, "TallBlock", -1,
             cornell_block(s, "TallBlock", cornell_tall_top, white), 0, 0, 0, NULL);
    /* Light: x 213..343, z 227..332 mm, just below the ceiling at 548.8. */
    int lm = light_mesh(s, "Light", 0.130f, 0.105f, light);
    add_node(s, "Light", -1, lm, 0.278f, 0.5488f - CORNELL_GAP, 0.2795f, NULL);

    /* Published camera: (278, 273, -800) looking +Z, 35 mm lens on a 25 mm
     * film: yfov = 2 atan(12.5 / 35) = 39.3 degrees. */
    gen_node n = GEN_NODE_INIT;
    n.name = "Camera";
    n.camera = gen_gltf_add_camera(s->g, "Camera", (float)(2 * atan(12.5 / 35.0)),
                                   1.0f, 0.01f, 10.0f);
    n.translation[0] = 0.278f;
    n.translation[1] = 0.273f;
    n.translation[2] = -0.800f;
    n.rotation[1] = 1.0f; /* 180 degrees about Y: (0, 1, 0, 0) */
    n.rotation[3] = 0.0f;
    gen_gltf_add_node(s->g, &n);
}

/* ---- floor texture ---------------------------------------------------- */

/* A 256 x 256 basket-weave parquet: 4 x 4 cells of four planks each,
 * alternating direction, per-plank tone and a wavy grain.  sRGB bytes. */
static uint8_t *parquet(scene *s)
{
    enum { N = 256, CELL = 64, PLANK = 16 };
    uint8_t *img = malloc((size_t)N * N * 3);
    if (!img)
        return NULL;
    float tone[4][4][4], phase[4][4][4];
    for (int a = 0; a < 4; a++)
        for (int b = 0; b < 4; b++)
            for (int p = 0; p < 4; p++) {
                tone[a][b][p] = (float)rng_range(s, 0.82, 1.12);
                phase[a][b][p] = (float)rng_range(s, 0, 2 * PI);
            }
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++) {
            int cx = x / CELL, cy = y / CELL, horiz = (cx + cy) % 2 == 0;
            int along = horiz ? x % CELL : y % CELL;
            int across = horiz ? y % CELL : x % CELL;
            int p = across / PLANK, in = across % PLANK;
            float ph = phase[cy][cx][p];
            double grain = 0.07 * sin(0.9 * in + 2.5 * sin(0.09 * along + ph) + ph);
            double v = tone[cy][cx][p] * (1.0 + grain);
            if (in == 0 || along == 0)
                v *= 0.55;     /* the seam between planks */
            double rgb[3] = {168 * v, 112 * v, 64 * v};
            for (int k = 0; k < 3; k++) {
                double c = rgb[k] < 0 ? 0 : rgb[k] > 255 ? 255 : rgb[k];
                img[((size_t)y * N + (size_t)x) * 3 + (size_t)k] = (uint8_t)lrint(c);
            }
        }
    return img;
}

/* ---- main ------------------------------------------------------------- */

static const char *const scene_names[4] = {"museum1", "museum2", "museum3", "cornell"};

static int build(int which, const char *dir, int detail, uint64_t seed,
                 int quiet)
{
    char err[512] = "";
    scene s = {gen_gltf_create(), seed, detail};
    if (!s.g) {
        fprintf(stderr, "gen_scenes: out of memory\n");
        return 1;
    }
    int floor_tex = -1, rc = 0;
    if (which == 1) {
        char path[4096];
        snprintf(path, sizeof path, "%s/museum2_floor.png", dir);
        scene ts = {NULL, seed ^ 0x5eed, detail};
        uint8_t *img = parquet(&ts);
        if (!img || gen_png_write(path, 256, 256, img, err, sizeof err)) {
            fprintf(stderr, "gen_scenes: %s\n", img ? err : "out of memory");
            free(img);
            gen_gltf_destroy(s.g);
            return 1;
        }
        free(img);
        floor_tex = gen_gltf_add_texture(s.g, "museum2_floor.png");
    }
    switch (which) {
    case 0: museum_small(&s, 0, -1); break;
    case 1: museum_small(&s, 1, floor_tex); break;
    case 2: museum_large(&s); break;
    default: cornell(&s); break;
    }
    if (gen_gltf_write(s.g, dir, scene_names[which], err, sizeof err)) {
        fprintf(stderr, "gen_scenes: %s\n", err);
        rc = 1;
    } else if (!quiet) {
        printf("%s/%s.gltf: %u triangles, %d nodes\n", dir, scene_names[which],
               gen_gltf_triangles(s.g), gen_gltf_node_count(s.g));
    }
    gen_gltf_destroy(s.g);
    return rc;
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: gen_scenes OUTDIR [options]\n"
            "Write the bundled test scenes (glTF 2.0) into OUTDIR.\n"
            "  --only NAME   write only NAME: museum1, museum2, museum3 or cornell\n"
            "  --detail N    tessellation of curved shapes, 1..%d (default %d)\n"
            "  --seed N      decorative variation: chair jitter, colours, texture\n"
            "                (default %u; the committed files use the defaults)\n"
            "  -q, --quiet   print nothing but errors\n"
            "  --help        this text\n"
            "  --version     print the version\n",
            DETAIL_MAX, DETAIL_DEFAULT, SCENE_SEED_DEFAULT);
}

static int usage_error(const char *msg, const char *arg)
{
    fprintf(stderr, "gen_scenes: %s%s%s (see --help)\n", msg, arg ? ": " : "",
            arg ? arg : "");
    return 2;
}

int main(int argc, char **argv)
{
    static const struct option opts[] = {
        {"only", required_argument, NULL, 'o'}, {"detail", required_argument, NULL, 'd'},
        {"seed", required_argument, NULL, 's'}, {"quiet", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'},       {"version", no_argument, NULL, 'V'},
        {NULL, 0, NULL, 0}};
    int only = -1, detail = DETAIL_DEFAULT, quiet = 0, c;
    uint64_t seed = SCENE_SEED_DEFAULT;
    char *end;
    opterr = 0;
    while ((c = getopt_long(argc, argv, "q", opts, NULL)) != -1) {
        switch (c) {
        case 'o':
            for (only = 3; only >= 0 && strcmp(optarg, scene_names[only]); only--)
                ;
            if (only < 0)
                return usage_error("unknown scene", optarg);
            break;
        case 'd':
            detail = (int)strtol(optarg, &end, 10);
            if (*end || detail < 1 || detail > DETAIL_MAX)
                return usage_error("--detail wants an integer 1..8", optarg);
            break;
        case 's':
            seed = strtoull(optarg, &end, 10);
            if (*end || !*optarg || *optarg == '-')
                return usage_error("--seed wants a non-negative integer", optarg);
            break;
        case 'q': quiet = 1; break;
        case 'h': usage(stdout); return 0;
        case 'V': printf("gen_scenes %s\n", GEN_VERSION); return 0;
        default: return usage_error("unknown or incomplete option", argv[optind - 1]);
        }
    }
    if (optind != argc - 1)
        return usage_error("expected one OUTDIR", NULL);
    const char *dir = argv[optind];
    for (int i = 0; i < 4; i++)
        if ((only < 0 || only == i) && build(i, dir, detail, seed, quiet))
            return 1;
    return 0;
}
