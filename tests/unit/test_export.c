/* SPDX-License-Identifier: Apache-2.0 */
/* lib/export: the glTF exporter (lie_gltf_export).  The property
 * pinned: loading an exported scene gives back the world it was written
 * from, the same content hash whenever no node was removed.
 * Size: one file per module (CONTRIBUTING.md, Tests): the round trips of
 * every part of a scene, and the side-file rules. */
#include <dirent.h>
#include <ftw.h>
#include <limits.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "edit/edit.h"
#include "export/export.h"
#include "fixtures.h"
#include "scene/scene.h"

#define SCENES TEST_SCENES "/"
#define FIXTURES TEST_SCENES "/../data/gltf/"

/* ---- helpers ------------------------------------------------------------- */

static void print_err(const char *what, const lie_error *err)
{
    char line[2200];
    lie_error_format(err, line, sizeof line);
    print_error("%s: %s\n", what, line);
}

static lie_scene *load(const char *path)
{
    lie_scene *s = NULL;
    lie_error err;
    lie_error_clear(&err);
    lie_status st = lie_scene_load(path, NULL, &s, &err);
    if (st != LIE_OK)
        print_err("load", &err);
    assert_int_equal(st, LIE_OK);
    return s;
}

static void export_ok(const lie_scene *s, const char *path)
{
    lie_error err;
    lie_error_clear(&err);
    lie_status st = lie_gltf_export(s, path, &err);
    if (st != LIE_OK)
        print_err("export", &err);
    assert_int_equal(st, LIE_OK);
}

/* A fresh temporary folder per test, removed with its contents after. */
static int make_dir(void **state)
{
    char *dir = malloc(PATH_MAX);
    if (!dir)
        return -1;
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, PATH_MAX, "%s/lie-export.XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        free(dir);
        return -1;
    }
    *state = dir;
    return 0;
}

static int rm_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw) { return remove(path); }

static int remove_dir(void **state)
{
    int rc = nftw(*state, rm_entry, 16, FTW_DEPTH | FTW_PHYS);
    free(*state);
    return rc;
}

static const char *in_dir(void **state, const char *name)
{
    static char buf[4][PATH_MAX];
    static int next;
    char *p = buf[next++ & 3];
    int n = snprintf(p, sizeof buf[0], "%s/%s", (const char *)*state, name);
    assert_true(n > 0 && (size_t)n < sizeof buf[0]);
    return p;
}

/* Number of entries in a folder, "." and ".." aside. */
static int count_entries(const char *dir)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        n += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    closedir(d);
    return n;
}

static unsigned char *slurp(const char *path, size_t *size)
{
    unsigned char *data = NULL;
    lie_error err;
    assert_int_equal(lie_read_file(path, &data, size, &err), LIE_OK);
    return data;
}

static int has_text(const char *path, const char *needle)
{
    size_t n;
    unsigned char *d = slurp(path, &n);
    char *t = malloc(n + 1);
    assert_non_null(t);
    memcpy(t, d, n);
    t[n] = 0;
    int found = strstr(t, needle) != NULL;
    free(t);
    free(d);
    return found;
}

/* The world of a and b agree field by field (a readable failure before the
 * hash comparison). */
