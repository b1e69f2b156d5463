/* SPDX-License-Identifier: Apache-2.0 */
/* lib/edit: edits as data.  Every operation built by its constructor,
 * written (libyaml's emitter) and parsed again is the same operation; the
 * written form is the one lie-view's records hold; a parsed edit keeps its
 * text for the cache's edit log; appending checks values as the parser
 * does; and the inverse of an edit, applied after it, gives back the scene
 * it was computed on. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lie.h"

#define MUSEUM TEST_SCENES "/museum1.gltf"
#define DATA "tests/data/gltf/"

static void assert_same_op(const lie_edit_op *a, const lie_edit_op *b)
{
    assert_int_equal(a->kind, b->kind);
    assert_string_equal(a->node, b->node);
    assert_int_equal(a->has, b->has);
    assert_memory_equal(a->v, b->v, sizeof a->v);
    assert_memory_equal(&a->degrees, &b->degrees, sizeof a->degrees);
    if (a->kind == LIE_EDIT_SET_TRANSFORM || (a->has & LIE_EDIT_HAS_TRANSFORM))
        assert_memory_equal(a->matrix, b->matrix, sizeof a->matrix);
    assert_true((a->file == NULL) == (b->file == NULL));
    if (a->file)
        assert_string_equal(a->file, b->file);
    assert_true((a->as == NULL) == (b->as == NULL));
    if (a->as)
        assert_string_equal(a->as, b->as);
    /* the float fields an operation's `has` gives */
    static const struct {
        unsigned bit;
        size_t offset, size;
    } fields[] = {{LIE_EDIT_HAS_BASE_COLOR, offsetof(lie_edit_op, base_color), 3 * sizeof(float)},
                  {LIE_EDIT_HAS_METALLIC, offsetof(lie_edit_op, metallic), sizeof(float)},
                  {LIE_EDIT_HAS_ROUGHNESS, offsetof(lie_edit_op, roughness), sizeof(float)},
                  {LIE_EDIT_HAS_EMISSIVE, offsetof(lie_edit_op, emissive), 3 * sizeof(float)},
                  {LIE_EDIT_HAS_STRENGTH, offsetof(lie_edit_op, strength), sizeof(float)},
                  {LIE_EDIT_HAS_COLOR, offsetof(lie_edit_op, color), 3 * sizeof(float)},
                  {LIE_EDIT_HAS_INTENSITY, offsetof(lie_edit_op, intensity), sizeof(float)},
                  {LIE_EDIT_HAS_RANGE, offsetof(lie_edit_op, range), sizeof(float)},
                  {LIE_EDIT_HAS_INNER, offsetof(lie_edit_op, inner_deg), sizeof(float)},
                  {LIE_EDIT_HAS_OUTER, offsetof(lie_edit_op, outer_deg), sizeof(float)}};
    for (size_t i = 0; i < sizeof fields / sizeof fields[0]; i++)
        if (a->has & fields[i].bit)
            assert_memory_equal((const char *)a + fields[i].offset, (const char *)b + fields[i].offset,
                                fields[i].size);
    assert_int_equal(a->n_weights, b->n_weights);
    if (a->n_weights)
        assert_memory_equal(a->weights, b->weights, sizeof(double) * (size_t)a->n_weights);
}

static lie_edit *parse_text(const unsigned char *text, size_t size)
{
    lie_edit *e = NULL;
    lie_error err;
    if (lie_edit_parse(text, size, "unit.yaml", &e, &err) != LIE_OK)
        fail_msg("%s", err.msg);
    return e;
}

static void append(lie_edit *e, lie_edit_op op)
{
    lie_error err;
    if (lie_edit_append(e, &op, &err) != LIE_OK)
        fail_msg("%s", err.msg);
}

