/* SPDX-License-Identifier: Apache-2.0 */
/* lie-inspect diff A B: compare two caches by content, not bytes.  Units
 * are matched by (triangle, emitter), nodes by patch path, blocker lists as
 * sets.  Provenance that cannot change an image (the scene's path as
 * given, the hash of the file before edits, the edit log: an edited cache
 * against a fresh build of the edited scene) is a note, a difference only
 * with --strict.  Exit 0 same, 1 different, 2 trouble (as diff(1)). */
#include "inspect.h"

#include <stdlib.h>
#include <string.h>

typedef enum diff_kind { D_ONLY_A = 0, D_ONLY_B, D_CLASS, D_LIST, D_DETAIL, D_KINDS } diff_kind;
static const char *const kind_name[D_KINDS] = {"only_a", "only_b", "class", "list", "detail"};

typedef struct diff_item {
    uint32_t tri;
    int e;
    lie_patch_path path;
    diff_kind kind;
    uint32_t na, nb; /* node in A, in B (UINT32_MAX: none) */
} diff_item;

/* A header field that differs. */
typedef struct diff_field {
    char name[32];
    char a[512], b[512];
    int counted; /* 0: provenance note */
} diff_field;

typedef struct diff_ctx {
    const lie_env *a, *b;
    uint64_t count[D_KINDS];
    diff_item *items;
    size_t n_items, cap, limit;
    int oom;
    diff_field *fields;
    int n_fields;
    size_t cap_fields;
} diff_ctx;

static void record(diff_ctx *d, diff_kind k, uint32_t tri, int e, lie_patch_path path, uint32_t na, uint32_t nb)
{
    d->count[k]++;
    if (d->n_items >= d->limit || d->oom)
        return;
    diff_item it = {tri, e, path, k, na, nb};
    if (!LIE_PUSH(d->items, d->n_items, d->cap, it))
        d->oom = 1;
}

/* A subtree present on one side only; returns the nodes in it. */
static uint64_t one_side(diff_ctx *d, const lie_env *env, uint32_t node, diff_kind k, uint32_t tri, int e,
                         lie_patch_path path)
{
    record(d, k, tri, e, path, k == D_ONLY_A ? node : UINT32_MAX, k == D_ONLY_B ? node : UINT32_MAX);
    uint64_t n = 1;
    const lie_pnode *x = &env->nodes[node];
    if (x->child)
        for (int c = 0; c < 4; c++)
            n += one_side(d, env, x->child + (uint32_t)c, k, tri, e, lie_patch_child(path, c));
    return n;
}

static int same_list(const lie_env *a, const lie_pnode *x, const lie_env *b, const lie_pnode *y)
{
    /* lists are sorted and unique (the reader checked), so equal sets are equal arrays */
    return x->count == y->count && memcmp(a->pool + x->list, b->pool + y->list, sizeof(uint32_t) * x->count) == 0;
}

/* Compare the trees under na and nb at the same patch; returns 1 if they differ. */
static int compare(diff_ctx *d, uint32_t na, uint32_t nb, uint32_t tri, int e, lie_patch_path path)
{
    const lie_pnode *x = &d->a->nodes[na], *y = &d->b->nodes[nb];
    int differ = 1;
    if (x->cls != y->cls)
        record(d, D_CLASS, tri, e, path, na, nb);
    else if (x->cls == LIE_CLASS_PARTIAL && !x->child && !same_list(d->a, x, d->b, y))
        record(d, D_LIST, tri, e, path, na, nb);
    else if (x->quality != y->quality || x->count != y->count)
        record(d, D_DETAIL, tri, e, path, na, nb);
    else
        differ = 0;
    for (int c = 0; c < 4; c++) {
        lie_patch_path cp = lie_patch_child(path, c);
        if (x->child && y->child)
            differ |= compare(d, x->child + (uint32_t)c, y->child + (uint32_t)c, tri, e, cp);
        else if (x->child)
            one_side(d, d->a, x->child + (uint32_t)c, D_ONLY_A, tri, e, cp);
        else if (y->child)
            one_side(d, d->b, y->child + (uint32_t)c, D_ONLY_B, tri, e, cp);
    }
    return differ | ((x->child != 0) != (y->child != 0));
}