static void assert_same_world(const lie_scene *a, const lie_scene *b)
{
    assert_int_equal(a->n_tris, b->n_tris);
    size_t n = a->n_tris;
    assert_memory_equal(a->tri_p, b->tri_p, sizeof(lie_vec3) * 3 * n);
    assert_memory_equal(a->tri_n, b->tri_n, sizeof(lie_vec3) * 3 * n);
    assert_memory_equal(a->tri_uv, b->tri_uv, sizeof(float) * 6 * n);
    assert_memory_equal(a->tri_material, b->tri_material, sizeof(int32_t) * n);
    assert_int_equal(a->n_materials, b->n_materials);
    for (int i = 0; i < a->n_materials; i++) {
        const lie_material *x = &a->materials[i], *y = &b->materials[i];
        assert_memory_equal(x->base_color, y->base_color, sizeof x->base_color);
        assert_true(x->metallic == y->metallic && x->roughness == y->roughness);
        assert_memory_equal(x->emissive, y->emissive, sizeof x->emissive);
        assert_int_equal(x->base_color_tex, y->base_color_tex);
        assert_int_equal(x->mr_tex, y->mr_tex);
        assert_int_equal(x->emissive_tex, y->emissive_tex);
        assert_int_equal(x->double_sided, y->double_sided);
    }
    assert_int_equal(a->n_textures, b->n_textures);
    for (int i = 0; i < a->n_textures; i++) {
        const lie_texture *x = &a->textures[i], *y = &b->textures[i];
        assert_int_equal(x->width, y->width);
        assert_int_equal(x->height, y->height);
        assert_int_equal(x->wrap_s, y->wrap_s);
        assert_int_equal(x->wrap_t, y->wrap_t);
        assert_texels_equal(x, y);
    }
    assert_int_equal(a->n_emitters, b->n_emitters);
    assert_int_equal(a->n_cameras, b->n_cameras);
    for (int i = 0; i < a->n_cameras; i++) {
        assert_memory_equal(&a->cameras[i].eye, &b->cameras[i].eye, sizeof(lie_vec3));
        assert_memory_equal(&a->cameras[i].forward, &b->cameras[i].forward, sizeof(lie_vec3));
        assert_true(a->cameras[i].yfov == b->cameras[i].yfov && a->cameras[i].aspect == b->cameras[i].aspect);
        assert_true((a->cameras[i].name == NULL) == (b->cameras[i].name == NULL));
        if (a->cameras[i].name)
            assert_string_equal(a->cameras[i].name, b->cameras[i].name);
    }
    assert_true(a->hash == b->hash);
}

/* Export s into the test's folder and load it back. */
static lie_scene *round_trip(void **state, const lie_scene *s, const char *name)
{
    const char *out = in_dir(state, name);
    export_ok(s, out);
    return load(out);
}

static void expect_round_trip(void **state, const char *path)
{
    lie_scene *s = load(path);
    lie_scene *r = round_trip(state, s, "out.gltf");
    assert_same_world(s, r);
    lie_scene_destroy(r);
    lie_scene_destroy(s);
}

/* Apply edit text (formats/edit.md) to s. */
static void apply_edit(lie_scene *s, const char *text)
{
    lie_edit *e = NULL;
    lie_error err;
    lie_error_clear(&err);
    lie_status st = lie_edit_parse((const unsigned char *)text, strlen(text), "edit.yaml", &e, &err);
    if (st == LIE_OK)
        st = lie_edit_apply(s, e, NULL, NULL, &err);
    if (st != LIE_OK)
        print_err("edit", &err);
    assert_int_equal(st, LIE_OK);
    lie_edit_destroy(e);
}

static int find_node(const lie_scene *s, const char *name)
{
    for (int i = 0; i < s->n_nodes; i++)
        if (s->nodes[i].name && strcmp(s->nodes[i].name, name) == 0)
            return i;
    return -1;
}

/* ---- round trips ------------------------------------------------------- */

static void test_export_museum2_round_trip_keeps_hash(void **state)
{
    /* the parquet texture (sRGB), the mirror, an emitter with strength > 1 */
    expect_round_trip(state, SCENES "museum2.gltf");
    assert_true(has_text(in_dir(state, "out.gltf"), "\"uri\": \"out_img0.png\""));
    assert_true(has_text(in_dir(state, "out.gltf"), "\"uri\": \"out.bin\""));
    assert_true(has_text(in_dir(state, "out.gltf"), "\"generator\": \"lie\""));
    assert_true(has_text(in_dir(state, "out.gltf"), "KHR_materials_emissive_strength"));
}

/* A normal map through KHR_texture_transform, TANGENT, glass with a
 * transmission texture; a JPEG written as the file's bytes. */
