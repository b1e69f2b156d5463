/* SPDX-License-Identifier: Apache-2.0 */
/* lie-inspect: output helpers, loading, tree walks. */
#include "inspect.h"

#include <stdlib.h>
#include <string.h>

const char *const inspect_prog = "lie-inspect";

int inspect_fail(const lie_error *err, int code) { return lie_report_error(inspect_prog, err, code); }

int inspect_stdout_check(void)
{
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "%s: -: write failed\n", inspect_prog);
        return 1;
    }
    return 0;
}

void inspect_json_string(FILE *fp, const char *s)
{
    const unsigned char *p = (const unsigned char *)s;
    fputc('"', fp);
    while (*p) {
        unsigned char b = *p;
        if (b == '"' || b == '\\') {
            fprintf(fp, "\\%c", b);
            p++;
        } else if (b < 0x20 || b == 0x7f) {
            fprintf(fp, "\\u%04x", b);
            p++;
        } else if (b < 0x80) {
            fputc(b, fp);
            p++;
        } else {
            int n = b >= 0xf0 && b <= 0xf4 ? 3 : b >= 0xe0 ? 2 : b >= 0xc2 && b < 0xe0 ? 1 : -1;
            uint32_t cp = n == 3 ? b & 0x07u : n == 2 ? b & 0x0fu : b & 0x1fu;
            int ok = n > 0 && b < 0xf5;
            for (int k = 1; ok && k <= n; k++) {
                if ((p[k] & 0xc0) != 0x80)
                    ok = 0;
                else
                    cp = (cp << 6) | (p[k] & 0x3fu);
            }
            /* no overlong forms, surrogates or code points past U+10FFFF */
            if (ok && ((n == 2 && (cp < 0x800 || (cp >= 0xd800 && cp <= 0xdfff))) ||
                       (n == 3 && (cp < 0x10000 || cp > 0x10ffff))))
                ok = 0;
            if (ok) {
                fwrite(p, 1, (size_t)n + 1, fp);
                p += n + 1;
            } else {
                fputs("\\ufffd", fp);
                p++;
            }
        }
    }
    fputc('"', fp);
}

void inspect_text_string(FILE *fp, const char *s)
{
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '\\')
            fputs("\\\\", fp);
        else if (*p < 0x20 || *p == 0x7f)
            fprintf(fp, "\\x%02x", *p);
        else
            fputc(*p, fp);
    }
}

void inspect_fmt_float(float f, char *buf, size_t size)
{
    for (int prec = 6; prec < 9; prec++) {
        snprintf(buf, size, "%.*g", prec, (double)f);
        if (strtof(buf, NULL) == f)
            return;
    }
    snprintf(buf, size, "%.9g", (double)f);
}

const char *inspect_emitter_type_name(uint32_t t)
{
    return lie_emitter_type_name((lie_emitter_type)t);
}

const char *inspect_mode_name(lie_blocker_mode m)
{
    return m == LIE_BLOCKERS_CONSERVATIVE ? "conservative" : "sampled";
}

lie_status inspect_load(const char *path, inspect_cache *l, lie_error *err)
{
    memset(l, 0, sizeof *l);
    lie_status st = lie_read_file(path, &l->data, &l->size, err);
    if (st == LIE_OK)
        st = lie_cache_decode(l->data, l->size, path, &l->cache, err);
    return st;
}

void inspect_unload(inspect_cache *l)
{
    lie_cache_destroy(l->cache);
    free(l->data);
    memset(l, 0, sizeof *l);
}

int inspect_path_cmp(lie_patch_path a, lie_patch_path b)
{
    int n = a.depth < b.depth ? a.depth : b.depth;
    for (int l = 0; l < n; l++) {
        int da = lie_patch_digit(a, l), db = lie_patch_digit(b, l);
        if (da != db)
            return da < db ? -1 : 1;
    }
    return (a.depth > b.depth) - (a.depth < b.depth);
}

/* Depth is at most LIE_PATCH_MAX_DEPTH: the decoder checked it. */
void inspect_walk(const lie_env *env, uint32_t node, uint32_t tri, int e, lie_patch_path path, inspect_node_fn fn,
                  void *ctx)
{
    fn(ctx, tri, e, path, node);
    const lie_pnode *n = &env->nodes[node];
    if (n->child)
        for (int d = 0; d < 4; d++)
            inspect_walk(env, n->child + (uint32_t)d, tri, e, lie_patch_child(path, d), fn, ctx);
}

void inspect_print_node(FILE *fp, const lie_env *env, const lie_pnode *n)
{
    fprintf(fp, "%s %u %u", lie_class_name((lie_class)n->cls), n->quality, n->count);
    if (n->cls == LIE_CLASS_PARTIAL && !n->child) {
        fputs(" :", fp);
        for (uint32_t k = 0; k < n->count; k++)
            fprintf(fp, " %u", env->pool[n->list + k]);
    }
}

void inspect_json_node(FILE *fp, const lie_env *env, const lie_pnode *n)
{
    fprintf(fp, "\"class\":\"%s\",\"quality\":%u,\"count\":%u", lie_class_name((lie_class)n->cls), n->quality,
            n->count);
    if (n->cls == LIE_CLASS_PARTIAL && !n->child) {
        fputs(",\"blockers\":[", fp);
        for (uint32_t k = 0; k < n->count; k++)
            fprintf(fp, "%s%u", k ? "," : "", env->pool[n->list + k]);
        fputc(']', fp);
    }
}