static void field(diff_ctx *d, const char *name, const char *a, const char *b, int counted)
{
    if (strcmp(a, b) == 0 || d->oom)
        return;
    if (!LIE_GROW(d->fields, d->cap_fields, (size_t)d->n_fields + 1)) {
        d->oom = 1;
        return;
    }
    diff_field *f = &d->fields[d->n_fields++];
    snprintf(f->name, sizeof f->name, "%s", name);
    snprintf(f->a, sizeof f->a, "%s", a);
    snprintf(f->b, sizeof f->b, "%s", b);
    f->counted = counted;
}

static void field_u(diff_ctx *d, const char *name, unsigned long long a, unsigned long long b, int counted)
{
    char x[32], y[32];
    snprintf(x, sizeof x, "%llu", a);
    snprintf(y, sizeof y, "%llu", b);
    field(d, name, x, y, counted);
}

static void field_hash(diff_ctx *d, const char *name, uint64_t a, uint64_t b, int counted)
{
    char x[32], y[32];
    snprintf(x, sizeof x, "%016llx", (unsigned long long)a);
    snprintf(y, sizeof y, "%016llx", (unsigned long long)b);
    field(d, name, x, y, counted);
}

static void emitter_str(const lie_cache *c, int e, char *buf, size_t size)
{
    if (e >= c->n_emitters) {
        snprintf(buf, size, "(none)");
        return;
    }
    const lie_cache_emitter *m = &c->emitters[e];
    snprintf(buf, size, "%s node %d first-tri %u tris %u", inspect_emitter_type_name(m->type), m->node, m->first_tri,
             m->n_tris);
}

static void edits_str(const lie_cache *c, char *buf, size_t size)
{
    size_t at = (size_t)snprintf(buf, size, "%d edit%s", c->n_edits, c->n_edits == 1 ? "" : "s");
    for (int i = 0; i < c->n_edits && at < size; i++)
        at += (size_t)snprintf(buf + at, size - at, "%s%s (%zu bytes, xxh3 %016llx)", i ? ", " : ": ",
                               c->edits[i].name, c->edits[i].size,
                               (unsigned long long)lie_hash_bytes(c->edits[i].text, c->edits[i].size, 0));
    if (at >= size && size > 4)
        memcpy(buf + size - 4, "...", 4);
}

static void compare_headers(diff_ctx *d, const lie_cache *a, const lie_cache *b, int strict)
{
    const lie_build_params *p = &a->env->params, *q = &b->env->params;
    char x[512], y[512];
    field_hash(d, "state hash", a->state_hash, b->state_hash, 1);
    field_u(d, "triangles", a->n_tris, b->n_tris, 1);
    field_u(d, "emitters", (unsigned long long)a->n_emitters, (unsigned long long)b->n_emitters, 1);
    field_u(d, "param samples", p->samples, q->samples, 1);
    field_u(d, "param max-samples", p->max_samples, q->max_samples, 1);
    field_u(d, "param max-blockers", p->max_blockers, q->max_blockers, 1);
    field_u(d, "param complex-cap", p->complex_cap, q->complex_cap, 1);
    snprintf(x, sizeof x, "%.9g", (double)p->min_patch);
    snprintf(y, sizeof y, "%.9g", (double)q->min_patch);
    field(d, "param min-patch", x, y, 1);
    snprintf(x, sizeof x, "%.9g", (double)p->split_gain);
    snprintf(y, sizeof y, "%.9g", (double)q->split_gain);
    field(d, "param split-gain", x, y, 1);
    field(d, "param blockers", inspect_mode_name(p->mode), inspect_mode_name(q->mode), 1);
    field_u(d, "param frames", p->frames, q->frames, 1);
    field_u(d, "param light-samples", p->light_samples, q->light_samples, 1);
    snprintf(x, sizeof x, "%.9g %.9g %.9g", (double)p->ns_segment, (double)p->ns_blocker, (double)p->ns_ray);
    snprintf(y, sizeof y, "%.9g %.9g %.9g", (double)q->ns_segment, (double)q->ns_blocker, (double)q->ns_ray);
    field(d, "param cost-ns", x, y, 1);
    field_u(d, "views", (unsigned long long)a->views.n_cams, (unsigned long long)b->views.n_cams, 1);
    int ne = a->n_emitters > b->n_emitters ? a->n_emitters : b->n_emitters;
    for (int e = 0; e < ne; e++) {
        char name[32];
        snprintf(name, sizeof name, "emitter %d", e);
        emitter_str(a, e, x, sizeof x);
        emitter_str(b, e, y, sizeof y);
        field(d, name, x, y, 1);
    }
    field(d, "scene path", a->scene_path, b->scene_path, strict);
    field_hash(d, "scene hash", a->scene_hash, b->scene_hash, strict);
    edits_str(a, x, sizeof x);
    edits_str(b, y, sizeof y);
    field(d, "edit log", x, y, strict);
}