static void test_export_normal_map_glass_and_jpeg_keep_hash_and_bytes(void **state)
{
    expect_round_trip(state, FIXTURES "fidelity.gltf");
    assert_true(has_text(in_dir(state, "out.gltf"), "normalTexture"));
    assert_true(has_text(in_dir(state, "out.gltf"), "\"TANGENT\""));
    assert_true(has_text(in_dir(state, "out.gltf"), "transmissionTexture"));
    size_t n, m;
    unsigned char *a = slurp(in_dir(state, "out_img0.jpg"), &n), *b = slurp(FIXTURES "checker.jpg", &m);
    assert_int_equal(n, m);
    assert_memory_equal(a, b, n);
    free(a);
    free(b);
}

static void test_export_cornell_round_trip_keeps_hash(void **state)
{
    expect_round_trip(state, SCENES "cornell.gltf");
}

static void test_export_textures_in_both_colour_spaces_and_16_bit_keep_hash(void **state)
{
    /* one image as sRGB base colour and emission and as linear
     * metallic-roughness; a 16-bit grey image; clamp/mirror wrap modes */
    expect_round_trip(state, FIXTURES "materials.gltf");
    size_t n;
    unsigned char *png = slurp(in_dir(state, "out_img1.png"), &n);
    assert_true(n > 25);
    assert_int_equal(png[24], 16); /* the file's own 16-bit image, written as it was read */
    free(png);
    png = slurp(in_dir(state, "out_img0.png"), &n);
    assert_int_equal(png[24], 8);
    free(png);
}

static void test_export_lights_cameras_and_skipped_primitives_keep_hash(void **state)
{
    expect_round_trip(state, FIXTURES "lights_cameras.gltf");
    assert_true(has_text(in_dir(state, "out.gltf"), "KHR_lights_punctual"));
    /* perspective cameras are infinite (no zfar); the orthographic one keeps its own */
    assert_false(has_text(in_dir(state, "out.gltf"), "\"zfar\": 0"));
    assert_true(has_text(in_dir(state, "out.gltf"), "\"orthographic\""));
    assert_true(has_text(in_dir(state, "out.gltf"), "\"zfar\": 10"));
    expect_round_trip(state, FIXTURES "modes.gltf");     /* strips, fans; points and lines dropped */
    expect_round_trip(state, FIXTURES "hierarchy.gltf"); /* TRS and matrix parents */
    expect_round_trip(state, FIXTURES "instanced.gltf");
    expect_round_trip(state, FIXTURES "sparse.gltf");
    expect_round_trip(state, FIXTURES "morph.gltf"); /* morphed meshes written as plain ones */
    assert_false(has_text(in_dir(state, "out.gltf"), "targets"));
    expect_round_trip(state, FIXTURES "quantized.gltf"); /* written back as floats */
    expect_round_trip(state, FIXTURES "vertex_colors.gltf");
    assert_true(has_text(in_dir(state, "out.gltf"), "COLOR_0"));
    expect_round_trip(state, FIXTURES "alpha_mask.gltf");
    assert_true(has_text(in_dir(state, "out.gltf"), "\"alphaMode\": \"MASK\""));
    expect_round_trip(state, FIXTURES "texture_transform.gltf");
    assert_true(has_text(in_dir(state, "out.gltf"), "KHR_texture_transform"));
    expect_round_trip(state, FIXTURES "texcoord1.gltf");
    assert_true(has_text(in_dir(state, "out.gltf"), "TEXCOORD_1"));
    assert_true(has_text(in_dir(state, "out.gltf"), "\"texCoord\": 1"));
}

static void test_export_edited_scene_round_trip_keeps_hash(void **state)
{
    lie_scene *s = load(SCENES "museum1.gltf");
    uint64_t before = s->hash;
    apply_edit(s, "- move: {node: Cube, by: [0.4, 0, -0.3]}\n"
                  "- rotate: {node: Chair2, axis: [0, 1, 0], degrees: 35}\n"
                  "- scale: {node: Table, by: [1, 1.2, 1]}\n"
                  "- set-material: {node: TableTop, base-color: [0.8, 0.1, 0.1], metallic: 0, roughness: 0.4}\n"
                  "- set-emission: {node: Light, emissive: [1, 0.8, 0.6], strength: 23.5}\n"
                  "- add: {file: " SCENES "cornell.gltf, node: TallBlock, as: Tower,"
                  " transform: {translation: [1.5, 0, 1.0], scale: [2, 2, 2]}}\n");
    assert_true(s->hash != before);
    lie_scene *r = round_trip(state, s, "edited.gltf");
    assert_same_world(s, r);
    assert_true(find_node(r, "Tower") >= 0);
    lie_scene_destroy(r);
    lie_scene_destroy(s);
}