static void test_every_operation_round_trips_through_its_written_form(void **state)
{
    lie_edit *e = lie_edit_create("unit.yaml");
    assert_non_null(e);
    double m[16];
    for (int k = 0; k < 16; k++)
        m[k] = k % 5 == 0 ? 1.0 : 0.1 * k - 0.0123456789012345; /* needs 17 digits */
    const float rgb[3] = {0.8f, 0.2f, 0.1f}, light[3] = {1.0f, 0.5f, 0.25f};
    const double w[3] = {0.25, 1.0 / 3.0, -0.5};
    append(e, lie_edit_op_move_by("Cube", 0.4, lie_edit_float_value(-0.3f), 1e-7));
    append(e, lie_edit_op_move_to("#3", -1.0, 0.2, 1.5));
    append(e, lie_edit_op_rotate("Chair2", 0.0, 1.0, 0.0, 35.0));
    append(e, lie_edit_op_rotate("Chair2", 0.1, 0.7, 1.0 / 3.0, 1.0 / 7.0)); /* 17-digit doubles */
    append(e, lie_edit_op_scale("Table", 1.0, 1.2, 1.0));
    append(e, lie_edit_op_set_transform("'odd: name', [x]", m));
    append(e, lie_edit_op_remove("Chair1"));
    append(e, lie_edit_op_restore("Chair1"));
    append(e, lie_edit_op_add("sub/other scene.gltf", "#0", "Tower", m));
    append(e, lie_edit_op_add("cornell.gltf", "TallBlock", "Block2", NULL));
    append(e, lie_edit_op_set_material("TableTop", LIE_EDIT_HAS_BASE_COLOR | LIE_EDIT_HAS_METALLIC | LIE_EDIT_HAS_ROUGHNESS,
                                       rgb, 0.0f, 0.4f));
    append(e, lie_edit_op_set_material("TableTop", LIE_EDIT_HAS_ROUGHNESS, NULL, 0.0f, 0.9f));
    append(e, lie_edit_op_set_emission("Light", LIE_EDIT_HAS_EMISSIVE | LIE_EDIT_HAS_STRENGTH, rgb, 14.0f));
    append(e, lie_edit_op_set_emission("Light", LIE_EDIT_HAS_STRENGTH, NULL, 0.0f));
    lie_edit_op one_prim = lie_edit_op_set_material("Blocks", LIE_EDIT_HAS_BASE_COLOR, rgb, 0.0f, 0.0f);
    one_prim.primitive = 2; /* one primitive of the node's mesh (lie-view's undo) */
    one_prim.has |= LIE_EDIT_HAS_PRIMITIVE;
    append(e, one_prim);
    append(e, lie_edit_op_set_weights("Half", w, 3));
    append(e, lie_edit_op_set_light("Spot", LIE_EDIT_HAS_COLOR | LIE_EDIT_HAS_INTENSITY | LIE_EDIT_HAS_RANGE |
                                                LIE_EDIT_HAS_INNER | LIE_EDIT_HAS_OUTER,
                                    light, 12.5f, 8.0f, 10.0f, 30.0f));
    append(e, lie_edit_op_set_light("Bulb", LIE_EDIT_HAS_INTENSITY, NULL, 3.0f, 0.0f, 0.0f, 0.0f));
    assert_int_equal(e->n_ops, 18);
    assert_null(e->text);

    unsigned char *text = NULL;
    size_t size = 0;
    lie_error err;
    assert_int_equal(lie_edit_write(e, &text, &size, &err), LIE_OK);
    assert_int_equal(strlen((const char *)text), size);
    lie_edit *back = parse_text(text, size);
    assert_int_equal(back->n_ops, e->n_ops);
    for (int i = 0; i < e->n_ops; i++)
        assert_same_op(&e->ops[i], &back->ops[i]);
    /* written again, the parsed edit gives the same text */
    unsigned char *again = NULL;
    size_t size2 = 0;
    lie_edit *copy = lie_edit_create("unit.yaml");
    for (int i = 0; i < back->n_ops; i++)
        append(copy, back->ops[i]);
    assert_int_equal(lie_edit_write(copy, &again, &size2, &err), LIE_OK);
    assert_int_equal(size, size2);
    assert_memory_equal(text, again, size);
    free(again);
    free(text);
    lie_edit_destroy(copy);
    lie_edit_destroy(back);
    lie_edit_destroy(e);
}