static void item_text(const diff_ctx *d, const diff_item *it)
{
    char name[64];
    lie_patch_format(it->tri, it->path, name, sizeof name);
    const lie_pnode *x = it->na != UINT32_MAX ? &d->a->nodes[it->na] : NULL;
    const lie_pnode *y = it->nb != UINT32_MAX ? &d->b->nodes[it->nb] : NULL;
    printf("  %s %d: ", name, it->e);
    switch (it->kind) {
    case D_ONLY_A:
    case D_ONLY_B:
        printf("only in %c: ", it->kind == D_ONLY_A ? 'A' : 'B');
        inspect_print_node(stdout, x ? d->a : d->b, x ? x : y);
        break;
    case D_CLASS:
        printf("class %s vs %s", lie_class_name((lie_class)x->cls), lie_class_name((lie_class)y->cls));
        break;
    case D_LIST: {
        /* the symmetric difference of two sorted lists */
        printf("blockers %u vs %u:", x->count, y->count);
        const uint32_t *p = d->a->pool + x->list, *q = d->b->pool + y->list;
        uint32_t i = 0, j = 0;
        while (i < x->count || j < y->count) {
            if (j >= y->count || (i < x->count && p[i] < q[j]))
                printf(" -%u", p[i++]);
            else if (i >= x->count || q[j] < p[i])
                printf(" +%u", q[j++]);
            else
                i++, j++;
        }
        break;
    }
    case D_DETAIL:
        printf("%s quality %u vs %u, count %u vs %u", lie_class_name((lie_class)x->cls), x->quality, y->quality,
               x->count, y->count);
        break;
    default: break;
    }
    putchar('\n');
}

static void item_json(const diff_ctx *d, const diff_item *it)
{
    char name[64];
    lie_patch_format(it->tri, it->path, name, sizeof name);
    printf("{\"patch\":\"%s\",\"emitter\":%d,\"kind\":\"%s\"", name, it->e, kind_name[it->kind]);
    if (it->na != UINT32_MAX) {
        printf(",\"a\":{");
        inspect_json_node(stdout, d->a, &d->a->nodes[it->na]);
        putchar('}');
    }
    if (it->nb != UINT32_MAX) {
        printf(",\"b\":{");
        inspect_json_node(stdout, d->b, &d->b->nodes[it->nb]);
        putchar('}');
    }
    putchar('}');
}