static void test_export_removed_node_is_absent(void **state)
{
    lie_scene *s = load(SCENES "museum1.gltf");
    apply_edit(s, "- remove: {node: Chair1}\n- move: {node: Cube, by: [0.2, 0, 0]}\n");
    lie_scene *r = round_trip(state, s, "removed.gltf");
    assert_int_equal(find_node(r, "Chair1"), -1);
    assert_int_equal(find_node(r, "ChairSeat1"), -1); /* the subtree went with it */
    assert_true(find_node(r, "Chair2") >= 0);
    /* the remaining triangles, in order, are the edited scene's live ones */
    uint32_t live = 0;
    for (uint32_t t = 0; t < s->n_tris; t++) {
        if (s->tri_removed[t])
            continue;
        assert_true(live < r->n_tris);
        assert_memory_equal(&s->tri_p[3 * (size_t)t], &r->tri_p[3 * (size_t)live], sizeof(lie_vec3) * 3);
        assert_memory_equal(&s->tri_n[3 * (size_t)t], &r->tri_n[3 * (size_t)live], sizeof(lie_vec3) * 3);
        assert_int_equal(s->tri_material[t], r->tri_material[live]);
        live++;
    }
    assert_true(live < s->n_tris);
    assert_int_equal(live, r->n_tris);
    assert_int_equal(s->n_emitters, r->n_emitters);
    lie_scene_destroy(r);
    lie_scene_destroy(s);
}

static void test_export_scene_built_in_memory_with_unusual_texture(void **state)
{
    /* a texture whose values are no 8-bit code's: written as 16-bit, back
     * within half a 16-bit step */
    lie_scene *s = lie_scene_new("memory");
    assert_non_null(s);
    s->textures = calloc(1, sizeof *s->textures);
    assert_non_null(s->textures);
    s->n_textures = 1;
    lie_texture *t = &s->textures[0];
    t->width = 2;
    t->height = 1;
    t->wrap_s = LIE_WRAP_MIRROR;
    t->wrap_t = LIE_WRAP_CLAMP;
    t->rgba = malloc(sizeof(float) * 8);
    assert_non_null(t->rgba);
    const float px[8] = {0.3f, 0.01f, 0.999f, 0.5f, 0.0f, 1.0f, 0.123456f, 0.25f};
    memcpy(t->rgba, px, sizeof px);
    lie_material m = lie_material_default();
    m.base_color_tex = 0;
    m.emissive[0] = 0.5f;
    assert_int_equal(lie_scene_add_material(s, &m), 0);
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, uv[6] = {0, 0, 1, 0, 0, 1};
    const uint32_t idx[3] = {0, 1, 2};
    int mesh = lie_scene_add_mesh(s, "tri", pos, NULL, uv, 3, idx, 1, 0);
    assert_true(mesh >= 0);
    lie_mat4 at = lie_mat4_translation(1, 2, 3);
    assert_true(lie_scene_add_node(s, "a", -1, &at, mesh, -1, -1) >= 0);
    assert_true(lie_scene_add_node(s, "b", 0, NULL, mesh, -1, -1) >= 0);
    lie_error err;
    assert_int_equal(lie_scene_flatten(s, &err), LIE_OK);

    lie_scene *r = round_trip(state, s, "mem.gltf");
    assert_int_equal(r->n_tris, 2);
    assert_memory_equal(s->tri_p, r->tri_p, sizeof(lie_vec3) * 6);
    assert_memory_equal(s->tri_n, r->tri_n, sizeof(lie_vec3) * 6);
    assert_int_equal(r->n_textures, 1);
    assert_int_equal(r->textures[0].wrap_s, LIE_WRAP_MIRROR);
    assert_int_equal(r->textures[0].wrap_t, LIE_WRAP_CLAMP);
    for (int i = 0; i < 8; i++) {
        float v[4];
        lie_texture_texel(&r->textures[0], (size_t)i / 4, v);
        assert_true(fabsf(v[i % 4] - px[i]) < 1e-4f);
    }
    assert_true(r->materials[0].emissive[0] == 0.5f);
    assert_int_equal(r->n_emitters, 2);
    size_t n;
    unsigned char *png = slurp(in_dir(state, "mem_tex0.png"), &n);
    assert_int_equal(png[24], 16);
    assert_int_equal(png[25], 6); /* RGBA: the alpha is not 1 everywhere */
    free(png);
    lie_scene_destroy(r);
    lie_scene_destroy(s);
}

