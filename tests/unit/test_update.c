/* SPDX-License-Identifier: Apache-2.0 */
/* lib/update (§5): an update equals a rebuild of the edited scene for each
 * of the eight edit operations of formats/edit.md, whatever the chunking of
 * its steps; edits that arrive while units are pending, and after a
 * commit, still give the rebuild; snapshots never show an answer the edit
 * changed. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "lie.h"

#define SCENE TEST_SCENES "/cornell.gltf"
#define EDIT_NAME TEST_SCENES "/update-test.yaml" /* never read: names the edit, resolves `add` */

/* The state a test's cache is built for: cornell after the edits `pre`
 * (applied to the loaded scene, not logged), built in `mode`. */
typedef struct base {
    const char *const *pre;
    int n_pre;
    lie_blocker_mode mode;
    int predict; /* complex units predicted, with a complex cap low enough for cornell to have some */
    uint32_t whole_pixels; /* the whole build's model (lie_whole_pixels); 0: the default */
} base;
static const base CORNELL = {NULL, 0, LIE_BLOCKERS_SAMPLED, 0, 0};

static lie_build_params params(const base *b)
{
    lie_build_params p = lie_build_params_default();
    p.min_patch = 1e-3f;
    p.threads = 2;
    p.mode = b->mode;
    if (b->predict) {
        p.complex_predict = 1;
        p.complex_cap = 0;
        p.max_blockers = 0;
    }
    if (b->whole_pixels)
        p.whole_pixels = b->whole_pixels;
    return p;
}

static lie_edit *parse(const char *text)
{
    lie_edit *e = NULL;
    lie_error err;
    if (lie_edit_parse((const unsigned char *)text, strlen(text), EDIT_NAME, &e, &err) != LIE_OK)
        fail_msg("%s", err.msg);
    return e;
}

static void apply(lie_scene *s, const char *const *texts, int n)
{
    lie_error err;
    lie_scene_options so = lie_scene_options_default();
    for (int i = 0; i < n; i++) {
        lie_edit *e = parse(texts[i]);
        if (lie_edit_apply(s, e, &so, NULL, &err) != LIE_OK)
            fail_msg("%s", err.msg);
        lie_edit_destroy(e);
    }
}

static lie_scene *load(const base *b)
{
    lie_scene *s = NULL;
    lie_error err;
    assert_int_equal(lie_scene_load(SCENE, NULL, &s, &err), LIE_OK);
    apply(s, b->pre, b->n_pre);
    return s;
}

static lie_env *build(const base *b, const lie_scene *s)
{
    lie_error err;
    lie_rt *rt = NULL;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_build_params p = params(b);
    lie_env *env = NULL;
    assert_int_equal(lie_env_build(s, rt, &p, NULL, &env, NULL, &err), LIE_OK);
    lie_rt_destroy(rt);
    return env;
}

/* A cache of the base state as lie-build makes it, and its scene. */
static lie_cache *make_cache(const base *b, lie_scene **scene)
{
    lie_error err;
    *scene = load(b);
    lie_cache *c = calloc(1, sizeof *c);
    c->scene_path = strdup(SCENE);
    c->scene_hash = (*scene)->hash;
    assert_int_equal(lie_cache_set_state(c, *scene, &err), LIE_OK);
    c->env = build(b, *scene);
    return c;
}

/* A fresh build of the base state after the edits, as lie-build would make it. */
static lie_env *rebuild(const base *b, const char *const *texts, int n, lie_scene **scene)
{
    lie_scene *s = load(b);
    apply(s, texts, n);
    lie_env *env = build(b, s);
    *scene = s;
    return env;
}

static void assert_env_equal(const lie_env *a, const lie_env *b)
{
    assert_int_equal(a->n_tris, b->n_tris);
    assert_int_equal(a->n_clusters, b->n_clusters);
    assert_int_equal(a->n_nodes, b->n_nodes);
    assert_int_equal(a->n_pool, b->n_pool);
    assert_true(a->scene_hash == b->scene_hash);
    assert_memory_equal(a->root, b->root, sizeof(uint32_t) * a->n_tris * (size_t)a->n_clusters);
    assert_memory_equal(a->nodes, b->nodes, sizeof(lie_pnode) * a->n_nodes);
    if (a->n_pool)
        assert_memory_equal(a->pool, b->pool, sizeof(uint32_t) * a->n_pool);
}

