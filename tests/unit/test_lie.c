/* SPDX-License-Identifier: Apache-2.0 */
/* lib/lie and lib/patch: blocker lists on scenes whose answer is known,
 * subdivision limits, conservative lists containing sampled ones,
 * determinism, unit rebuilds, and the patch quad-tree's geometry.
 * Size: one file per module (CONTRIBUTING.md, Tests): lib/lie's behaviours
 * and lib/patch's, in groups below. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "lie.h"
#include "fixtures.h"
#include "lie/shaft.h"

static lie_env *build(const lie_scene *s, lie_rt **rt, lie_build_params p)
{
    lie_error err;
    if (!*rt)
        assert_int_equal(lie_rt_create(s, rt, &err), LIE_OK);
    lie_env *env = NULL;
    lie_build_stats st;
    assert_int_equal(lie_env_build(s, *rt, &p, NULL, &env, &st, &err), LIE_OK);
    return env;
}

/* A scene with a white Lambert floor (triangles 0 and 1, 4 x 4 at y = 0)
 * and two materials: *white (the floor's) and *glow, a double-sided
 * emitter of radiance 5. */
static lie_scene *floor_scene(const char *name, int *white_out, int *glow_out)
{
    lie_scene *s = lie_scene_new(name);
    lie_material white = lie_material_default();
    white.metallic = 0.0f;
    *white_out = lie_scene_add_material(s, &white);
    lie_material glow = white;
    glow.emissive[0] = glow.emissive[1] = glow.emissive[2] = 5.0f;
    glow.double_sided = 1;
    *glow_out = lie_scene_add_material(s, &glow);
    uint32_t idx4[6] = {0, 1, 2, 0, 2, 3};
    float fl[12] = {-2, 0, -2, -2, 0, 2, 2, 0, 2, 2, 0, -2};
    lie_scene_add_node(s, "Floor", -1, NULL, lie_scene_add_mesh(s, "Floor", fl, NULL, NULL, 4, idx4, 2, *white_out),
                       -1, -1);
    return s;
}

/* An emitter of many triangles: a tessellated panel, tilted, over a
 * floor, with a small occluder between.  Its shaft tests use a box
 * oriented to its plane (8 points, not 3 per triangle): the box holds
 * every vertex and is flat, and conservative lists still give the exact
 * image's blockers (every triangle that meets the shaft). */
static lie_scene *panel_scene(int n)
{
    int mw, ml;
    lie_scene *s = floor_scene("panel", &mw, &ml);
    uint32_t idx4[6] = {0, 1, 2, 0, 2, 3};
    float oc[12] = {-0.2f, 1, -0.2f, -0.2f, 1, 0.2f, 0.2f, 1, 0.2f, 0.2f, 1, -0.2f};
    lie_scene_add_node(s, "Occluder", -1, NULL, lie_scene_add_mesh(s, "Occ", oc, NULL, NULL, 4, idx4, 2, mw), -1,
                       -1);
    /* an n x n grid in a plane tilted 30 degrees about x, at height 2 */
    float *pos = malloc(sizeof(float) * 3 * (size_t)((n + 1) * (n + 1)));
    uint32_t *idx = malloc(sizeof(uint32_t) * 6 * (size_t)(n * n));
    float c = cosf(0.5236f), sn = sinf(0.5236f);
    for (int i = 0; i <= n; i++)
        for (int j = 0; j <= n; j++) {
            float u = -0.5f + (float)i / (float)n, v = -0.5f + (float)j / (float)n;
            float *p = &pos[3 * (i * (n + 1) + j)];
            p[0] = u;
            p[1] = 2.0f + v * sn;
            p[2] = v * c;
        }
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            uint32_t a = (uint32_t)(i * (n + 1) + j), b = a + 1, d = a + (uint32_t)n + 1, e = d + 1;
            uint32_t *q = &idx[6 * (i * n + j)];
            q[0] = a, q[1] = d, q[2] = b, q[3] = b, q[4] = d, q[5] = e;
        }
    lie_scene_add_node(s, "Panel", -1, NULL,
                       lie_scene_add_mesh(s, "Panel", pos, NULL, NULL, (uint32_t)((n + 1) * (n + 1)), idx,
                                          (uint32_t)(2 * n * n), ml),
                       -1, -1);
    free(pos);
    free(idx);
    lie_error err;
    assert_int_equal(lie_scene_flatten(s, &err), LIE_OK);
    assert_int_equal(s->n_emitters, 1);
    return s;
}