static void test_written_form_is_one_line_per_operation(void **state)
{
    lie_edit *e = lie_edit_create("unit.yaml");
    const float c[3] = {0.8f, 0.1f, 0.1f};
    append(e, lie_edit_op_move_by("Cube", lie_edit_float_value(0.4f), 0.0, lie_edit_float_value(-0.3f)));
    append(e, lie_edit_op_remove("#12"));
    append(e, lie_edit_op_set_material("TableTop", LIE_EDIT_HAS_BASE_COLOR, c, 0.0f, 0.0f));
    append(e, lie_edit_op_rotate("Chair2", 0.0, 1.0, 0.0, 0.1));
    unsigned char *text = NULL;
    size_t size = 0;
    lie_error err;
    assert_int_equal(lie_edit_write(e, &text, &size, &err), LIE_OK);
    assert_string_equal((const char *)text, "- move: {node: Cube, by: [0.400000006, 0, -0.300000012]}\n"
                                             "- remove: {node: '#12'}\n"
                                             "- set-material: {node: TableTop, base-color: [0.800000012, "
                                             "0.100000001, 0.100000001]}\n"
                                             "- rotate: {node: Chair2, axis: [0, 1, 0], degrees: 0.1}\n");
    free(text);
    lie_edit_destroy(e);
    /* no operation: an empty file, which parses to no operation */
    e = lie_edit_create("unit.yaml");
    assert_int_equal(lie_edit_write(e, &text, &size, &err), LIE_OK);
    assert_int_equal(size, 0);
    lie_edit *back = parse_text(text, size);
    assert_int_equal(back->n_ops, 0);
    free(text);
    lie_edit_destroy(back);
    lie_edit_destroy(e);
}

static void test_parsed_edit_keeps_its_text_for_the_log(void **state)
{
    const char *src = "# a comment the log keeps\n- move: {node: Cube, by: [0.40, 0, -0.3]}   \n";
    lie_edit *e = parse_text((const unsigned char *)src, strlen(src));
    unsigned char *text = NULL;
    size_t size = 0;
    lie_error err;
    assert_int_equal(lie_edit_text(e, &text, &size, &err), LIE_OK);
    assert_int_equal(size, strlen(src));
    assert_memory_equal(text, src, size);
    free(text);
    /* appended to, it is no longer that text: the log gets its written form */
    append(e, lie_edit_op_remove("Chair1"));
    assert_int_equal(lie_edit_text(e, &text, &size, &err), LIE_OK);
    assert_string_equal((const char *)text, "- move: {node: Cube, by: [0.4, 0, -0.3]}\n- remove: {node: Chair1}\n");
    free(text);
    lie_edit_destroy(e);
}

static void test_append_checks_values_as_the_parser_does(void **state)
{
    lie_edit *e = lie_edit_create("unit.yaml");
    lie_error err;
    const float bad[3] = {1.5f, 0.0f, 0.0f};
    lie_edit_op op = lie_edit_op_set_material("TableTop", LIE_EDIT_HAS_BASE_COLOR, bad, 0.0f, 0.0f);
    assert_int_equal(lie_edit_append(e, &op, &err), LIE_ERR_FORMAT);
    assert_non_null(strstr(err.msg, "set-material.base-color: components must be in [0, 1]"));
    op = lie_edit_op_rotate("Cube", 0.0, 0.0, 0.0, 10.0);
    assert_int_equal(lie_edit_append(e, &op, &err), LIE_ERR_FORMAT);
    assert_non_null(strstr(err.msg, "rotate.axis: must not be zero"));
    op = lie_edit_op_set_material("TableTop", 0, NULL, 0.0f, 0.0f);
    assert_int_equal(lie_edit_append(e, &op, &err), LIE_ERR_FORMAT);
    op = lie_edit_op_remove(NULL);
    assert_int_equal(lie_edit_append(e, &op, &err), LIE_ERR_ARG);
    op = lie_edit_op_move_by("Cube", NAN, 0.0, 0.0);
    assert_int_not_equal(lie_edit_append(e, &op, &err), LIE_OK);
    assert_int_equal(e->n_ops, 0); /* nothing was appended */
    lie_edit_destroy(e);
}