/* An update of a fresh cache of the base state (make_cache). */
static lie_update *start(const base *b, lie_cache **c, lie_scene **s, int keep_trees)
{
    lie_error err;
    *c = make_cache(b, s);
    lie_update_options o = lie_update_options_default();
    o.threads = 2;
    o.keep_trees = keep_trees;
    lie_update *u = NULL;
    assert_int_equal(lie_update_create(*c, *s, &o, &u, &err), LIE_OK);
    return u;
}

/* Update the base state by `texts` (in steps of `chunk` units, 0 = at
 * once) and check the cache against a rebuild: environments, state, edit
 * log. */
static void check_update_on(const base *b, const char *const *texts, int n, size_t chunk, uint64_t *flagged)
{
    lie_error err;
    lie_scene *s = NULL, *ref_scene = NULL;
    lie_cache *c = NULL;
    lie_update *u = start(b, &c, &s, 0);
    for (int i = 0; i < n; i++) {
        lie_edit *e = parse(texts[i]);
        assert_int_equal(lie_update_edit(u, e, &err), LIE_OK);
        lie_edit_destroy(e);
    }
    lie_update_stats st;
    lie_update_get_stats(u, &st);
    if (flagged)
        *flagged = st.units_flagged + st.units_rebuilt;
    size_t left = lie_update_pending(u), before = left;
    int steps = 0;
    do {
        assert_int_equal(lie_update_step(u, chunk, &left, &err), LIE_OK);
        steps++;
    } while (left);
    if (chunk && before > chunk)
        assert_true(steps > 1);
    assert_int_equal(lie_update_pending(u), 0);
    lie_update_destroy(u);

    lie_env *ref = rebuild(b, texts, n, &ref_scene);
    assert_env_equal(c->env, ref);
    assert_int_equal(c->n_tris, ref_scene->n_tris);
    assert_true(c->state_hash == ref_scene->hash);
    assert_int_equal(c->n_emitters, ref_scene->n_emitters);
    for (int e = 0; e < c->n_emitters; e++) {
        assert_int_equal(c->emitters[e].node, ref_scene->emitters[e].node);
        assert_int_equal(c->emitters[e].first_tri, ref_scene->emitters[e].first_tri);
    }
    assert_int_equal(c->n_edits, n);
    for (int i = 0; i < n; i++) {
        assert_string_equal(c->edits[i].name, EDIT_NAME);
        assert_int_equal(c->edits[i].size, strlen(texts[i]));
        assert_memory_equal(c->edits[i].text, texts[i], strlen(texts[i]));
    }
    lie_env_destroy(ref);
    lie_scene_destroy(ref_scene);
    lie_cache_destroy(c);
    lie_scene_destroy(s);
}

static void check_update(const char *const *texts, int n, size_t chunk, uint64_t *flagged)
{
    check_update_on(&CORNELL, texts, n, chunk, flagged);
}

static const char *const OPS[8] = {
    "- move: {node: TallBlock, by: [0.08, 0, -0.05]}\n",
    "- rotate: {node: ShortBlock, axis: [0, 1, 0], degrees: 25}\n",
    "- scale: {node: TallBlock, by: [1, 0.8, 1]}\n",
    "- set-transform: {node: ShortBlock, matrix: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0.05,0,0.1,1]}\n",
    "- remove: {node: ShortBlock}\n",
    "- add: {file: cornell.gltf, node: TallBlock, as: Tower, transform: {translation: [0.1, 0, 0.1], scale: [0.3, 0.3, 0.3]}}\n",
    "- set-material: {node: ShortBlock, base-color: [0.8, 0.1, 0.1], roughness: 0.4}\n",
    "- set-emission: {node: Light, strength: 0}\n",
};

static void test_update_equals_rebuild_for_each_operation(void **state)
{
    (void)state;
    for (int i = 0; i < 8; i++) {
        uint64_t flagged = 0;
        check_update(&OPS[i], 1, 0, &flagged);
        /* geometry edits reach some units; a material leaves every unit
         * alone, and cornell's only light switched off leaves no unit */
        if (i < 6)
            assert_true(flagged > 0);
        else
            assert_int_equal(flagged, 0);
    }
}

/* Units predicted complex (lie_build_params.complex_predict) are one
 * complex leaf each; an edit in such a unit's shaft may change the
 * prediction, and the update must find it as a rebuild does. */