static void test_lie_many_triangle_emitter_uses_a_flat_oriented_box(void **state)
{
    (void)state;
    lie_scene *s = panel_scene(6);
    const lie_emitter *em = &s->emitters[0];
    assert_int_equal(em->n_tris, 72);
    assert_int_equal(em->n_hull, 8);
    /* the box is flat: its corners lie within a hair of the panel's plane */
    lie_vec3 nrm = s->tri_ng[em->first_tri];
    lie_vec3 p0 = s->tri_p[3 * (size_t)em->first_tri];
    for (int k = 0; k < 8; k++)
        assert_true(fabsf(lie_v3_dot(nrm, lie_v3_sub(em->hull[k], p0))) < 1e-3f);
    /* every vertex of the emitter is inside the box (GJK, in double: the
     * box is too thin to test its faces in float) */
    for (uint32_t t = 0; t < 3 * em->n_tris; t++) {
        lie_vec3 v = s->tri_p[3 * (size_t)em->first_tri + t];
        lie_vec3 point[3] = {v, v, v};
        assert_true(lie_hull_meets_triangle(em->hull, 8, point, 1e-6));
    }
    /* and a point a millimetre off the panel's plane is not */
    lie_vec3 off = lie_v3_add(s->tri_p[3 * (size_t)em->first_tri], lie_v3_scale(nrm, 1e-3f));
    lie_vec3 offp[3] = {off, off, off};
    assert_false(lie_hull_meets_triangle(em->hull, 8, offp, 1e-6));
    /* conservative lists with the box: the floor under the occluder lists
     * its triangles (the panel's own triangles are listed too: Embree can
     * report a grazing segment meeting a neighbour of its sample's
     * triangle, and the LIE image must equal Embree's) */
    lie_rt *rt = NULL;
    lie_build_params p = lie_build_params_default();
    p.mode = LIE_BLOCKERS_CONSERVATIVE;
    p.min_patch = 1e-2f;
    p.max_blockers = p.complex_cap = 1024; /* keep the (long) lists whole */
    lie_env *env = build(s, &rt, p);
    int found = 0;
    for (uint32_t i = 0; i < env->n_nodes; i++) {
        const lie_pnode *nd = &env->nodes[i];
        if (nd->cls != LIE_CLASS_PARTIAL)
            continue;
        for (uint32_t k = 0; k < nd->count; k++) {
            uint32_t b = env->pool[nd->list + k];
            found += b == 2 || b == 3;
        }
    }
    assert_true(found > 0);
    lie_env_destroy(env);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
    /* a panel of few triangles keeps its vertices */
    s = panel_scene(1);
    assert_int_equal(s->emitters[0].n_hull, 0);
    lie_scene_destroy(s);
}

/* A closed, double-sided emitter (a bulb) hides its far side behind its
 * near side: a floor patch's blockers are mostly the bulb's own triangles,
 * and no subdivision removes them, so the pair is complex at once instead
 * of being split down to the smallest patches. */