static void test_fields_of_one_operation_parse_without_a_node(void **state)
{
    lie_edit *e = NULL;
    lie_error err;
    assert_int_equal(lie_edit_parse_fields("set-material", "{base-color: [0.8, 0.2, 0.1], roughness: 0.5}",
                                           "script.txt", &e, &err),
                     LIE_OK);
    assert_int_equal(e->n_ops, 1);
    assert_null(e->ops[0].node);
    assert_null(e->text);
    assert_int_equal(e->ops[0].kind, LIE_EDIT_SET_MATERIAL);
    assert_int_equal(e->ops[0].has, LIE_EDIT_HAS_BASE_COLOR | LIE_EDIT_HAS_ROUGHNESS);
    assert_true(e->ops[0].base_color[0] == 0.8f && e->ops[0].roughness == 0.5f);
    /* with its node set, it is an operation like any other */
    lie_edit *built = lie_edit_create("script.txt");
    lie_edit_op op = e->ops[0];
    op.node = "Chair2";
    append(built, op);
    lie_edit_destroy(built);
    lie_edit_destroy(e);
    assert_int_equal(lie_edit_parse_fields("set-emission", "strength: 7", "script.txt", &e, &err), LIE_OK);
    assert_int_equal(e->ops[0].has, LIE_EDIT_HAS_STRENGTH);
    lie_edit_destroy(e);
    assert_int_equal(lie_edit_parse_fields("set-material", "metallic: 2", "script.txt", &e, &err), LIE_ERR_FORMAT);
    assert_non_null(strstr(err.msg, "set-material.metallic: must be in [0, 1]"));
    assert_null(e);
}

static lie_scene *load(const char *path)
{
    lie_scene *s = NULL;
    lie_error err;
    if (lie_scene_load(path, NULL, &s, &err) != LIE_OK)
        fail_msg("%s", err.msg);
    return s;
}

static void apply(lie_scene *s, const lie_edit *e)
{
    lie_error err;
    if (lie_edit_apply(s, e, NULL, NULL, &err) != LIE_OK)
        fail_msg("%s", err.msg);
}

/* The world as it looks: every triangle's corners and its material's
 * values.  A set-material gives a node its own copies of its materials (the
 * content hash counts materials and their indices), which no edit takes
 * back; its inverse restores what the copies hold. */
static uint64_t appearance(const lie_scene *s)
{
    lie_hasher *h = lie_hasher_create(0);
    lie_hasher_update(h, s->tri_p, sizeof(lie_vec3) * 3 * s->n_tris);
    lie_hasher_update(h, s->tri_removed, s->n_tris);
    for (uint32_t t = 0; t < s->n_tris; t++) {
        const lie_material *m = lie_scene_material(s, s->tri_material[t]);
        float f[9] = {m->base_color[0], m->base_color[1], m->base_color[2], m->metallic, m->roughness,
                      m->emissive[0],   m->emissive[1],   m->emissive[2],   (float)m->base_color_tex};
        lie_hasher_update(h, f, sizeof f);
    }
    uint64_t d = lie_hasher_digest(h);
    lie_hasher_destroy(h);
    return d;
}

/* Apply op, then its inverse: the scene's content hash (for materials, how
 * it looks) and every node's transform and removal are what they were. */
static void check_inverse(const char *path, lie_edit_op op)
{
    lie_scene *s = load(path);
    int materials = op.kind == LIE_EDIT_SET_MATERIAL || op.kind == LIE_EDIT_SET_EMISSION;
    uint64_t hash = materials ? appearance(s) : s->hash;
    int n_nodes = s->n_nodes;
    lie_mat4 *local = malloc(sizeof *local * (size_t)n_nodes);
    for (int i = 0; i < n_nodes; i++)
        local[i] = s->nodes[i].local;
    lie_edit *e = lie_edit_create("unit.yaml"), *inv = NULL;
    append(e, op);
    lie_error err;
    assert_int_equal(lie_edit_inverse(s, e, &inv, &err), LIE_OK);
    apply(s, e);
    assert_true((materials ? appearance(s) : s->hash) != hash || op.kind == LIE_EDIT_SET_LIGHT); /* it changed */
    apply(s, inv);
    if ((materials ? appearance(s) : s->hash) != hash)
        fail_msg("%s: operation %d on %s: the hash differs after the inverse", path, (int)op.kind, op.node);
    for (int i = 0; i < n_nodes; i++) {
        assert_memory_equal(&local[i], &s->nodes[i].local, sizeof local[i]);
        assert_int_equal(s->nodes[i].removed, 0);
    }
    free(local);
    lie_edit_destroy(inv);
    lie_edit_destroy(e);
    lie_scene_destroy(s);
}

