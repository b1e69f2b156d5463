/* SPDX-License-Identifier: Apache-2.0 */
/* lib/scene animations (animate.c, glTF 2.0 §3.11 and Appendix C), skins
 * in lie_scene_flatten (§3.7.3) and the set-weights / set-light edits.
 * Fixture: tests/data/gltf/animated.gltf (gen_fixtures.py). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "edit/edit.h"
#include "scene/scene.h"

#define ANIMATED "tests/data/gltf/animated.gltf"

static lie_scene *load(void)
{
    lie_scene *s = NULL;
    lie_error err;
    lie_error_clear(&err);
    if (lie_scene_load(ANIMATED, NULL, &s, &err) != LIE_OK)
        fail_msg("%s: %s", err.file, err.msg);
    return s;
}

static lie_pose *pose_at(const lie_scene *s, int a, double t)
{
    lie_pose *p = NULL;
    lie_error err;
    lie_error_clear(&err);
    assert_int_equal(lie_animation_pose(s, a, t, &p, &err), LIE_OK);
    return p;
}

static void test_animation_read_with_its_range(void **state)
{
    (void)state;
    lie_scene *s = load();
    assert_int_equal(s->n_animations, 2);
    assert_int_equal(lie_scene_find_animation(s, "Idle"), 1);
    assert_int_equal(lie_scene_find_animation(s, "#0"), 0);
    assert_int_equal(lie_scene_find_animation(s, "2"), -1);
    assert_float_equal(s->animations[0].start, 0.5, 0.0);
    assert_float_equal(s->animations[0].end, 2.5, 0.0);
    assert_int_equal(s->animations[0].n_channels, 9);
    assert_false(lie_scene_node_in_scene(s, 12)); /* Offstage */
    assert_true(lie_scene_node_in_scene(s, 8));   /* Bone1, a child */
    lie_scene_destroy(s);
}

static void test_pose_linear_step_and_clamping(void **state)
{
    (void)state;
    lie_scene *s = load();
    lie_pose *p = pose_at(s, 0, 0.75); /* key time 1.25 */
    assert_true(p->trs_set[2] & (1u << LIE_ANIM_TRANSLATION));
    assert_float_equal(p->trs[10 * 2 + 2], 0.75, 1e-12);  /* Slider z: 0 -> 1 over 0.5..1.5 */
    assert_float_equal(p->trs[10 * 5 + 2], 0.8, 1e-6);    /* Stepper: key 1 (t 1.0) held until 1.5 */
    assert_float_equal(p->weights[6][0], 0.75, 1e-12);     /* Sheet weight 0 -> 1 */
    assert_false(p->trs_set[0]);                           /* Floor untouched */
    lie_pose_destroy(p);
    p = pose_at(s, 0, -3.0); /* before the first key: the first value */
    assert_float_equal(p->trs[10 * 2 + 2], 0.0, 0.0);
    lie_pose_destroy(p);
    p = pose_at(s, 0, 100.0); /* after the last key: the last value */
    assert_float_equal(p->trs[10 * 2 + 0], -0.5, 1e-7);
    assert_float_equal(p->trs[10 * 5 + 0], -1.6, 1e-6);
    assert_float_equal(p->weights[6][0], 0.2, 1e-7);
    lie_pose_destroy(p);
    lie_scene_destroy(s);
}

static void test_pose_slerp_is_unit_and_on_the_arc(void **state)
{
    (void)state;
    lie_scene *s = load();
    for (int k = 0; k <= 8; k++) {
        lie_pose *p = pose_at(s, 0, 0.25 * k);
        const double *q = p->trs + 10 * 3 + 3; /* Spinner: about y, 0 -> 90 -> 180 degrees */
        double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        assert_float_equal(len, 1.0, 1e-12);
        double angle = 2.0 * atan2(q[1], q[3]) * 180.0 / M_PI;
        double want = k <= 4 ? 22.5 * k : 90.0 + 22.5 * (k - 4);
        assert_float_equal(angle, want, 1e-4);
        lie_pose_destroy(p);
    }
    lie_scene_destroy(s);
}

static void test_pose_cubicspline_hermite(void **state)
{
    (void)state;
    lie_scene *s = load();
    /* Pulser's y scale: key 0.5 value 1 out-tangent 1, key 1.5 in-tangent 1 value 1.6 */
    for (int i = 0; i <= 4; i++) {
        double u = 0.25 * i;
        lie_pose *p = pose_at(s, 0, u);
        double h00 = 2 * u * u * u - 3 * u * u + 1, h10 = u * u * u - 2 * u * u + u, h01 = -2 * u * u * u + 3 * u * u,
               h11 = u * u * u - u * u;
        assert_float_equal(p->trs[10 * 4 + 8], h00 * 1 + h10 * 1 + h01 * 1.6 + h11 * 1, 1e-6);
        assert_float_equal(p->trs[10 * 4 + 7], 1.0, 1e-12);
        lie_pose_destroy(p);
    }
    lie_scene_destroy(s);
}