/* ---- output ------------------------------------------------------------- */

/* x.gltf, x.bin and x_tex0.png of folders a and b are byte for byte the same. */
static void assert_same_export(void **state, const char *a, const char *b)
{
    const char *names[] = {"x.gltf", "x.bin", "x_img0.png"};
    for (size_t i = 0; i < sizeof names / sizeof *names; i++) {
        char pa[PATH_MAX], pb[PATH_MAX];
        snprintf(pa, sizeof pa, "%s/%s", a, names[i]);
        snprintf(pb, sizeof pb, "%s/%s", b, names[i]);
        size_t na, nb;
        unsigned char *da = slurp(in_dir(state, pa), &na), *db = slurp(in_dir(state, pb), &nb);
        assert_int_equal(na, nb);
        assert_memory_equal(da, db, na);
        free(da);
        free(db);
    }
}

/* Export through a group with options (force or not), committed. */
static lie_status export_with(const lie_scene *s, const char *path, int force, lie_error *err)
{
    lie_gltf_export_options o = lie_gltf_export_options_default();
    o.force = force;
    lie_atomic_group *g = lie_atomic_group_create();
    assert_non_null(g);
    lie_status st = lie_gltf_export_group(s, path, &o, g, err);
    if (st == LIE_OK)
        st = lie_atomic_group_commit(g, err);
    lie_atomic_group_destroy(g);
    return st;
}

static void test_export_is_deterministic(void **state)
{
    lie_scene *s = load(SCENES "museum2.gltf");
    assert_int_equal(mkdir(in_dir(state, "a"), 0777), 0);
    assert_int_equal(mkdir(in_dir(state, "b"), 0777), 0);
    export_ok(s, in_dir(state, "a/x.gltf"));
    export_ok(s, in_dir(state, "b/x.gltf"));
    assert_same_export(state, "a", "b");
    assert_int_equal(count_entries(in_dir(state, "a")), 3); /* no temporary left */
    lie_scene_destroy(s);
}

static void test_export_file_names_are_uri_escaped(void **state)
{
    lie_scene *s = load(SCENES "museum2.gltf");
    lie_scene *r = round_trip(state, s, "my scene%.gltf");
    assert_true(r->hash == s->hash);
    assert_true(has_text(in_dir(state, "my scene%.gltf"), "my%20scene%25_img0.png"));
    assert_int_equal(access(in_dir(state, "my scene%_img0.png"), F_OK), 0);
    lie_scene_destroy(r);
    lie_scene_destroy(s);
}

static void test_export_into_missing_directory_fails_cleanly(void **state)
{
    lie_scene *s = load(SCENES "museum2.gltf");
    lie_error err;
    lie_error_clear(&err);
    lie_status st = lie_gltf_export(s, in_dir(state, "nowhere/out.gltf"), &err);
    assert_int_equal(st, LIE_ERR_IO);
    assert_int_equal(err.status, LIE_ERR_IO);
    assert_true(err.msg[0] != 0);
    assert_null(strchr(err.msg, '\n'));
    assert_non_null(strstr(err.file, "nowhere/"));
    assert_int_equal(count_entries(*state), 0);
    lie_scene_destroy(s);
}