int inspect_diff(const char *pa, const char *pb, const inspect_options *o)
{
    inspect_cache la, lb;
    lie_error err;
    if (inspect_load(pa, &la, &err) != LIE_OK) {
        inspect_unload(&la);
        return inspect_fail(&err, 2);
    }
    if (inspect_load(pb, &lb, &err) != LIE_OK) {
        inspect_unload(&la);
        inspect_unload(&lb);
        return inspect_fail(&err, 2);
    }
    const lie_cache *A = la.cache, *B = lb.cache;
    diff_ctx d;
    memset(&d, 0, sizeof d);
    d.a = A->env;
    d.b = B->env;
    d.limit = o->all ? SIZE_MAX : INSPECT_DIFF_SHOWN;
    compare_headers(&d, A, B, o->strict);

    uint32_t nt = A->n_tris > B->n_tris ? A->n_tris : B->n_tris;
    int na = A->env->n_clusters, nb = B->env->n_clusters; /* units per triangle */
    int ne = na > nb ? na : nb;
    uint64_t compared = 0, identical = 0, only_a = 0, only_b = 0;
    for (uint32_t t = 0; t < nt; t++)
        for (int e = 0; e < ne; e++) {
            int in_a = t < A->n_tris && e < na, in_b = t < B->n_tris && e < nb;
            uint32_t ra = in_a ? d.a->root[(size_t)t * (size_t)na + (size_t)e] : 0;
            uint32_t rb = in_b ? d.b->root[(size_t)t * (size_t)nb + (size_t)e] : 0;
            if (in_a && in_b) {
                compared++;
                identical += !compare(&d, ra, rb, t, e, lie_patch_root());
            } else if (in_a) {
                only_a++;
                one_side(&d, d.a, ra, D_ONLY_A, t, e, lie_patch_root());
            } else {
                only_b++;
                one_side(&d, d.b, rb, D_ONLY_B, t, e, lie_patch_root());
            }
        }
    if (d.oom) {
        free(d.items);
        free(d.fields);
        inspect_unload(&la);
        inspect_unload(&lb);
        lie_error_set(&err, LIE_ERR_NOMEM, pa, "out of memory");
        return inspect_fail(&err, 2);
    }
    uint64_t total = 0;
    for (int k = 0; k < D_KINDS; k++)
        total += d.count[k];
    int header_diffs = 0, notes = 0;
    for (int i = 0; i < d.n_fields; i++) {
        header_diffs += d.fields[i].counted;
        notes += !d.fields[i].counted;
    }
    int same = total == 0 && header_diffs == 0;

    if (o->quiet) {
        /* exit status only */
    } else if (o->json) {
        printf("{\"a\":");
        inspect_json_string(stdout, pa);
        printf(",\"b\":");
        inspect_json_string(stdout, pb);
        printf(",\"same\":%s,\"strict\":%s", same ? "true" : "false", o->strict ? "true" : "false");
        printf(",\"units\":{\"compared\":%llu,\"identical\":%llu,\"differing\":%llu,\"only_a\":%llu,\"only_b\":%llu}",
               (unsigned long long)compared, (unsigned long long)identical,
               (unsigned long long)(compared - identical), (unsigned long long)only_a, (unsigned long long)only_b);
        printf(",\"nodes\":{");
        for (int k = 0; k < D_KINDS; k++)
            printf("%s\"%s\":%llu", k ? "," : "", kind_name[k], (unsigned long long)d.count[k]);
        putchar('}');
        for (int pass = 0; pass < 2; pass++) {
            printf(",\"%s\":[", pass == 0 ? "header" : "notes");
            int first = 1;
            for (int i = 0; i < d.n_fields; i++) {
                const diff_field *f = &d.fields[i];
                if (f->counted != (pass == 0))
                    continue;
                printf("%s{\"field\":", first ? "" : ",");
                inspect_json_string(stdout, f->name);
                printf(",\"a\":");
                inspect_json_string(stdout, f->a);
                printf(",\"b\":");
                inspect_json_string(stdout, f->b);
                putchar('}');
                first = 0;
            }
            putchar(']');
        }
        printf(",\"differences_total\":%llu,\"differences\":[", (unsigned long long)total);
        for (size_t i = 0; i < d.n_items; i++) {
            if (i)
                putchar(',');
            item_json(&d, &d.items[i]);
        }
        printf("]}\n");
    } else {
        printf("A: %s\nB: %s\n", pa, pb);
        printf("units: %llu compared, %llu identical, %llu differing", (unsigned long long)compared,
               (unsigned long long)identical, (unsigned long long)(compared - identical));
        if (only_a || only_b)
            printf("; %llu only in A, %llu only in B", (unsigned long long)only_a, (unsigned long long)only_b);
        printf("\nnodes: %llu only in A, %llu only in B, %llu different class, %llu different list, "
               "%llu different quality or count\n",
               (unsigned long long)d.count[D_ONLY_A], (unsigned long long)d.count[D_ONLY_B],
               (unsigned long long)d.count[D_CLASS], (unsigned long long)d.count[D_LIST],
               (unsigned long long)d.count[D_DETAIL]);
        for (int pass = 0; pass < 2; pass++) {
            if (pass == 0 && header_diffs)
                printf("header: %d difference%s\n", header_diffs, header_diffs == 1 ? "" : "s");
            if (pass == 1 && notes)
                printf("notes (provenance: cannot change an image; --strict counts them):\n");
            for (int i = 0; i < d.n_fields; i++) {
                const diff_field *f = &d.fields[i];
                if (f->counted != (pass == 0))
                    continue;
                printf("  %s: ", f->name);
                inspect_text_string(stdout, f->a);
                printf(" vs ");
                inspect_text_string(stdout, f->b);
                putchar('\n');
            }
        }
        if (total) {
            if (d.n_items < total)
                printf("first %zu of %llu differences (--all shows every one):\n", d.n_items,
                       (unsigned long long)total);
            else
                printf("differences:\n");
            for (size_t i = 0; i < d.n_items; i++)
                item_text(&d, &d.items[i]);
        }
        printf("%s\n", same ? "same" : "different");
    }
    free(d.items);
    free(d.fields);
    inspect_unload(&la);
    inspect_unload(&lb);
    if (inspect_stdout_check())
        return 2;
    return same ? 0 : 1;
}