static void test_lie_self_occluding_emitter_is_complex_without_splitting(void **state)
{
    (void)state;
    int mw, mg;
    lie_scene *s = floor_scene("bulb", &mw, &mg);
    enum { RINGS = 16, SEGS = 24 };
    float pos[3 * (RINGS + 1) * SEGS];
    uint32_t idx[6 * RINGS * SEGS];
    for (int i = 0; i <= RINGS; i++)
        for (int j = 0; j < SEGS; j++) {
            float th = 3.14159265f * (float)i / RINGS, ph = 6.2831853f * (float)j / SEGS;
            float *p = &pos[3 * (i * SEGS + j)];
            p[0] = 0.5f * sinf(th) * cosf(ph);
            p[1] = 2.0f + 0.5f * cosf(th);
            p[2] = 0.5f * sinf(th) * sinf(ph);
        }
    int nt = 0;
    for (int i = 0; i < RINGS; i++)
        for (int j = 0; j < SEGS; j++) {
            uint32_t a = (uint32_t)(i * SEGS + j), b = (uint32_t)(i * SEGS + (j + 1) % SEGS);
            uint32_t c = a + SEGS, d = b + SEGS;
            uint32_t *q = &idx[6 * (i * SEGS + j)];
            q[0] = a, q[1] = c, q[2] = b, q[3] = b, q[4] = c, q[5] = d;
            nt += 2;
        }
    lie_scene_add_node(s, "Bulb", -1, NULL,
                       lie_scene_add_mesh(s, "Bulb", pos, NULL, NULL, (RINGS + 1) * SEGS, idx, (uint32_t)nt, mg), -1,
                       -1);
    lie_error err;
    assert_int_equal(lie_scene_flatten(s, &err), LIE_OK);
    assert_int_equal(s->n_emitters, 1);
    lie_rt *rt = NULL;
    lie_env *env = build(s, &rt, lie_build_params_default());
    for (uint32_t t = 0; t < 2; t++) {
        const lie_pnode *n = &env->nodes[env->root[t]];
        assert_int_equal(n->cls, LIE_CLASS_COMPLEX);
        assert_int_equal(n->child, 0);
        assert_true(n->count > 64);
    }
    lie_env_destroy(env);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

/* Visit every leaf of unit (tri, e) with its patch path. */
typedef void (*leaf_fn)(const lie_env *env, const lie_pnode *n, uint32_t tri, lie_patch_path path, void *ctx);
static void walk(const lie_env *env, uint32_t node, uint32_t tri, lie_patch_path path, leaf_fn fn, void *ctx)
{
    const lie_pnode *n = &env->nodes[node];
    if (n->child) {
        assert_int_equal(n->cls, LIE_CLASS_SPLIT);
        for (int k = 0; k < 4; k++)
            walk(env, n->child + (uint32_t)k, tri, lie_patch_child(path, k), fn, ctx);
        return;
    }
    fn(env, n, tri, path, ctx);
}

typedef struct occ_check {
    const lie_scene *s;
    int partial_with_both, occluded, visible, partial;
} occ_check;

static void check_floor_leaf(const lie_env *env, const lie_pnode *n, uint32_t tri, lie_patch_path path, void *ctx)
{
    occ_check *c = ctx;
    lie_vec3 V[3];
    lie_patch_world(path, &c->s->tri_p[3 * (size_t)tri], V);
    lie_vec3 ctr = lie_v3_scale(lie_v3_add(V[0], lie_v3_add(V[1], V[2])), 1.0f / 3.0f);
    float r = fmaxf(fabsf(ctr.x), fabsf(ctr.z));
    switch (n->cls) {
    case LIE_CLASS_PARTIAL:
        c->partial++;
        assert_true(n->count >= 1 && n->count <= 2);
        for (uint32_t i = 0; i < n->count; i++)
            assert_true(env->pool[n->list + i] == 2 || env->pool[n->list + i] == 3);
        if (n->count == 2)
            c->partial_with_both++;
        break;
    case LIE_CLASS_OCCLUDED:
        c->occluded++;
        /* the umbra is at most the occluder's size, right under it */
        assert_true(r < 0.3f);
        break;
    case LIE_CLASS_VISIBLE:
        c->visible++;
        /* the penumbra ends where the light's far edge is hidden: |x| < 0.3*2 + 0.5 = 1.1 */
        assert_true(r > 0.05f);
        break;
    default:
        fail_msg("floor leaf of class %s", lie_class_name((lie_class)n->cls));
    }
}

static void test_lie_quad_between_floor_and_light_is_the_only_blocker(void **state)
{
    (void)state;
    lie_scene *s = occluder_scene();
    lie_rt *rt = NULL;
    lie_build_params p = lie_build_params_default();
    p.min_patch = 2e-4f; /* patches small enough to lie whole in the umbra (|x|, |z| < 0.1) */
    p.max_blockers = 0; /* split any list of two, to get small patches */
    p.split_gain = 0.0f; /* the paper's rule: split wherever a list is too long */
    p.whole_pixels = 0;  /* and no pixel rule (lie_whole_pixels) */
    lie_env *env = build(s, &rt, p);
    occ_check c = {s, 0, 0, 0, 0};
    for (uint32_t t = 0; t < 2; t++)
        walk(env, env->root[t], t, lie_patch_root(), check_floor_leaf, &c);
    assert_true(c.partial > 0);
    assert_true(c.occluded > 0);
    assert_true(c.visible > 0);
    /* the light itself and the occluder's top face: the light is not lit by itself */
    assert_int_equal(env->nodes[env->root[4]].cls, LIE_CLASS_UNLIT);
    assert_int_equal(env->nodes[env->root[5]].cls, LIE_CLASS_UNLIT);
    lie_env_destroy(env);
    /* without subdivision, both occluder triangles are in the floor's lists */
    p.max_blockers = 8;
    env = build(s, &rt, p);
    for (uint32_t t = 0; t < 2; t++) {
        const lie_pnode *n = &env->nodes[env->root[t]];
        assert_int_equal(n->cls, LIE_CLASS_PARTIAL);
        assert_int_equal(n->count, 2);
        assert_int_equal(env->pool[n->list], 2);
        assert_int_equal(env->pool[n->list + 1], 3);
        assert_true(n->quality >= p.samples);
    }
    lie_env_destroy(env);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

/* A floor under a light with nothing between (triangles 0-1 and 2-3). */
static lie_scene *open_scene(void)
{
    int mw, ml;
    lie_scene *s = floor_scene("open", &mw, &ml);
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    float li[12] = {-0.5f, 2, -0.5f, 0.5f, 2, -0.5f, 0.5f, 2, 0.5f, -0.5f, 2, 0.5f};
    lie_scene_add_node(s, "Light", -1, NULL, lie_scene_add_mesh(s, "Light", li, NULL, NULL, 4, idx, 2, ml), -1, -1);
    lie_error err;
    assert_int_equal(lie_scene_flatten(s, &err), LIE_OK);
    return s;
}

/* A pair whose shaft no triangle enters is visible after a probe of a few
 * segments (lib/lie/sample.c, SHAFT_PROBE), not a whole first round, and
 * is stored as that round would have left it (quality = samples). */
static void test_lie_empty_shaft_is_visible_after_a_probe(void **state)
{
    (void)state;
    lie_scene *s = open_scene();
    lie_rt *rt = NULL;
    lie_error err;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_build_params p = lie_build_params_default();
    lie_env *env = NULL;
    lie_build_stats st;
    memset(&st, 0, sizeof st);
    assert_int_equal(lie_env_build(s, rt, &p, NULL, &env, &st, &err), LIE_OK);
    for (uint32_t t = 0; t < 2; t++) {
        const lie_pnode *n = &env->nodes[env->root[t]];
        assert_int_equal(n->cls, LIE_CLASS_VISIBLE);
        assert_int_equal(n->child, 0);
        assert_int_equal(n->quality, p.samples);
    }
    assert_int_equal(env->nodes[env->root[2]].cls, LIE_CLASS_UNLIT);
    assert_int_equal(env->nodes[env->root[3]].cls, LIE_CLASS_UNLIT);
    assert_true(st.segments > 0);
    assert_true(st.segments <= 2 * (uint64_t)p.samples / 4); /* two floor pairs, an eighth of a round each */
    lie_env_destroy(env);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

static size_t sorted_unique(uint32_t *v, size_t n)
{
    qsort(v, n, sizeof *v, cmp_u32);
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (m == 0 || v[m - 1] != v[i])
            v[m++] = v[i];
    return m;
}

/* lie_rt_all_hits8 (the build's packets of segments) reports, lane by
 * lane, what lie_rt_all_hits reports for each segment alone: the union of
 * the hits, less each lane's exclusions, and which lanes were blocked. */
static void test_rt_packet_all_hits_equal_single_segments(void **state)
{
    (void)state;
    lie_scene *s = test_scene("cornell.gltf");
    lie_rt *rt = NULL;
    lie_error err;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_vec3 lo = s->bounds.lo, ext = lie_v3_sub(s->bounds.hi, s->bounds.lo);
    uint32_t *one = NULL, *all = NULL;
    size_t n_one = 0, cap_one = 0, n_all = 0, cap_all = 0, blocked_seen = 0;
    for (uint64_t q = 0; q < 200; q++) {
        int n = 1 + (int)(q % 8);
        lie_vec3 org[8], dir[8];
        float tnear[8], tfar[8];
        uint32_t ex[8][2];
        int n_ex[8];
        unsigned want = 0;
        n_all = 0;
        size_t n_union = 0;
        uint32_t uni[512];
        for (int k = 0; k < n; k++) {
            float u[6];
            for (int d = 0; d < 6; d++)
                u[d] = lie_hash_to_unit(lie_hash_u64x4(q, (uint64_t)k, (uint64_t)d, 7));
            lie_vec3 a = lie_v3(lo.x + u[0] * ext.x, lo.y + u[1] * ext.y, lo.z + u[2] * ext.z);
            lie_vec3 b = lie_v3(lo.x + u[3] * ext.x, lo.y + u[4] * ext.y, lo.z + u[5] * ext.z);
            org[k] = a;
            dir[k] = lie_v3_sub(b, a);
            tnear[k] = 0.0f;
            tfar[k] = 1.0f;
            ex[k][0] = (uint32_t)(q + (uint64_t)k) % s->n_tris; /* something to leave out */
            n_ex[k] = 1;
            n_one = 0;
            assert_int_equal(lie_rt_all_hits(rt, org[k], dir[k], 0.0f, 1.0f, ex[k], 1, &one, &n_one, &cap_one), LIE_OK);
            if (n_one)
                want |= 1u << k;
            for (size_t j = 0; j < n_one && n_union < 512; j++)
                uni[n_union++] = one[j];
        }
        unsigned got = 0;
        assert_int_equal(lie_rt_all_hits8(rt, org, dir, tnear, tfar, (const uint32_t(*)[2])ex, n_ex, n, &all, &n_all,
                                          &cap_all, &got),
                         LIE_OK);
        assert_int_equal(got, want);
        n_union = sorted_unique(uni, n_union);
        n_all = sorted_unique(all, n_all);
        assert_int_equal(n_all, n_union);
        if (n_all)
            assert_memory_equal(all, uni, n_all * sizeof *all);
        blocked_seen += want != 0;
    }
    assert_true(blocked_seen > 20); /* the segments did meet the box's walls and blocks */
    free(one);
    free(all);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

static int list_has(const uint32_t *list, uint32_t n, uint32_t t)
{
    uint32_t lo = 0, hi = n;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        if (list[mid] < t)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < n && list[lo] == t;
}

typedef struct size_check {
    const lie_scene *s;
    const lie_build_params *p;
    const lie_rt *rt;
    int completed;  /* long lists above the smallest size: exact, made so at a leaf */
} size_check;

/* Every triangle a segment from a point of patch `path` of tri to a point
 * of emitter 0 meets (other than the patch's own and the emitter point's)
 * is in list[0..n): on a 6 x 6 grid of each. */
static void assert_list_complete(const lie_scene *s, const lie_rt *rt, uint32_t tri, lie_patch_path path,
                                 const uint32_t *blockers, uint32_t n)
{
    lie_vec3 V[3];
    lie_patch_world(path, &s->tri_p[3 * (size_t)tri], V);
    uint32_t *hits = NULL;
    size_t n_hits = 0, cap = 0;
    for (int i = 0; i < 36; i++) {
        float b1, b2;
        lie_sample_triangle(((float)(i % 6) + 0.5f) / 6.0f, ((float)(i / 6) + 0.5f) / 6.0f, &b1, &b2);
        lie_vec3 p = lie_v3_add(lie_v3_scale(V[0], 1.0f - b1 - b2),
                                lie_v3_add(lie_v3_scale(V[1], b1), lie_v3_scale(V[2], b2)));
        for (int j = 0; j < 36; j++) {
            lie_vec3 q, nq, org, dir;
            float e1, e2, tnear, tfar;
            uint32_t ex[2] = {tri, lie_emitter_point(s, 0, ((float)(j % 6) + 0.5f) / 6.0f,
                                                     ((float)(j / 6) + 0.5f) / 6.0f, &q, &nq, &e1, &e2)};
            if (!(lie_v3_dot(s->tri_ng[tri], lie_v3_sub(q, p)) > 0.0f) ||
                !lie_shadow_segment(p, s->tri_ng[tri], q, &org, &dir, &tnear, &tfar))
                continue;
            n_hits = 0;
            assert_int_equal(lie_rt_all_hits(rt, org, dir, tnear, tfar, ex, 2, &hits, &n_hits, &cap), LIE_OK);
            for (size_t k = 0; k < n_hits; k++)
                assert_true(list_has(blockers, n, hits[k]));
        }
    }
    free(hits);
}

static void check_leaf_size(const lie_env *env, const lie_pnode *n, uint32_t tri, lie_patch_path path, void *ctx)
{
    size_check *c = ctx;
    float area = c->s->tri_area[tri] / (float)(1u << (2 * path.depth));
    float min_area = c->p->min_patch * c->s->max_tri_area;
    /* a leaf was split from a parent larger than min; it is at least a quarter of that */
    if (path.depth > 0)
        assert_true(4.0f * area > min_area * 0.999f);
    /* A long sampled list only survives at the smallest size.  A pair that
     * sampling called occluded or visible without proof is a leaf with
     * its exact list, whatever its length (lib/lie/subdiv.c): complete. */
    if (n->cls == LIE_CLASS_PARTIAL && n->count > c->p->max_blockers && !(area <= min_area * 1.001f)) {
        assert_list_complete(c->s, c->rt, tri, path, env->pool + n->list, n->count);
        c->completed++;
    }
}

static void test_lie_subdivision_stops_at_min_patch(void **state)
{
    (void)state;
    lie_scene *s = occluder_scene();
    lie_rt *rt = NULL;
    lie_build_params p = lie_build_params_default();
    p.max_blockers = 0; /* split every partial patch, as far as allowed */
    p.split_gain = 0.0f;
    p.whole_pixels = 0; /* no pixel rule: as far as the lists need */
    p.samples = 16;
    p.max_samples = 32;
    const float sizes[] = {1e-1f, 1e-2f, 2e-3f};
    uint32_t prev_nodes = 0;
    for (int i = 0; i < 3; i++) {
        p.min_patch = sizes[i];
        lie_env *env = build(s, &rt, p);
        size_check c = {s, &p, rt, 0};
        for (uint32_t t = 0; t < 2; t++)
            walk(env, env->root[t], t, lie_patch_root(), check_leaf_size, &c);
        assert_true(c.completed < 64); /* few: sampling shapes the tree */
        assert_true(env->n_nodes > prev_nodes); /* smaller patches, more of them */
        prev_nodes = env->n_nodes;
        lie_env_destroy(env);
    }
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

/* The cost rule (split_gain): a split is kept only where it shortens the
 * lists.  On museum1 it keeps far fewer nodes than the paper's rule and
 * undoes some splits.  A leaf it keeps though it could split, with a long
 * list, holds its exact list (the triangles meeting the pair's hull): that
 * contains every blocker the paper's deeper tree found by sampling below
 * the same patch. */
typedef struct gain_check {
    const lie_scene *s;
    const lie_env *paper;    /* split_gain 0 */
    const lie_build_params *p;
    int checked;
} gain_check;

static void paper_lists_inside(const lie_env *paper, uint32_t node, const uint32_t *list, uint32_t n, int *leaves)
{
    const lie_pnode *x = &paper->nodes[node];
    if (x->child) {
        for (uint32_t k = 0; k < 4; k++)
            paper_lists_inside(paper, x->child + k, list, n, leaves);
        return;
    }
    if (x->cls != LIE_CLASS_PARTIAL)
        return;
    ++*leaves;
    for (uint32_t j = 0; j < x->count; j++)
        assert_true(list_has(list, n, paper->pool[x->list + j]));
}

static void check_gain_leaf(const lie_env *env, const lie_pnode *n, uint32_t tri, lie_patch_path path, void *ctx)
{
    gain_check *g = ctx;
    if (n->cls != LIE_CLASS_PARTIAL || n->count <= g->p->max_blockers)
        return;
    float area = g->s->tri_area[tri] / (float)(1u << (2 * path.depth));
    if (!(area > g->p->min_patch * g->s->max_tri_area))
        return;
    /* the same patch in the paper's tree */
    uint32_t node = g->paper->root[tri];
    for (int d = 0; d < path.depth && g->paper->nodes[node].child; d++)
        node = g->paper->nodes[node].child + (uint32_t)lie_patch_digit(path, d);
    int leaves = 0;
    paper_lists_inside(g->paper, node, &env->pool[n->list], n->count, &leaves);
    g->checked += leaves > 0;
}

static void test_lie_split_kept_only_where_it_pays(void **state)
{
    (void)state;
    lie_scene *s = test_scene("museum1.gltf");
    lie_error err;
    lie_rt *rt = NULL;
    lie_build_params p = test_params(1e-3f);
    p.split_gain = 0.0f;
    lie_env *paper = build(s, &rt, p);
    lie_env *env = NULL;
    lie_build_stats st;
    p.split_gain = LIE_SPLIT_GAIN_DEFAULT;
    assert_int_equal(lie_env_build(s, rt, &p, NULL, &env, &st, &err), LIE_OK);
    assert_true(st.splits_undone > 0);
    assert_true(env->n_nodes < paper->n_nodes);
    gain_check g = {s, paper, &p, 0};
    for (uint32_t t = 0; t < s->n_tris; t++)
        walk(env, env->root[t], t, lie_patch_root(), check_gain_leaf, &g);
    assert_true(g.checked > 0);
    lie_env_destroy(env);
    lie_env_destroy(paper);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

static void test_lie_conservative_lists_contain_sampled_lists(void **state)
{
    (void)state;
    lie_scene *s = test_scene("cornell.gltf");
    lie_rt *rt = NULL;
    lie_build_params p = lie_build_params_default();
    p.max_blockers = 1u << 20; /* no subdivision: compare whole triangles */
    p.complex_cap = 1u << 20;
    p.samples = 64;
    p.max_samples = 256;
    lie_env *sampled = build(s, &rt, p);
    p.mode = LIE_BLOCKERS_CONSERVATIVE;
    lie_env *cons = build(s, &rt, p);
    size_t n_units = (size_t)s->n_tris * (size_t)s->n_clusters;
    int partial_seen = 0;
    for (size_t u = 0; u < n_units; u++) {
        const lie_pnode *a = &sampled->nodes[sampled->root[u]], *b = &cons->nodes[cons->root[u]];
        assert_int_equal(a->child, 0);
        assert_int_equal(b->child, 0);
        if (a->cls == LIE_CLASS_UNLIT) {
            assert_int_equal(b->cls, LIE_CLASS_UNLIT);
            continue;
        }
        if (a->cls == LIE_CLASS_PARTIAL || a->cls == LIE_CLASS_OCCLUDED)
            assert_int_equal(b->cls, LIE_CLASS_PARTIAL); /* some blocker was found: the shaft is not empty */
        if (a->cls != LIE_CLASS_PARTIAL)
            continue;
        partial_seen++;
        /* every sampled blocker is in the conservative list */
        for (uint32_t i = 0; i < a->count; i++) {
            uint32_t t = sampled->pool[a->list + i];
            int found = 0;
            for (uint32_t j = 0; j < b->count; j++)
                found |= cons->pool[b->list + j] == t;
            assert_true(found);
        }
    }
    assert_true(partial_seen > 0);
    lie_env_destroy(sampled);
    lie_env_destroy(cons);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

static void test_lie_build_is_identical_for_any_thread_count(void **state)
{
    (void)state;
    lie_scene *s = test_scene("cornell.gltf");
    lie_rt *rt = NULL;
    lie_build_params p = test_params(1e-3f);
    for (int mode = 0; mode < 2; mode++) {
        p.mode = (lie_blocker_mode)mode;
        p.threads = 1;
        lie_env *a = build(s, &rt, p);
        p.threads = 3;
        lie_env *b = build(s, &rt, p);
        assert_env_equal(a, b);
        lie_env_destroy(a);
        lie_env_destroy(b);
    }
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

/* --complex-predict: on cornell with a low complex cap some units are
 * predicted complex, each one complex leaf; the build is the same for any
 * thread count, rebuilding units gives it again, and an audit (built as
 * without the prediction) names the same units, which it measures. */
static void test_lie_units_predicted_complex_are_one_complex_leaf(void **state)
{
    (void)state;
    lie_scene *s = test_scene("cornell.gltf");
    lie_rt *rt = NULL;
    lie_error err;
    assert_int_equal(lie_rt_create(s, &rt, &err), LIE_OK);
    lie_build_params p = test_params(1e-3f);
    p.complex_cap = 0;
    p.max_blockers = 0;
    p.complex_predict = 1;
    lie_build_control ctl;
    memset(&ctl, 0, sizeof ctl);
    lie_build_stats on, on3, audit, tally;
    lie_env *a = NULL, *b = NULL, *c = NULL;
    p.threads = 1;
    assert_int_equal(lie_env_build_with(s, rt, &p, &ctl, &a, &on, &err), LIE_OK);
    p.threads = 3;
    assert_int_equal(lie_env_build_with(s, rt, &p, &ctl, &b, &on3, &err), LIE_OK);
    assert_env_equal(a, b);
    assert_true(on.complex_predicted > 0);
    assert_int_equal(on.complex_predicted, on3.complex_predicted);
    /* each predicted unit is a root that is a complex leaf */
    size_t n_units = (size_t)s->n_tris * (size_t)s->n_clusters, complex_roots = 0;
    for (size_t u = 0; u < n_units; u++)
        complex_roots += a->nodes[a->root[u]].cls == LIE_CLASS_COMPLEX;
    assert_true(complex_roots >= on.complex_predicted);
    lie_env_stats(a, &tally);
    assert_int_equal(tally.pairs[LIE_CLASS_COMPLEX], on.pairs[LIE_CLASS_COMPLEX]);
    uint32_t units[64];
    size_t n = 0;
    for (uint32_t u = 0; u < n_units && n < 64; u += 2)
        units[n++] = u;
    assert_int_equal(lie_env_rebuild_units(b, s, rt, units, n, 2, NULL, &err), LIE_OK);
    assert_env_equal(a, b);
    p.complex_predict = 0;
    ctl.audit_complex = 1;
    assert_int_equal(lie_env_build_with(s, rt, &p, &ctl, &c, &audit, &err), LIE_OK);
    assert_int_equal(audit.complex_predicted, on.complex_predicted);
    assert_true(audit.complex_predicted_measured <= audit.complex_predicted);
    assert_true(audit.complex_measured >= audit.complex_predicted_measured);
    assert_true(audit.segments > on.segments); /* the predicted units' trees were built */
    lie_env_destroy(a);
    lie_env_destroy(b);
    lie_env_destroy(c);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

static void test_lie_rebuilding_units_equals_building(void **state)
{
    (void)state;
    lie_scene *s = test_scene("cornell.gltf");
    lie_error err;
    lie_rt *rt = NULL;
    lie_build_params p = test_params(1e-3f);
    lie_env *a = build(s, &rt, p);
    lie_env *b = build(s, &rt, p);
    /* rebuild every third unit of b: nothing may change */
    uint32_t units[64];
    size_t n = 0;
    for (uint32_t u = 0; u < s->n_tris * (uint32_t)s->n_clusters && n < 64; u += 3)
        units[n++] = u;
    assert_int_equal(lie_env_rebuild_units(b, s, rt, units, n, 2, NULL, &err), LIE_OK);
    assert_env_equal(a, b);
    lie_env_destroy(a);
    lie_env_destroy(b);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

/* lie-build under mpirun: ranges of units built apart join into one
 * build's env, whatever the cut; a missing part is refused. */
static void test_lie_parts_joined_equal_one_build(void **state)
{
    (void)state;
    lie_scene *s = test_scene("cornell.gltf");
    lie_error err;
    lie_rt *rt = NULL;
    lie_build_params p = test_params(1e-3f);
    p.threads = 2;
    lie_env *whole = build(s, &rt, p);
    uint64_t n = (uint64_t)s->n_tris * (uint64_t)s->n_clusters;
    for (uint64_t step = 1; step <= n; step += 5) {
        lie_env_part parts[64];
        size_t k = 0;
        lie_build_stats sum, st;
        memset(&sum, 0, sizeof sum);
        for (uint64_t u = 0; u < n && k < 64; u += step, k++) {
            uint64_t c = n - u < step ? n - u : step;
            assert_int_equal(lie_env_build_range(s, rt, &p, NULL, u, c, &parts[k], &st, &err), LIE_OK);
            lie_build_stats_add(&sum, &st);
        }
        if (k == 64) {
            for (size_t i = 0; i < k; i++)
                lie_env_part_free(&parts[i]);
            continue;
        }
        lie_env *joined = NULL;
        assert_int_equal(lie_env_join(s, &p, parts, k, &joined, &err), LIE_OK);
        assert_env_equal(whole, joined);
        lie_env_destroy(joined);
        if (k > 1) { /* a part missing */
            assert_int_equal(lie_env_join(s, &p, parts + 1, k - 1, &joined, &err), LIE_ERR_ARG);
            assert_null(joined);
        }
        for (size_t i = 0; i < k; i++)
            lie_env_part_free(&parts[i]);
    }
    lie_env_destroy(whole);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
}

/* lie-build under mpirun hands units out costliest first by these
 * weights: positive, one triangle's clusters alike, growing with the
 * triangle's area, a range the slice of the whole, a bad range refused. */
static void test_lie_unit_weights(void **state)
{
    (void)state;
    lie_scene *s = test_scene("cornell.gltf");
    lie_error err;
    lie_build_params p = test_params(1e-3f);
    uint64_t n = (uint64_t)s->n_tris * (uint64_t)s->n_clusters;
    double *w = calloc((size_t)n + 1, sizeof *w), *part = calloc((size_t)n + 1, sizeof *part);
    assert_non_null(w);
    assert_non_null(part);
    assert_int_equal(lie_env_unit_weights(s, &p, NULL, 0, n, w, &err), LIE_OK);
    for (uint64_t u = 0; u < n; u++) {
        uint32_t t = (uint32_t)(u / (uint64_t)s->n_clusters);
        assert_true(w[u] >= 1.0);
        assert_true(w[u] == w[(uint64_t)t * (uint64_t)s->n_clusters]);
        for (uint32_t o = 0; o < s->n_tris; o++)
            if (s->tri_area[o] < s->tri_area[t])
                assert_true(w[(uint64_t)o * (uint64_t)s->n_clusters] <= w[u]);
    }
    uint64_t first = n / 3, count = n / 2;
    assert_int_equal(lie_env_unit_weights(s, &p, NULL, first, count, part, &err), LIE_OK);
    assert_memory_equal(part, w + first, sizeof *w * (size_t)count);
    assert_int_equal(lie_env_unit_weights(s, &p, NULL, n - 1, 2, part, &err), LIE_ERR_ARG);
    free(w);
    free(part);
    lie_scene_destroy(s);
}

static void test_patch_children_tile_the_parent(void **state)
{
    (void)state;
    /* the four children's areas add up to the parent's, and a point's leaf
     * contains it */
    lie_vec3 v[3] = {{0, 0, 0}, {3, 0, 0}, {0, 0, 2}};
    lie_patch_path p = lie_patch_child(lie_patch_child(lie_patch_root(), 3), 1);
    lie_vec3 w[3];
    lie_patch_world(p, v, w);
    float pa = 0.5f * lie_v3_len(lie_v3_cross(lie_v3_sub(w[1], w[0]), lie_v3_sub(w[2], w[0])));
    assert_float_equal(pa, 3.0f / 16.0f, 1e-6f);
    float sum = 0.0f;
    for (int k = 0; k < 4; k++) {
        lie_vec3 c[3];
        lie_patch_world(lie_patch_child(p, k), v, c);
        sum += 0.5f * lie_v3_len(lie_v3_cross(lie_v3_sub(c[1], c[0]), lie_v3_sub(c[2], c[0])));
    }
    assert_float_equal(sum, pa, 1e-6f);
    /* descending from the root with a point's barycentrics follows the
     * patch whose corners contain it */
    for (int i = 0; i < 200; i++) {
        float b1 = lie_hash_to_unit(lie_hash_u64x4((uint64_t)i, 1, 0, 0));
        float b2 = lie_hash_to_unit(lie_hash_u64x4((uint64_t)i, 2, 0, 0));
        if (b1 + b2 > 1.0f) {
            b1 = 1.0f - b1;
            b2 = 1.0f - b2;
        }
        float x = b1, y = b2;
        lie_patch_path path = lie_patch_root();
        for (int d = 0; d < 5; d++)
            path = lie_patch_child(path, lie_patch_descend(&x, &y));
        double c[3][3];
        lie_patch_corners(path, c);
        /* solve point = sum c_k * l_k with the local (x, y) */
        double l0 = 1.0 - x - y;
        double pb1 = c[0][1] * l0 + c[1][1] * x + c[2][1] * y;
        double pb2 = c[0][2] * l0 + c[1][2] * x + c[2][2] * y;
        assert_true(fabs(pb1 - b1) < 1e-5 && fabs(pb2 - b2) < 1e-5);
        assert_true(x >= -1e-6f && y >= -1e-6f && x + y <= 1.0f + 1e-5f);
    }
}

static void test_patch_names_round_trip(void **state)
{
    (void)state;
    lie_patch_path p = lie_patch_root();
    const int digits[] = {0, 3, 1, 2, 2};
    for (int i = 0; i < 5; i++)
        p = lie_patch_child(p, digits[i]);
    char buf[64];
    lie_patch_format(417, p, buf, sizeof buf);
    assert_string_equal(buf, "417/03122");
    uint32_t tri;
    lie_patch_path q;
    assert_true(lie_patch_parse(buf, &tri, &q));
    assert_int_equal(tri, 417);
    assert_int_equal(q.depth, 5);
    assert_true(q.digits == p.digits);
    assert_true(lie_patch_parse("12", &tri, &q) && q.depth == 0);
    assert_false(lie_patch_parse("12/", &tri, &q));
    assert_false(lie_patch_parse("12/4", &tri, &q));
    assert_false(lie_patch_parse("x", &tri, &q));
    assert_false(lie_patch_parse("-1", &tri, &q));
}

/* Spot cones and range (KHR_lights_punctual): a patch outside the outer
 * cone, or past the range, is unlit; one the renderer may weight above 0
 * never is.  Checked against the renderer's own falloff on sample points. */
static float spot_falloff(const lie_emitter *em, lie_vec3 o)
{
    lie_vec3 d = lie_v3_sub(em->position, o);
    float dist = lie_v3_len(d);
    lie_vec3 wi = lie_v3_scale(d, 1.0f / dist);
    float a = 1.0f;
    if (em->cos_outer > -1.5f) {
        float cd = -lie_v3_dot(em->direction, wi);
        a = cd > em->cos_outer ? 1.0f : 0.0f;
    }
    if (em->range > 0.0f && dist >= em->range)
        a = 0.0f;
    return a;
}

static void test_lie_spot_cone_and_range_cull_exactly_the_dark_patches(void **state)
{
    (void)state;
    lie_emitter em;
    memset(&em, 0, sizeof em);
    em.type = LIE_EMITTER_POINT;
    em.position = lie_v3(0.0f, 4.0f, 0.0f);
    em.direction = lie_v3(0.0f, -1.0f, 0.0f);
    em.cos_inner = cosf(0.3f);
    em.cos_outer = cosf(0.5f); /* lights a disc of radius 4 tan 0.5 = 2.19 on the floor */
    em.range = 0.0f;
    lie_scene s;
    memset(&s, 0, sizeof s);
    s.emitters = &em;
    s.n_emitters = 1;
    const lie_vec3 up = lie_v3(0.0f, 1.0f, 0.0f);
    int culled = 0, kept = 0;
    for (int pass = 0; pass < 2; pass++) {
        if (pass == 1) {
            em.cos_outer = -2.0f; /* a point light with a range of 5 */
            em.range = 5.0f;
        }
        for (int i = -12; i <= 12; i++)
            for (int j = -12; j <= 12; j++) {
                float x = 0.5f * (float)i, z = 0.5f * (float)j;
                lie_vec3 V[3] = {lie_v3(x, 0, z), lie_v3(x, 0, z + 0.4f), lie_v3(x + 0.4f, 0, z)};
                int reach = lie_emitter_can_reach(&s, 0, 0, V, up, 0);
                float lit = 0.0f;
                for (int a = 0; a <= 8; a++)
                    for (int b = 0; a + b <= 8; b++) {
                        float b1 = (float)a / 8.0f, b2 = (float)b / 8.0f, b0 = 1.0f - b1 - b2;
                        lie_vec3 o = lie_v3_add(lie_v3_add(lie_v3_scale(V[0], b0), lie_v3_scale(V[1], b1)),
                                                lie_v3_scale(V[2], b2));
                        lit = fmaxf(lit, spot_falloff(&em, o));
                    }
                if (lit > 0.0f)
                    assert_true(reach); /* never cull a patch the renderer lights */
                culled += !reach;
                kept += reach;
            }
    }
    assert_true(culled > 200); /* most of the floor is dark, and culled */
    assert_true(kept > 50);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lie_quad_between_floor_and_light_is_the_only_blocker),
        cmocka_unit_test(test_lie_subdivision_stops_at_min_patch),
        cmocka_unit_test(test_lie_split_kept_only_where_it_pays),
        cmocka_unit_test(test_lie_conservative_lists_contain_sampled_lists),
        cmocka_unit_test(test_lie_build_is_identical_for_any_thread_count),
        cmocka_unit_test(test_lie_rebuilding_units_equals_building),
        cmocka_unit_test(test_lie_units_predicted_complex_are_one_complex_leaf),
        cmocka_unit_test(test_lie_parts_joined_equal_one_build),
        cmocka_unit_test(test_lie_unit_weights),
        cmocka_unit_test(test_patch_children_tile_the_parent),
        cmocka_unit_test(test_patch_names_round_trip),
        cmocka_unit_test(test_lie_many_triangle_emitter_uses_a_flat_oriented_box),
        cmocka_unit_test(test_lie_self_occluding_emitter_is_complex_without_splitting),
        cmocka_unit_test(test_lie_spot_cone_and_range_cull_exactly_the_dark_patches),
        cmocka_unit_test(test_lie_empty_shaft_is_visible_after_a_probe),
        cmocka_unit_test(test_rt_packet_all_hits_equal_single_segments),
    };
    return cmocka_run_group_tests_name("lie", tests, NULL, NULL);
}
