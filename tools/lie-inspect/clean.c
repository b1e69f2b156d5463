/* SPDX-License-Identifier: Apache-2.0 */
/* lie-inspect clean DIR: remove stale temporaries of the tools' own naming
 * (lie_tmp_clean in lib/core does the work), one line per file. */
#include "inspect.h"

typedef struct clean_ctx {
    const char *dir;
    const inspect_options *o;
} clean_ctx;

static void report(void *ctx, const char *name, uint64_t bytes)
{
    const clean_ctx *c = ctx;
    if (c->o->quiet)
        return;
    fputs(c->o->dry_run ? "would remove " : "removed ", stdout);
    inspect_text_string(stdout, c->dir);
    fputc('/', stdout);
    inspect_text_string(stdout, name);
    printf(" (%llu bytes)\n", (unsigned long long)bytes);
}

int inspect_clean(const char *dir, const inspect_options *o)
{
    lie_error err;
    lie_error_clear(&err);
    clean_ctx c = {dir, o};
    if (lie_tmp_clean(dir, o->min_age, o->dry_run, report, &c, &err) != LIE_OK)
        return inspect_fail(&err, 1);
    return inspect_stdout_check();
}
