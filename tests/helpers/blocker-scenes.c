/* SPDX-License-Identifier: Apache-2.0 */
/* blocker-scenes: write the fixtures that sampled blocker lists get wrong
 * when nothing completes them (lib/lie/sample.c, lib/lie/subdiv.c): real
 * meshes' thin parts and many small triangles between a light and what it
 * lights, and emitters of many triangles (closed emissive cubes).
 *
 *   blocker-scenes OUTDIR
 *
 * writes OUTDIR/thin.gltf (+ .bin) and OUTDIR/cubes.gltf (+ .bin), each a
 * closed room seen from the camera "Inside".  Conventions as the bundled
 * scenes' (tests/scenes/README.md): +Y up, metres, rooms face inward,
 * solids outward, one-sided materials.  Output is a function of the
 * program alone (a fixed splitmix64 sequence places the small triangles). */
#include "../scenes/gen/gen_gltf.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define PI 3.14159265358979323846

static uint64_t rng_state = 1;

static double rng(void) /* uniform in [0, 1): splitmix64 */
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return (double)((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
}

/* A closed room w x h x d centred on x = z = 0, floor at y = 0, faces inward. */
static void room(gen_geom *m, float w, float h, float d)
{
    float x = w / 2, z = d / 2;
    gen_geom_quad_facing(m, (const float[4][3]){{-x, 0, -z}, {x, 0, -z}, {x, 0, z}, {-x, 0, z}}, (float[3]){0, 1, 0});
    gen_geom_quad_facing(m, (const float[4][3]){{-x, h, -z}, {x, h, -z}, {x, h, z}, {-x, h, z}}, (float[3]){0, -1, 0});
    gen_geom_quad_facing(m, (const float[4][3]){{-x, 0, -z}, {x, 0, -z}, {x, h, -z}, {-x, h, -z}}, (float[3]){0, 0, 1});
    gen_geom_quad_facing(m, (const float[4][3]){{-x, 0, z}, {x, 0, z}, {x, h, z}, {-x, h, z}}, (float[3]){0, 0, -1});
    gen_geom_quad_facing(m, (const float[4][3]){{-x, 0, -z}, {-x, 0, z}, {-x, h, z}, {-x, h, -z}}, (float[3]){1, 0, 0});
    gen_geom_quad_facing(m, (const float[4][3]){{x, 0, -z}, {x, 0, z}, {x, h, z}, {x, h, -z}}, (float[3]){-1, 0, 0});
}

static void box(gen_geom *m, float x0, float y0, float z0, float x1, float y1, float z1)
{
    gen_geom_box(m, (float[3]){x0, y0, z0}, (float[3]){x1, y1, z1});
}

/* One triangle with its flat normal, front towards +y or -y at random. */
static void small_tri(gen_geom *m, const float c[3], float size)
{
    float p[3][3];
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 3; a++)
            p[k][a] = c[a] + (float)((rng() - 0.5) * size);
    float e1[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
    float e2[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    float l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(l > 0.0f))
        return;
    for (int a = 0; a < 3; a++)
        n[a] /= l;
    uint32_t i0 = gen_geom_vertex(m, p[0], n, NULL), i1 = gen_geom_vertex(m, p[1], n, NULL),
             i2 = gen_geom_vertex(m, p[2], n, NULL);
    gen_geom_tri(m, i0, i1, i2);
}

static int add_mesh_node(gen_gltf *g, const char *name, gen_geom *m, int material, float tx, float ty, float tz)
{
    gen_prim prim = {m, material};
    int mesh = gen_gltf_add_mesh(g, name, &prim, 1);
    gen_node n = GEN_NODE_INIT;
    n.name = name;
    n.mesh = mesh;
    n.translation[0] = tx;
    n.translation[1] = ty;
    n.translation[2] = tz;
    int r = gen_gltf_add_node(g, &n);
    gen_geom_free(m);
    return r;
}

/* The camera "Inside" at eye, looking at target. */
static void camera(gen_gltf *g, const double eye[3], const double target[3])
{
    double f[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
    double yaw = atan2(-f[0], -f[2]), pitch = atan2(f[1], sqrt(f[0] * f[0] + f[2] * f[2]));
    /* q = yaw about y, then pitch about x */
    double cy = cos(yaw / 2), sy = sin(yaw / 2), cp = cos(pitch / 2), sp = sin(pitch / 2);
    gen_node n = GEN_NODE_INIT;
    n.name = "Inside";
    n.camera = gen_gltf_add_camera(g, "Inside", (float)(60.0 * PI / 180.0), 0.0f, 0.01f, 100.0f);
    n.rotation[0] = (float)(cy * sp);
    n.rotation[1] = (float)(sy * cp);
    n.rotation[2] = (float)(-sy * sp);
    n.rotation[3] = (float)(cy * cp);
    for (int a = 0; a < 3; a++)
        n.translation[a] = (float)eye[a];
    gen_gltf_add_node(g, &n);
}

/* A room lit by one ceiling panel, with between the panel and the floor:
 * a grille of thin slats (1 cm), a perforated plate of many small squares,
 * a cloud of small triangles (leaves), and thin rods on the floor. */
static int thin(const char *dir, char *err, size_t n_err)
{
    gen_gltf *g = gen_gltf_create();
    if (!g)
        return -1;
    gen_material white = GEN_MATERIAL_INIT, grey = GEN_MATERIAL_INIT, leaf = GEN_MATERIAL_INIT,
                 light = GEN_MATERIAL_INIT;
    white.name = "white";
    white.base_color[0] = white.base_color[1] = white.base_color[2] = 0.8f;
    grey.name = "grey";
    grey.base_color[0] = grey.base_color[1] = grey.base_color[2] = 0.5f;
    leaf.name = "leaf";
    leaf.base_color[0] = 0.2f, leaf.base_color[1] = 0.6f, leaf.base_color[2] = 0.2f;
    leaf.double_sided = 1;
    light.name = "light";
    light.base_color[0] = light.base_color[1] = light.base_color[2] = 0.0f;
    light.emissive[0] = light.emissive[1] = light.emissive[2] = 1.0f;
    light.emissive_strength = 20.0f;
    int m_white = gen_gltf_add_material(g, &white), m_grey = gen_gltf_add_material(g, &grey),
        m_leaf = gen_gltf_add_material(g, &leaf), m_light = gen_gltf_add_material(g, &light);
    gen_geom m;
    gen_geom_init(&m);
    room(&m, 6, 3, 6);
    add_mesh_node(g, "Room", &m, m_white, 0, 0, 0);
    gen_geom_init(&m);
    gen_geom_quad_facing(&m, (const float[4][3]){{-0.6f, 0, -0.6f}, {0.6f, 0, -0.6f}, {0.6f, 0, 0.6f}, {-0.6f, 0, 0.6f}},
                         (float[3]){0, -1, 0});
    add_mesh_node(g, "Light", &m, m_light, 0, 2.995f, 0);
    /* the grille: 24 slats 1 cm square, 5 cm apart, under the light */
    gen_geom_init(&m);
    for (int i = 0; i < 24; i++) {
        float x = -0.6f + 0.05f * (float)i;
        box(&m, x, 0, -0.8f, x + 0.01f, 0.01f, 0.8f);
    }
    add_mesh_node(g, "Grille", &m, m_grey, -1.2f, 2.2f, 0);
    /* the plate: 30 x 30 squares of 2 cm, 1 cm apart (1,800 triangles) */
    gen_geom_init(&m);
    for (int i = 0; i < 30; i++)
        for (int k = 0; k < 30; k++) {
            float x = -0.45f + 0.03f * (float)i, z = -0.45f + 0.03f * (float)k;
            gen_geom_quad_facing(&m, (const float[4][3]){{x, 0, z}, {x + 0.02f, 0, z}, {x + 0.02f, 0, z + 0.02f}, {x, 0, z + 0.02f}},
                                 (float[3]){0, -1, 0});
        }
    add_mesh_node(g, "Plate", &m, m_grey, 1.1f, 1.9f, 0.4f);
    /* leaves: 1,500 triangles of about 2 cm in a ball of 35 cm */
    gen_geom_init(&m);
    for (int i = 0; i < 1500; i++) {
        float c[3];
        do {
            for (int a = 0; a < 3; a++)
                c[a] = (float)(rng() * 2.0 - 1.0);
        } while (c[0] * c[0] + c[1] * c[1] + c[2] * c[2] > 1.0f);
        for (int a = 0; a < 3; a++)
            c[a] *= 0.35f;
        small_tri(&m, c, 0.025f);
    }
    add_mesh_node(g, "Leaves", &m, m_leaf, 0.1f, 1.6f, -1.1f);
    /* rods: 36 sticks 8 mm thick, 40 cm tall, standing on the floor in a
     * ring under the light: sharp shadows at their feet */
    gen_geom_init(&m);
    for (int i = 0; i < 36; i++) {
        double a = 2.0 * PI * (double)i / 36.0;
        float x = (float)(0.7 * cos(a)), z = (float)(0.7 * sin(a));
        box(&m, x - 0.004f, 0, z - 0.004f, x + 0.004f, 0.4f, z + 0.004f);
    }
    add_mesh_node(g, "Rods", &m, m_grey, 0, 0, 0);
    camera(g, (const double[3]){0, 1.4, 2.2}, (const double[3]){0, 0.1, -0.2});
    int r = gen_gltf_write(g, dir, "thin", err, n_err);
    gen_gltf_destroy(g);
    return r;
}

/* A room lit only by five emissive cubes (closed emitters of 12
 * triangles): one on the floor, one in a corner touching two walls, one on
 * a table, two in the air, with a chair and the table between them. */
static int cubes(const char *dir, char *err, size_t n_err)
{
    gen_gltf *g = gen_gltf_create();
    if (!g)
        return -1;
    gen_material white = GEN_MATERIAL_INIT, wood = GEN_MATERIAL_INIT, glow = GEN_MATERIAL_INIT;
    white.name = "white";
    white.base_color[0] = white.base_color[1] = white.base_color[2] = 0.8f;
    wood.name = "wood";
    wood.base_color[0] = 0.5f, wood.base_color[1] = 0.35f, wood.base_color[2] = 0.2f;
    glow.name = "glow";
    glow.base_color[0] = glow.base_color[1] = glow.base_color[2] = 0.0f;
    glow.emissive[0] = 1.0f, glow.emissive[1] = 0.9f, glow.emissive[2] = 0.7f;
    glow.emissive_strength = 10.0f;
    int m_white = gen_gltf_add_material(g, &white), m_wood = gen_gltf_add_material(g, &wood),
        m_glow = gen_gltf_add_material(g, &glow);
    gen_geom m;
    gen_geom_init(&m);
    room(&m, 6, 3, 6);
    add_mesh_node(g, "Room", &m, m_white, 0, 0, 0);
    /* a table (top and four legs) and a chair */
    gen_geom_init(&m);
    box(&m, -0.6f, 0.72f, -0.4f, 0.6f, 0.76f, 0.4f);
    for (int i = 0; i < 4; i++) {
        float x = i & 1 ? 0.52f : -0.6f, z = i & 2 ? 0.32f : -0.4f;
        box(&m, x, 0, z, x + 0.08f, 0.72f, z + 0.08f);
    }
    add_mesh_node(g, "Table", &m, m_wood, 0, 0, 0);
    gen_geom_init(&m);
    box(&m, -0.22f, 0.42f, -0.22f, 0.22f, 0.46f, 0.22f);
    box(&m, -0.22f, 0.46f, 0.18f, 0.22f, 0.95f, 0.22f);
    for (int i = 0; i < 4; i++) {
        float x = i & 1 ? 0.18f : -0.22f, z = i & 2 ? 0.18f : -0.22f;
        box(&m, x, 0, z, x + 0.04f, 0.42f, z + 0.04f);
    }
    add_mesh_node(g, "Chair", &m, m_wood, 0.2f, 0, 1.0f);
    static const float at[5][3] = {{-1.5f, 0, -1.2f}, {2.7f, 0, -2.7f}, {-0.3f, 0.76f, 0}, {1.2f, 1.6f, 0.8f},
                                   {-1.8f, 2.2f, 1.5f}};
    static const char *const names[5] = {"Cube0", "Cube1", "Cube2", "Cube3", "Cube4"};
    for (int i = 0; i < 5; i++) {
        gen_geom_init(&m);
        box(&m, 0, 0, 0, 0.3f, 0.3f, 0.3f);
        add_mesh_node(g, names[i], &m, m_glow, at[i][0], at[i][1], at[i][2]);
    }
    camera(g, (const double[3]){0.5, 1.5, 2.7}, (const double[3]){-0.3, 0.4, -0.8});
    int r = gen_gltf_write(g, dir, "cubes", err, n_err);
    gen_gltf_destroy(g);
    return r;
}

int main(int argc, char **argv)
{
    char err[512];
    if (argc != 2) {
        fprintf(stderr, "usage: blocker-scenes OUTDIR\n");
        return 2;
    }
    if (thin(argv[1], err, sizeof err) != 0 || cubes(argv[1], err, sizeof err) != 0) {
        fprintf(stderr, "blocker-scenes: %s\n", err);
        return 1;
    }
    return 0;
}