static void test_update_equals_rebuild_with_complex_units_predicted(void **state)
{
    (void)state;
    for (int m = 0; m < 2; m++) {
        const base b = {NULL, 0, m ? LIE_BLOCKERS_CONSERVATIVE : LIE_BLOCKERS_SAMPLED, 1, 0};
        for (int i = 0; i < 6; i++)
            check_update_on(&b, &OPS[i], 1, 0, NULL);
    }
}

/* restore (an undo of remove): the removed block comes back, update equal
 * to rebuild, and the environments equal those of a cache never edited */
static void test_update_restore_after_remove_equals_rebuild(void **state)
{
    (void)state;
    const char *texts[2] = {OPS[4], "- restore: {node: ShortBlock}\n"};
    uint64_t flagged = 0;
    check_update(texts, 2, 0, &flagged);
    assert_true(flagged > 0);
    check_update(texts, 2, 13, NULL);
}


/* set-material and set-emission with `primitive: K` change that primitive
 * of the node's own mesh alone (lie-view's undo restores each primitive's
 * material so); update equals rebuild; K past the node's primitives is an
 * error at the operation's line, as is a K that is not an integer. */
static void test_set_material_of_one_primitive(void **state)
{
    (void)state;
    const char *texts[2] = {"- set-material: {node: ShortBlock, primitive: 0, base-color: [0.1, 0.7, 0.2]}\n",
                            "- set-emission: {node: Light, primitive: 0, strength: 3}\n"};
    uint64_t flagged = 0;
    check_update(texts, 2, 0, &flagged);
    lie_error err;
    lie_scene *s = load(&CORNELL);
    lie_scene_options so = lie_scene_options_default();
    lie_edit *e = parse(texts[0]);
    assert_int_equal(lie_edit_apply(s, e, &so, NULL, &err), LIE_OK);
    lie_edit_destroy(e);
    int node = -1;
    assert_int_equal(lie_edit_find_node(s, "ShortBlock", &node, "", 0, 0, &err), LIE_OK);
    const lie_material *m = lie_scene_material(s, s->meshes[s->nodes[node].mesh].prims[0].material);
    assert_float_equal(m->base_color[1], 0.7f, 0.0f);
    int tall = -1;
    assert_int_equal(lie_edit_find_node(s, "TallBlock", &tall, "", 0, 0, &err), LIE_OK);
    m = lie_scene_material(s, s->meshes[s->nodes[tall].mesh].prims[0].material);
    assert_float_not_equal(m->base_color[1], 0.7f, 0.0f); /* the shared material was copied first */
    e = parse("\n- set-material: {node: ShortBlock, primitive: 1, roughness: 0.5}\n");
    assert_int_equal(lie_edit_apply(s, e, &so, NULL, &err), LIE_ERR_FORMAT);
    assert_int_equal(err.line, 2);
    assert_non_null(strstr(err.msg, "has 1 primitive in its own mesh, no primitive 1"));
    lie_edit_destroy(e);
    lie_scene_destroy(s);
    const char *bad[] = {"- set-material: {node: ShortBlock, primitive: 1e300, roughness: 0.5}\n",
                         "- set-material: {node: ShortBlock, primitive: -1, roughness: 0.5}\n",
                         "- set-emission: {node: Light, primitive: 0.5, strength: 1}\n"};
    for (int i = 0; i < 3; i++) {
        lie_edit *b = NULL;
        assert_int_equal(lie_edit_parse((const unsigned char *)bad[i], strlen(bad[i]), EDIT_NAME, &b, &err),
                         LIE_ERR_FORMAT);
        assert_non_null(strstr(err.msg, "primitive: expected an integer"));
    }
}

static void test_update_in_chunks_equals_update_at_once(void **state)
{
    (void)state;
    check_update(&OPS[0], 1, 3, NULL);
    check_update(&OPS[5], 1, 17, NULL);
    check_update(&OPS[3], 1, 40, NULL);
}

static void test_update_of_several_files_equals_rebuild(void **state)
{
    (void)state;
    const char *texts[3] = {OPS[0], OPS[1], OPS[4]};
    check_update(texts, 3, 0, NULL);
    check_update(texts, 3, 11, NULL);
}

/* Emitters renumbered: an emitter that appears before the others (walls
 * made emissive come before cornell's light in the walk) or goes moves the
 * indices of every emitter after it, whose units continue unchanged.  In
 * both blocker modes, in one file and over a chain. */