/* The arm's top vertices follow Bone1: rotated 45 degrees about z around (ax, 0.5, az). */
static void test_skin_follows_joints(void **state)
{
    (void)state;
    lie_scene *s = load();
    int arm = -1;
    for (int i = 0; i < s->n_instances; i++)
        if (s->instances[i].node == 9)
            arm = i;
    assert_true(arm >= 0);
    uint32_t t0 = s->instances[arm].first_tri;
    /* bind pose: the mesh's own positions */
    assert_float_equal(s->tri_p[3 * (t0 + 3) + 0].y, 1.0f, 1e-6);
    lie_pose *p = pose_at(s, 0, 1.0); /* key time 1.5: Bone1 at +45 degrees */
    lie_edit_op op;
    memset(&op, 0, sizeof op);
    op.kind = LIE_EDIT_SET_TRANSFORM;
    op.node = "#8";
    lie_mat4 m = lie_node_trs_matrix(p->trs + 10 * 8);
    memcpy(op.matrix, m.m, sizeof op.matrix);
    lie_edit e = {"unit.yaml", &op, 1, NULL, 0};
    lie_edit_effect fx;
    memset(&fx, 0, sizeof fx);
    lie_error err;
    lie_error_clear(&err);
    assert_int_equal(lie_edit_apply(s, &e, NULL, &fx, &err), LIE_OK);
    int arm_flagged = 0;
    for (int k = 0; k < fx.n_nodes; k++)
        arm_flagged |= fx.nodes[k] == 9;
    assert_true(arm_flagged); /* a joint's edit is an edit of the mesh it deforms */
    lie_edit_effect_free(&fx);
    /* triangle 3 = (2, 4, 5): vertex 2 is the top left, (ax - 0.15, 1, az) */
    lie_vec3 top = s->tri_p[3 * (t0 + 3) + 0];
    double c = cos(M_PI / 4), sn = sin(M_PI / 4), dx = -0.15, dy = 0.5;
    assert_float_equal(top.x, 1.8 + c * dx - sn * dy, 1e-5);
    assert_float_equal(top.y, 0.5 + sn * dx + c * dy, 1e-5);
    lie_pose_destroy(p);
    lie_scene_destroy(s);
}

static lie_status apply_text(lie_scene *s, const char *text, lie_error *err)
{
    lie_edit *e = NULL;
    lie_status st = lie_edit_parse((const unsigned char *)text, strlen(text), "unit.yaml", &e, err);
    if (st == LIE_OK)
        st = lie_edit_apply(s, e, NULL, NULL, err);
    lie_edit_destroy(e);
    return st;
}

static void test_set_weights_matches_import_and_checks_count(void **state)
{
    (void)state;
    lie_scene *s = load();
    lie_error err;
    lie_error_clear(&err);
    assert_int_equal(apply_text(s, "- set-weights: {node: Sheet, weights: [1]}\n", &err), LIE_OK);
    int sheet = -1;
    for (int i = 0; i < s->n_instances; i++)
        if (s->instances[i].node == 6)
            sheet = i;
    /* target 0 lifts vertices 2 and 3 by 0.5 */
    uint32_t t = s->instances[sheet].first_tri;
    assert_float_equal(s->tri_p[3 * t + 2].y, 1.1f, 1e-6);
    assert_int_equal(apply_text(s, "- set-weights: {node: Sheet, weights: [1, 0]}\n", &err), LIE_ERR_FORMAT);
    assert_non_null(strstr(err.msg, "2 weights, node 'Sheet' has 1 morph targets"));
    assert_int_equal(apply_text(s, "- set-weights: {node: Floor, weights: [1]}\n", &err), LIE_ERR_FORMAT);
    lie_scene_destroy(s);
}

static void test_set_light_changes_the_emitter(void **state)
{
    (void)state;
    lie_scene *s = load();
    lie_error err;
    lie_error_clear(&err);
    uint64_t h = s->hash;
    assert_int_equal(apply_text(s, "- set-light: {node: Bulb, color: [1, 0, 0], intensity: 4, range: 3}\n", &err),
                     LIE_OK);
    int e = -1;
    for (int i = 0; i < s->n_emitters; i++)
        if (s->emitters[i].type == LIE_EMITTER_POINT)
            e = i;
    assert_true(e >= 0);
    assert_float_equal(s->emitters[e].intensity[0], 4.0f, 0.0f);
    assert_float_equal(s->emitters[e].intensity[1], 0.0f, 0.0f);
    assert_float_equal(s->emitters[e].range, 3.0f, 0.0f);
    assert_true(s->hash != h);
    assert_int_equal(apply_text(s, "- move: {node: Bulb, by: [1, 0, 0]}\n", &err), LIE_OK);
    assert_float_equal(s->emitters[e].position.x, -1.0f, 1e-6);
    assert_int_equal(apply_text(s, "- set-emission: {node: Bulb, strength: 2}\n", &err), LIE_ERR_FORMAT);
    assert_int_equal(apply_text(s, "- set-light: {node: Bulb, outer-cone: 30}\n", &err), LIE_ERR_FORMAT);
    lie_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_animation_read_with_its_range),
        cmocka_unit_test(test_pose_linear_step_and_clamping),
        cmocka_unit_test(test_pose_slerp_is_unit_and_on_the_arc),
        cmocka_unit_test(test_pose_cubicspline_hermite),
        cmocka_unit_test(test_skin_follows_joints),
        cmocka_unit_test(test_set_weights_matches_import_and_checks_count),
        cmocka_unit_test(test_set_light_changes_the_emitter),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