static void test_export_failure_part_way_removes_files_written(void **state)
{
    /* the .bin cannot be renamed into place (a folder holds its name) after
     * the texture was written: the texture goes again, nothing else is left */
    lie_scene *s = load(SCENES "museum2.gltf");
    assert_int_equal(mkdir(in_dir(state, "out.bin"), 0777), 0);
    lie_error err;
    lie_error_clear(&err);
    /* forced: the folder is not ours, and would be refused before writing */
    lie_status st = export_with(s, in_dir(state, "out.gltf"), 1, &err);
    assert_int_equal(st, LIE_ERR_IO);
    assert_non_null(strstr(err.file, "out.bin"));
    assert_int_equal(count_entries(*state), 1);
    assert_int_equal(count_entries(in_dir(state, "out.bin")), 0);
    lie_scene_destroy(s);
}

static void test_export_to_stdout_or_own_sidecar_name_refused(void **state)
{
    lie_scene *s = load(SCENES "cornell.gltf");
    lie_error err;
    lie_error_clear(&err);
    assert_int_equal(lie_gltf_export(s, "-", &err), LIE_ERR_ARG);
    assert_int_equal(lie_gltf_export(s, in_dir(state, "x.bin"), &err), LIE_ERR_ARG);
    assert_int_equal(lie_gltf_export(s, in_dir(state, ""), &err), LIE_ERR_ARG);
    assert_int_equal(lie_gltf_export(NULL, in_dir(state, "x.gltf"), &err), LIE_ERR_ARG);
    assert_int_equal(count_entries(*state), 0);
    lie_scene_destroy(s);
}

/* ---- GLB ----------------------------------------------------------------- */

static uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* The container of glTF 2.0 §4.4: header, a JSON chunk padded with spaces,
 * one BIN chunk padded with zeros, nothing after; the JSON names no file. */
static void assert_glb_container(const char *path)
{
    size_t n;
    unsigned char *d = slurp(path, &n);
    assert_true(n >= 28);
    assert_memory_equal(d, "glTF", 4);
    assert_int_equal(le32(d + 4), 2);
    assert_int_equal(le32(d + 8), n);
    uint32_t jl = le32(d + 12);
    assert_int_equal(le32(d + 16), 0x4E4F534Au);
    assert_int_equal(jl % 4, 0);
    assert_true(20 + (size_t)jl + 8 <= n);
    char *json = malloc(jl + 1);
    assert_non_null(json);
    memcpy(json, d + 20, jl);
    json[jl] = 0;
    size_t end = strlen(json);
    while (end > 0 && json[end - 1] == ' ')
        end--;
    assert_int_equal(json[end - 1], '}'); /* padding is spaces only */
    assert_null(strstr(json, "\"uri\""));
    assert_non_null(strstr(json, "\"mimeType\":\"image/png\""));
    free(json);
    size_t at = 20 + jl;
    uint32_t bl = le32(d + at);
    assert_int_equal(le32(d + at + 4), 0x004E4942u);
    assert_int_equal(bl % 4, 0);
    assert_int_equal(at + 8 + bl, n); /* one BIN chunk, and it ends the file */
    free(d);
}

static void test_export_glb_round_trip_keeps_hash_and_textures(void **state)
{
    /* several images, both colour spaces, a 16-bit one: all inside the .glb */
    lie_scene *s = load(FIXTURES "materials.gltf");
    assert_true(s->n_textures >= 2);
    lie_scene *r = round_trip(state, s, "out.glb");
    assert_same_world(s, r); /* textures pixel for pixel, then the content hash */
    assert_glb_container(in_dir(state, "out.glb"));
    assert_int_equal(count_entries(*state), 1); /* no .bin, no PNG, no temporary */
    lie_scene_destroy(r);
    lie_scene_destroy(s);
}

static void test_export_gltf_to_glb_to_gltf_gives_the_same_files(void **state)
{
    lie_scene *s = load(SCENES "museum2.gltf");
    assert_int_equal(mkdir(in_dir(state, "a"), 0777), 0);
    assert_int_equal(mkdir(in_dir(state, "c"), 0777), 0);
    lie_scene *a = round_trip(state, s, "a/x.gltf");
    lie_scene *b = round_trip(state, a, "b.GLB"); /* the extension in any case */
    lie_scene *c = round_trip(state, b, "c/x.gltf");
    assert_same_world(s, b);
    assert_same_world(a, c);
    assert_glb_container(in_dir(state, "b.GLB"));
    assert_same_export(state, "a", "c");
    lie_scene_destroy(c);
    lie_scene_destroy(b);
    lie_scene_destroy(a);
    lie_scene_destroy(s);
}