static void test_update_equals_rebuild_when_emitters_are_renumbered(void **state)
{
    (void)state;
    static const char *const ON[4] = {
        "- set-emission: {node: BackWall, emissive: [1, 1, 1], strength: 1}\n",
        "- set-emission: {node: Floor, emissive: [0.5, 0.5, 0.5], strength: 2}\n",
        "- set-emission: {node: LeftWall, emissive: [1, 0.2, 0.2], strength: 1}\n"
        "- set-emission: {node: RightWall, emissive: [0.2, 1, 0.2], strength: 1}\n",
        "- set-emission: {node: BackWall, strength: 0}\n",
    };
    for (int m = 0; m < 2; m++) {
        const base b = {NULL, 0, m ? LIE_BLOCKERS_CONSERVATIVE : LIE_BLOCKERS_SAMPLED, 0, 0};
        for (int i = 0; i < 3; i++)
            check_update_on(&b, &ON[i], 1, 0, NULL);
        check_update_on(&b, ON, 4, 7, NULL); /* on, more before it, the first off again */
        /* a base with the back wall lit: turning it off renumbers the light */
        const base lit = {ON, 1, b.mode, 0, 0};
        check_update_on(&lit, &ON[3], 1, 0, NULL);
    }
}

/* Scene-wide quantities: edits that grow the scene's bounds (its largest
 * extent, and with it how far the shafts of a directional light reach) or
 * its largest triangle, with cornell open to a sun (its ceiling removed, a
 * directional light added) and without, in both blocker modes. */
static void test_update_equals_rebuild_when_scene_wide_sizes_change(void **state)
{
    (void)state;
    static const char *const SUN[2] = {
        "- remove: {node: Ceiling}\n",
        "- add: {file: ../data/gltf/lights_cameras.gltf, node: \"#3\", as: Sun,"
        " transform: {rotation: [-0.3535534, 0.3535534, 0.1464466, 0.8535534]}}\n",
    };
    static const char *const GROW[5] = {
        "- move: {node: TallBlock, by: [2, 0, 0]}\n",                      /* the largest extent grows */
        "- move: {node: ShortBlock, by: [0, 0, -3.5]}\n",                  /* along another axis */
        "- add: {file: cornell.gltf, node: ShortBlock, as: Far, transform: {translation: [9, 0, 0]}}\n",
        "- scale: {node: TallBlock, by: [3, 1, 3]}\n",                     /* the largest triangle grows */
        "- move: {node: TallBlock, by: [0.05, 0, 0.02]}\n",               /* inside the bounds */
    };
    for (int m = 0; m < 2; m++) {
        const lie_blocker_mode mode = m ? LIE_BLOCKERS_CONSERVATIVE : LIE_BLOCKERS_SAMPLED;
        const base open = {SUN, 2, mode, 0, 0}, closed = {NULL, 0, mode, 0, 0};
        for (int i = 0; i < 5; i++) {
            check_update_on(&open, &GROW[i], 1, 0, NULL);
            if (i < 3)
                check_update_on(&closed, &GROW[i], 1, 0, NULL);
        }
        check_update_on(&open, GROW, 3, 9, NULL);
    }
}

/* A whole build's cost model (lie_whole_pixels) with frames of few pixels:
 * the units whose share of the light cannot pay are left unbuilt, and
 * patches split only where their pixels pay.  An edit of the light decides
 * those units again, one that moves the scene's surface past a power of
 * two rebuilds every unit: update equals rebuild either way; and the build
 * is the same for any thread count. */