static void test_inverse_after_an_edit_restores_the_scene(void **state)
{
    const float red[3] = {0.8f, 0.1f, 0.1f}, green[3] = {0.1f, 0.9f, 0.2f}, blue[3] = {0.2f, 0.3f, 1.0f};
    double m[16] = {0, 0, -1, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0.5, 0.25, -1, 1};
    const double w[2] = {0.75, 0.125};
    check_inverse(MUSEUM, lie_edit_op_move_by("Cube", 0.4, 0.0, -0.3));
    check_inverse(MUSEUM, lie_edit_op_move_to("Chair2", -1.0, 0.2, 1.5));
    check_inverse(MUSEUM, lie_edit_op_rotate("Chair2", 0.0, 1.0, 0.0, 35.0));
    check_inverse(MUSEUM, lie_edit_op_scale("Table", 1.0, 1.2, 1.0));
    check_inverse(MUSEUM, lie_edit_op_set_transform("Cube", m));
    check_inverse(MUSEUM, lie_edit_op_remove("Chair1"));
    check_inverse(MUSEUM, lie_edit_op_set_material("Table", LIE_EDIT_HAS_BASE_COLOR | LIE_EDIT_HAS_ROUGHNESS, red,
                                                   0.0f, 0.4f));
    check_inverse(MUSEUM, lie_edit_op_set_emission("Light", LIE_EDIT_HAS_STRENGTH, NULL, 3.0f));
    check_inverse(MUSEUM, lie_edit_op_set_emission("Cube", LIE_EDIT_HAS_EMISSIVE | LIE_EDIT_HAS_STRENGTH, green, 2.0f));
    check_inverse(DATA "morph.gltf", lie_edit_op_set_weights("Half", w, 2));
    check_inverse(DATA "lights_cameras.gltf",
                  lie_edit_op_set_light("#1", LIE_EDIT_HAS_COLOR | LIE_EDIT_HAS_INTENSITY | LIE_EDIT_HAS_RANGE, blue,
                                        2.0f, 9.0f, 0.0f, 0.0f));
    check_inverse(DATA "lights_cameras.gltf", lie_edit_op_set_light("#2", LIE_EDIT_HAS_OUTER, NULL, 0.0f, 0.0f, 0.0f, 40.0f));

    /* a removal and its restoration: the restore's inverse removes again */
    lie_scene *s = load(MUSEUM);
    lie_edit *rm = lie_edit_create("unit.yaml"), *inv = NULL, *inv2 = NULL;
    append(rm, lie_edit_op_remove("Chair1"));
    lie_error err;
    assert_int_equal(lie_edit_inverse(s, rm, &inv, &err), LIE_OK);
    apply(s, rm);
    assert_int_equal(inv->n_ops, 1);
    assert_int_equal(inv->ops[0].kind, LIE_EDIT_RESTORE);
    assert_int_equal(lie_edit_inverse(s, inv, &inv2, &err), LIE_OK);
    assert_int_equal(inv2->ops[0].kind, LIE_EDIT_REMOVE);
    lie_edit_destroy(inv2);
    lie_edit_destroy(inv);
    lie_edit_destroy(rm);
    lie_scene_destroy(s);
}

static void test_add_has_no_inverse(void **state)
{
    lie_scene *s = load(MUSEUM);
    lie_edit *e = lie_edit_create(TEST_SCENES "/edit.yaml"), *inv = NULL;
    append(e, lie_edit_op_add("cornell.gltf", "TallBlock", "Tower", NULL));
    lie_error err;
    assert_int_equal(lie_edit_inverse(s, e, &inv, &err), LIE_ERR_UNSUPPORTED);
    assert_null(inv);
    lie_edit_destroy(e);
    lie_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_operation_round_trips_through_its_written_form),
        cmocka_unit_test(test_written_form_is_one_line_per_operation),
        cmocka_unit_test(test_parsed_edit_keeps_its_text_for_the_log),
        cmocka_unit_test(test_append_checks_values_as_the_parser_does),
        cmocka_unit_test(test_fields_of_one_operation_parse_without_a_node),
        cmocka_unit_test(test_inverse_after_an_edit_restores_the_scene),
        cmocka_unit_test(test_add_has_no_inverse),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
