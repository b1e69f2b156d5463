/* SPDX-License-Identifier: Apache-2.0 */
/* lib/core: growable arrays (LIE_GROW, LIE_PUSH) and the shadow-ray
 * conventions of lib/rt/rt.h that lib/lie, lib/rst and lib/shade share. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <stdlib.h>

#include <cmocka.h>

#include "core/core.h"
#include "rt/rt.h"

static void test_push_keeps_every_element_in_order(void **state)
{
    (void)state;
    uint32_t *v = NULL;
    size_t n = 0, cap = 0;
    for (uint32_t i = 0; i < 10000; i++)
        assert_true(LIE_PUSH(v, n, cap, i * 7u));
    assert_int_equal(n, 10000);
    assert_true(cap >= n && cap < 2 * n + 8);
    for (uint32_t i = 0; i < 10000; i++)
        assert_int_equal(v[i], i * 7u);
    free(v);
}

static void test_grow_reserves_at_least_what_is_asked(void **state)
{
    (void)state;
    lie_vec3 *v = NULL;
    size_t cap = 0;
    assert_true(lie_grow(&v, &cap, 0, sizeof *v));
    assert_null(v); /* nothing asked, nothing allocated */
    assert_true(LIE_GROW(v, cap, 3));
    assert_true(cap >= 3);
    v[2] = lie_v3(1, 2, 3);
    size_t before = cap;
    assert_true(LIE_GROW(v, cap, before)); /* room already: unchanged */
    assert_int_equal(cap, before);
    assert_true(LIE_GROW(v, cap, 1000));
    assert_true(cap >= 1000);
    assert_true(v[2].x == 1.0f && v[2].z == 3.0f); /* contents kept */
    free(v);
}

static void test_grow_refuses_sizes_past_memory_and_keeps_the_array(void **state)
{
    (void)state;
    double *v = NULL;
    size_t n = 0, cap = 0;
    assert_true(LIE_PUSH(v, n, cap, 2.5));
    double *keep = v;
    size_t keep_cap = cap;
    assert_false(LIE_GROW(v, cap, SIZE_MAX / 4));
    assert_ptr_equal(v, keep);
    assert_int_equal(cap, keep_cap);
    assert_true(v[0] == 2.5);
    free(v);
}

static void test_shadow_segment_uses_the_shared_offset_and_end(void **state)
{
    (void)state;
    lie_vec3 p = lie_v3(-300.0f, 2.0f, 5.0f), ng = lie_v3(0, 1, 0), q = lie_v3(-300.0f, 12.0f, 5.0f);
    float eps = lie_ray_eps(p);
    assert_true(eps == 1e-4f * 300.0f);
    assert_true(lie_ray_eps(lie_v3(0.5f, -0.25f, 0)) == 1e-4f); /* at least 1e-4 */
    assert_true(lie_ray_eps_bound(300.0f) >= eps);
    lie_vec3 org, dir;
    float tnear, tfar;
    assert_true(lie_shadow_segment(p, ng, q, &org, &dir, &tnear, &tfar));
    lie_vec3 o = lie_ray_origin(p, ng, eps);
    assert_true(org.x == o.x && org.y == o.y && org.z == o.z);
    float len = lie_v3_len(lie_v3_sub(q, o));
    assert_true(tfar == lie_ray_end(len, eps));
    /* the vector form stops at the same place, to rounding */
    float d2 = len * len, k = lie_ray_end_scale(d2, eps);
    assert_float_equal(k * len, tfar, 1e-5f * len);
    assert_true(lie_ray_end_scale(0.0f, eps) == 0.0f);
    /* a target closer than two offsets gives no segment */
    assert_false(lie_shadow_segment(p, ng, lie_v3(-300.0f, 2.0f + eps, 5.0f), &org, &dir, &tnear, &tfar));
}

typedef struct progress_log {
    size_t calls, first, last, total, max;
    int decreasing;
} progress_log;

static void log_progress(void *pctx, size_t done, size_t total)
{
    progress_log *l = pctx; /* calls never overlap (lie_parallel_for) */
    if (l->calls++ == 0)
        l->first = done;
    if (done < l->max)
        l->decreasing = 1;
    l->max = done > l->max ? done : l->max;
    l->last = done;
    l->total = total;
}

static void count_item(void *ctx, size_t item, int worker)
{
    (void)worker;
    ((int *)ctx)[item]++;
}

/* Progress is the summed weight of the finished items over all workers,
 * from 0 to the total, never going back. */
static void test_parallel_progress_weighted(void **state)
{
    (void)state;
    enum { N = 200 };
    uint32_t w[N];
    size_t sum = 0;
    for (int i = 0; i < N; i++)
        sum += w[i] = (uint32_t)(1 + (i * 7) % 13);
    for (int threads = 1; threads <= 4; threads++) {
        int seen[N] = {0};
        progress_log l;
        memset(&l, 0, sizeof l);
        assert_int_equal(lie_parallel_for_weighted(N, threads, count_item, seen, w, log_progress, &l), LIE_OK);
        for (int i = 0; i < N; i++)
            assert_int_equal(seen[i], 1);
        assert_int_equal(l.first, 0);
        assert_int_equal(l.last, sum);
        assert_int_equal(l.total, sum);
        assert_false(l.decreasing);
        assert_true(l.calls >= 2);
    }
    progress_log l;
    memset(&l, 0, sizeof l);
    int seen[N] = {0};
    assert_int_equal(lie_parallel_for(N, 3, count_item, seen, log_progress, &l), LIE_OK);
    assert_int_equal(l.last, N);
    assert_int_equal(l.total, N);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_push_keeps_every_element_in_order),
        cmocka_unit_test(test_parallel_progress_weighted),
        cmocka_unit_test(test_grow_reserves_at_least_what_is_asked),
        cmocka_unit_test(test_grow_refuses_sizes_past_memory_and_keeps_the_array),
        cmocka_unit_test(test_shadow_segment_uses_the_shared_offset_and_end),
    };
    return cmocka_run_group_tests_name("core", tests, NULL, NULL);
}