static void test_update_equals_rebuild_under_the_whole_build_model(void **state)
{
    (void)state;
    static const char *const SUN[2] = {
        "- remove: {node: Ceiling}\n",
        "- add: {file: ../data/gltf/lights_cameras.gltf, node: \"#3\", as: Sun,"
        " transform: {rotation: [-0.3535534, 0.3535534, 0.1464466, 0.8535534]}}\n",
    };
    static const char *const MORE[4] = {
        "- add: {file: cornell.gltf, node: ShortBlock, as: Far, transform: {translation: [9, 0, 0]}}\n",
        "- scale: {node: TallBlock, by: [3, 1, 3]}\n",
        "- set-emission: {node: Light, strength: 0.3}\n",
        "- move: {node: Light, by: [0.1, 0, 0.05]}\n",
    };
    const base b = {SUN, 2, LIE_BLOCKERS_SAMPLED, 0, 3000};
    lie_scene *s = load(&b);
    lie_env *env = build(&b, s);
    size_t units = (size_t)env->n_tris * (size_t)env->n_clusters, none = 0, built = 0;
    for (size_t u = 0; u < units; u++) {
        uint32_t cls = env->nodes[env->root[u]].cls;
        none += cls == LIE_CLASS_NONE;
        built += cls != LIE_CLASS_NONE && cls != LIE_CLASS_UNLIT;
    }
    assert_true(none > 0);  /* the model leaves some units to Embree ... */
    assert_true(built > 0); /* ... and builds others */
    lie_build_params p1 = params(&b);
    p1.threads = 1;
    lie_rt *rt = NULL;
    lie_error err;
    lie_env *one = NULL;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    assert_int_equal(lie_env_build(s, rt, &p1, NULL, &one, NULL, &err), LIE_OK);
    assert_env_equal(env, one);
    lie_env_destroy(one);
    lie_rt_destroy(rt);
    lie_env_destroy(env);
    /* one of the edits moves the surface past a power of two */
    int area_changed = 0;
    for (int i = 0; i < 2; i++) {
        lie_scene *e = load(&b);
        apply(e, &MORE[i], 1);
        area_changed |= lie_whole_area(e) != lie_whole_area(s);
        lie_scene_destroy(e);
    }
    assert_true(area_changed);
    lie_scene_destroy(s);
    for (int i = 0; i < 8; i++)
        check_update_on(&b, &OPS[i], 1, 0, NULL);
    for (int i = 0; i < 4; i++)
        check_update_on(&b, &MORE[i], 1, 0, NULL);
}

/* A cache read from a file older than LIE_CACHE_RULES_VERSION holds units
 * of older rules: its update recomputes every unit, and the result is the
 * present rules' rebuild. */
static void test_update_of_an_older_cache_rebuilds_every_unit(void **state)
{
    (void)state;
    lie_error err;
    lie_scene *s = NULL, *ref_scene = NULL;
    lie_cache *c = make_cache(&CORNELL, &s);
    c->version = LIE_CACHE_RULES_VERSION - 1;
    assert_true(lie_cache_rules_old(c));
    lie_edit *e = parse(OPS[0]);
    lie_update_stats st;
    assert_int_equal(lie_update_apply(c, s, (const lie_edit *const *)&e, 1, NULL, &st, &err), LIE_OK);
    assert_int_equal(st.units_rebuilt, st.units);
    assert_false(lie_cache_rules_old(c));
    lie_env *ref = rebuild(&CORNELL, &OPS[0], 1, &ref_scene);
    assert_env_equal(c->env, ref);
    lie_env_destroy(ref);
    lie_scene_destroy(ref_scene);
    lie_edit_destroy(e);
    lie_cache_destroy(c);
    lie_scene_destroy(s);
}

/* Interactive use: an edit while units are pending, then one after the
 * commit (with keep_trees), each state equal to a rebuild. */
static void test_update_edits_while_pending_and_after_commit(void **state)
{
    (void)state;
    lie_error err;
    lie_scene *s = NULL, *ref_scene = NULL;
    lie_cache *c = NULL;
    lie_update *u = start(&CORNELL, &c, &s, 1);
    const char *texts[3] = {OPS[0], OPS[1], OPS[2]};
    for (int i = 0; i < 3; i++) {
        lie_edit *e = parse(texts[i]);
        assert_int_equal(lie_update_edit(u, e, &err), LIE_OK);
        lie_edit_destroy(e);
        size_t left = 0;
        if (i == 0) {
            assert_int_equal(lie_update_step(u, 2, &left, &err), LIE_OK); /* part of the work, then edit 2 */
            assert_true(left > 0);
            continue;
        }
        do
            assert_int_equal(lie_update_step(u, 5, &left, &err), LIE_OK);
        while (left);
        lie_env *ref = rebuild(&CORNELL, texts, i + 1, &ref_scene);
        assert_env_equal(c->env, ref);
        assert_int_equal(c->n_edits, i + 1);
        lie_env_destroy(ref);
        lie_scene_destroy(ref_scene);
    }
    lie_update_destroy(u);
    lie_cache_destroy(c);
    lie_scene_destroy(s);
}

/* The leaf at `path` of the tree below `node`, if the tree has a leaf there. */
static const lie_pnode *leaf_at(const lie_env *env, uint32_t node, lie_patch_path path)
{
    for (int d = 0; d < path.depth; d++) {
        if (!env->nodes[node].child)
            return NULL;
        node = env->nodes[node].child + (uint32_t)lie_patch_digit(path, d);
    }
    return env->nodes[node].child ? NULL : &env->nodes[node];
}