/* ---- side files: replaced only when ours ---------------------------------- */

static void write_text(const char *path, const char *text)
{
    FILE *fp = fopen(path, "wb");
    assert_non_null(fp);
    assert_int_equal(fputs(text, fp) >= 0, 1);
    assert_int_equal(fclose(fp), 0);
}

static void expect_refused(const lie_scene *s, const char *out, const char *side, int entries, void **state)
{
    lie_error err;
    lie_error_clear(&err);
    assert_int_equal(export_with(s, out, 0, &err), LIE_ERR_IO);
    assert_string_equal(err.file, side);
    assert_string_equal(err.msg, "exists (use --force to overwrite)");
    assert_int_equal(count_entries(*state), entries); /* nothing written, no temporary */
}

static void test_export_side_files_of_another_are_refused_unless_forced(void **state)
{
    lie_scene *s = load(SCENES "museum2.gltf");
    const char *out = in_dir(state, "x.gltf");
    char bin[PATH_MAX], png[PATH_MAX];
    snprintf(bin, sizeof bin, "%s", in_dir(state, "x.bin"));
    snprintf(png, sizeof png, "%s", in_dir(state, "x_img0.png"));
    lie_error err;
    lie_error_clear(&err);

    /* a .bin nobody listed */
    write_text(bin, "someone else's");
    expect_refused(s, out, bin, 1, state);
    assert_true(has_text(bin, "someone else's"));
    assert_int_equal(export_with(s, out, 1, &err), LIE_OK); /* forced */
    assert_int_equal(count_entries(*state), 3);

    /* our own files, untouched: replaced without --force */
    assert_int_equal(export_with(s, out, 0, &err), LIE_OK);
    assert_true(has_text(out, "\"lie.files\""));

    /* ours once, changed since: refused */
    FILE *fp = fopen(png, "ab");
    assert_non_null(fp);
    fputc('x', fp);
    fclose(fp);
    expect_refused(s, out, png, 3, state);

    /* listed by a .gltf another program wrote: not ours either */
    assert_int_equal(export_with(s, out, 1, &err), LIE_OK);
    write_text(out, "{\"asset\":{\"version\":\"2.0\",\"generator\":\"other\","
                    "\"extras\":{\"lie.files\":{\"x.bin\":\"0\"}}}}");
    expect_refused(s, out, bin, 3, state);

    /* a .glb has no side files: nothing to refuse */
    assert_int_equal(export_with(s, in_dir(state, "x.glb"), 0, &err), LIE_OK);
    lie_scene_destroy(s);
}

#define T(f) cmocka_unit_test_setup_teardown(f, make_dir, remove_dir)

int main(void)
{
    const struct CMUnitTest tests[] = {
        T(test_export_museum2_round_trip_keeps_hash),
        T(test_export_cornell_round_trip_keeps_hash),
        T(test_export_textures_in_both_colour_spaces_and_16_bit_keep_hash),
        T(test_export_lights_cameras_and_skipped_primitives_keep_hash),
        T(test_export_edited_scene_round_trip_keeps_hash),
        T(test_export_removed_node_is_absent),
        T(test_export_scene_built_in_memory_with_unusual_texture),
        T(test_export_is_deterministic),
        T(test_export_file_names_are_uri_escaped),
        T(test_export_into_missing_directory_fails_cleanly),
        T(test_export_failure_part_way_removes_files_written),
        T(test_export_to_stdout_or_own_sidecar_name_refused),
        T(test_export_glb_round_trip_keeps_hash_and_textures),
        T(test_export_normal_map_glass_and_jpeg_keep_hash_and_bytes),
        T(test_export_gltf_to_glb_to_gltf_gives_the_same_files),
        T(test_export_side_files_of_another_are_refused_unless_forced),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