typedef struct snap_check {
    const lie_env *snap, *final;
    uint32_t final_root;
    uint64_t none, same;
} snap_check;

/* Every snapshot leaf is pending (none) or what the finished update holds
 * for the same patch, wherever the update has a leaf there. */
static void check_leaves(snap_check *k, uint32_t node, lie_patch_path path)
{
    const lie_pnode *x = &k->snap->nodes[node];
    if (x->child) {
        for (uint32_t i = 0; i < 4; i++)
            check_leaves(k, x->child + i, lie_patch_child(path, (int)i));
        return;
    }
    if (x->cls == LIE_CLASS_NONE) {
        k->none++;
        return;
    }
    const lie_pnode *y = leaf_at(k->final, k->final_root, path);
    if (!y)
        return;
    assert_int_equal(x->cls, y->cls);
    assert_int_equal(x->count, y->count);
    if (x->cls == LIE_CLASS_PARTIAL)
        assert_memory_equal(k->snap->pool + x->list, k->final->pool + y->list, sizeof(uint32_t) * x->count);
    k->same++;
}

static void test_update_snapshots_never_show_a_changed_answer(void **state)
{
    (void)state;
    lie_error err;
    lie_scene *s = NULL, *ref_scene = NULL;
    lie_cache *c = NULL;
    lie_update *u = start(&CORNELL, &c, &s, 0);
    lie_env *final = rebuild(&CORNELL, &OPS[0], 1, &ref_scene);
    lie_edit *e = parse(OPS[0]);
    assert_int_equal(lie_update_edit(u, e, &err), LIE_OK);
    lie_edit_destroy(e);
    size_t left = lie_update_pending(u);
    assert_true(left > 4);
    int rounds = 0;
    for (;;) {
        lie_env *snap = NULL;
        assert_int_equal(lie_update_snapshot(u, &snap, &err), LIE_OK);
        assert_int_equal(snap->n_tris, s->n_tris);
        assert_int_equal(snap->n_clusters, s->n_clusters);
        snap_check k = {snap, final, 0, 0, 0};
        for (size_t unit = 0; unit < (size_t)s->n_tris * (size_t)s->n_clusters; unit++) {
            k.final_root = final->root[unit];
            check_leaves(&k, snap->root[unit], lie_patch_root());
        }
        assert_true(k.same > 0);
        if (left)
            assert_true(k.none > 0); /* pending pairs go to Embree */
        else
            assert_env_equal(snap, final);
        lie_env_destroy(snap);
        if (!left)
            break;
        assert_int_equal(lie_update_step(u, 2, &left, &err), LIE_OK);
        rounds++;
    }
    assert_true(rounds > 1);
    lie_update_destroy(u);
    lie_env_destroy(final);
    lie_scene_destroy(ref_scene);
    lie_cache_destroy(c);
    lie_scene_destroy(s);
}

static void test_update_refuses_a_scene_that_is_not_the_caches(void **state)
{
    (void)state;
    lie_error err;
    lie_scene *s = NULL;
    lie_cache *c = make_cache(&CORNELL, &s);
    c->state_hash ^= 1;
    lie_update *u = NULL;
    assert_int_equal(lie_update_create(c, s, NULL, &u, &err), LIE_ERR_ARG);
    assert_null(u);
    lie_cache_destroy(c);
    lie_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_update_equals_rebuild_for_each_operation),
        cmocka_unit_test(test_update_restore_after_remove_equals_rebuild),
        cmocka_unit_test(test_update_equals_rebuild_with_complex_units_predicted),
        cmocka_unit_test(test_set_material_of_one_primitive),
        cmocka_unit_test(test_update_in_chunks_equals_update_at_once),
        cmocka_unit_test(test_update_of_several_files_equals_rebuild),
        cmocka_unit_test(test_update_equals_rebuild_when_emitters_are_renumbered),
        cmocka_unit_test(test_update_equals_rebuild_when_scene_wide_sizes_change),
        cmocka_unit_test(test_update_equals_rebuild_under_the_whole_build_model),
        cmocka_unit_test(test_update_of_an_older_cache_rebuilds_every_unit),
        cmocka_unit_test(test_update_edits_while_pending_and_after_commit),
        cmocka_unit_test(test_update_snapshots_never_show_a_changed_answer),
        cmocka_unit_test(test_update_refuses_a_scene_that_is_not_the_caches),
    };
    return cmocka_run_group_tests_name("update", tests, NULL, NULL);
}
