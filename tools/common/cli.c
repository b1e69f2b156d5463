/* SPDX-License-Identifier: Apache-2.0 */
/* Strict parsing of command-line values ("12x" or "" is an error, never 12
 * or 0) and the tools' messages (tools/common/cli.h). */
#include "common/cli.h"
#include "scene/scene.h"
#include "version/version.h"

#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int lie_parse_long(const char *s, long min, long max, long *out)
{
    if (!s || !*s)
        return 0;
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || *end || v < min || v > max)
        return 0;
    *out = v;
    return 1;
}

int lie_frame_pattern_ok(const char *s)
{
    int convs = 0;
    for (const char *p = s; *p; p++) {
        if (*p != '%')
            continue;
        if (p[1] == '%') {
            p++;
            continue;
        }
        p++;
        if (*p == '0')
            p++;
        int digits = 0;
        while (*p >= '0' && *p <= '9' && digits < 2) {
            p++;
            digits++;
        }
        if (*p != 'd')
            return 0;
        convs++;
    }
    return convs == 1;
}

int lie_parse_range(const char *s, long min, long max, long *a, long *b)
{
    const char *dash = s ? strchr(s, '-') : NULL;
    char first[32];
    if (!dash || dash == s || (size_t)(dash - s) >= sizeof first)
        return 0;
    memcpy(first, s, (size_t)(dash - s));
    first[dash - s] = 0;
    return lie_parse_long(first, min, max, a) && lie_parse_long(dash + 1, min, max, b) && *a <= *b;
}

int lie_parse_float(const char *s, float min, float max, float *out)
{
    if (!s || !*s)
        return 0;
    char *end;
    errno = 0;
    float v = strtof(s, &end);
    if (errno || *end || !isfinite(v) || v < min || v > max)
        return 0;
    *out = v;
    return 1;
}

int lie_parse_size(const char *s, int max, int *w, int *h)
{
    if (!s)
        return 0;
    char *end;
    errno = 0;
    long a = strtol(s, &end, 10);
    if (errno || end == s || (*end != 'x' && *end != 'X'))
        return 0;
    const char *p = end + 1;
    long b = strtol(p, &end, 10);
    if (errno || end == p || *end || a < 1 || b < 1 || a > max || b > max)
        return 0;
    *w = (int)a;
    *h = (int)b;
    return 1;
}

/* The length of the well-formed UTF-8 sequence at p (RFC 3629: no overlong forms, no
 * surrogates, nothing past U+10FFFF), or 0. */
static int utf8_len(const unsigned char *p)
{
    int n = p[0] < 0x80 ? 1 : p[0] >= 0xc2 && p[0] <= 0xdf ? 2 : p[0] >= 0xe0 && p[0] <= 0xef ? 3
                          : p[0] >= 0xf0 && p[0] <= 0xf4 ? 4 : 0;
    for (int i = 1; i < n; i++)
        if ((p[i] & 0xc0) != 0x80)
            return 0;
    if ((p[0] == 0xe0 && p[1] < 0xa0) || (p[0] == 0xed && p[1] > 0x9f) || (p[0] == 0xf0 && p[1] < 0x90) ||
        (p[0] == 0xf4 && p[1] > 0x8f))
        return 0;
    return n;
}

void lie_json_string(FILE *fp, const char *s)
{
    fputc('"', fp);
    for (const unsigned char *p = (const unsigned char *)s; *p;) {
        int n = utf8_len(p);
        if (n == 0)
            fprintf(fp, "\\udc%02x", *p++);
        else if (*p == '"' || *p == '\\')
            fprintf(fp, "\\%c", *p++);
        else if (*p < 0x20)
            fprintf(fp, "\\u%04x", *p++);
        else
            for (; n > 0; n--)
                fputc(*p++, fp);
    }
    fputc('"', fp);
}

FILE *lie_stats_json_begin(lie_stats_json *j, const char *tool, const char *input)
{
    j->buf = NULL;
    j->size = 0;
    j->fp = open_memstream(&j->buf, &j->size);
    if (!j->fp)
        return NULL;
    fprintf(j->fp, "{\"schema\":%d,\"tool\":", LIE_STATS_SCHEMA);
    lie_json_string(j->fp, tool);
    if (input) {
        fputs(",\"input\":", j->fp);
        lie_json_string(j->fp, input);
    }
    return j->fp;
}

lie_status lie_stats_json_end(const lie_cli *cli, lie_stats_json *j, lie_error *err)
{
    const char *name = cli->stats_file ? cli->stats_file : "--stats=json";
    int ok = j->fp && fclose(j->fp) == 0 && j->buf;
    j->fp = NULL;
    lie_status st = LIE_OK;
    if (!ok) {
        st = lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
    } else if (!cli->stats_file) {
        fwrite(j->buf, 1, j->size, stderr);
        fflush(stderr);
    } else { /* "-": lie_atomic_open's stdout */
        lie_atomic_file af;
        if ((st = lie_atomic_open(&af, cli->stats_file, err)) == LIE_OK) {
            if (fwrite(j->buf, 1, j->size, af.fp) != j->size) {
                lie_atomic_abort(&af);
                st = lie_error_set(err, LIE_ERR_IO, name, "cannot write");
            } else {
                st = lie_atomic_commit(&af, err);
            }
        }
    }
    free(j->buf);
    j->buf = NULL;
    return st;
}

int lie_parse_stats(const char *arg)
{
    if (!arg)
        return 1;
    return strcmp(arg, "json") == 0 ? 2 : 0;
}

/* Under mpirun every rank parses the same command line and meets the same
 * usage error: only rank 0 says it (Open MPI's OMPI_COMM_WORLD_RANK, or
 * PMIx's PMIX_RANK, set before MPI_Init), and every rank exits 2. */
static int first_rank(void)
{
    const char *r = getenv("OMPI_COMM_WORLD_RANK");
    if (!r)
        r = getenv("PMIX_RANK");
    return !r || strcmp(r, "0") == 0;
}

int lie_usage_error(const char *prog, const char *fmt, ...)
{
    if (!first_rank()) {
        /* mpirun kills the other ranks as soon as one exits non-zero: were
         * this rank to exit first, rank 0 could be killed before its line
         * is out.  Rank 0's exit ends this wait (mpirun's SIGTERM); the
         * timeout only bounds a run whose rank 0 met no usage error. */
        for (int i = 0; i < 100; i++)
            usleep(100000);
        return 2;
    }
    /* one write: under mpirun stderr is forwarded in chunks that other
     * output may otherwise split */
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    fprintf(stderr, "%s: %s (see --help)\n", prog, msg);
    return 2;
}

int lie_report_error(const char *prog, const lie_error *err, int code)
{
    char line[2200];
    lie_error_format(err, line, sizeof line);
    fprintf(stderr, "%s: %s\n", prog, line);
    return code;
}

double lie_phase(const char *prog, int verbose, const char *phase, double since)
{
    double now = lie_time_now();
    if (verbose)
        fprintf(stderr, "%s: %s: %.3f s\n", prog, phase, now - since);
    return now;
}

void lie_print_scene_warnings(const char *prog, const lie_scene *s, const char *fallback)
{
    int kept = s->n_warnings < LIE_SCENE_WARNINGS_MAX ? s->n_warnings : LIE_SCENE_WARNINGS_MAX;
    char file[1024], w[2048]; /* both may carry bytes of the file: escaped like errors */
    lie_escape_controls(file, sizeof file, s->path && s->path[0] ? s->path : fallback ? fallback : "");
    for (int i = 0; i < kept; i++) {
        lie_escape_controls(w, sizeof w, s->warnings[i]);
        fprintf(stderr, "%s: %s: warning: %s\n", prog, file, w);
    }
    if (s->n_warnings > kept)
        fprintf(stderr, "%s: %s: warning: %d more warnings\n", prog, file, s->n_warnings - kept);
}

/* A shared option: -1 to go on, else the exit status. */
static int shared_option(lie_cli *cli, int c, const char *arg, char *const argv[])
{
    long v;
    switch (c) {
    case LIE_OPT_EXTERNAL: cli->external = 1; return -1;
    case LIE_OPT_STATS:
        if (!(cli->stats = lie_parse_stats(arg)))
            return lie_usage_error(cli->tool, "--stats: expected --stats or --stats=json, got '%s'", arg);
        if (cli->stats_file && cli->stats != 2)
            return lie_usage_error(cli->tool, "%s", "--stats-file writes JSON: not with --stats (text)");
        return -1;
    case LIE_OPT_STATS_FILE:
        if (!arg[0])
            return lie_usage_error(cli->tool, "%s", "--stats-file: expected a file name");
        if (cli->stats == 1)
            return lie_usage_error(cli->tool, "%s", "--stats-file writes JSON: not with --stats (text)");
        cli->stats_file = arg;
        cli->stats = 2;
        return -1;
    case LIE_OPT_THREADS:
        if (!lie_cli_long(cli, 0, 4096, &v))
            return cli->status;
        cli->threads = (int)v;
        return -1;
    case 'o': cli->output = arg; return -1;
    case 'q': cli->quiet = 1; return -1;
    case 'v': cli->verbose = 1; return -1;
    case 'h': cli->usage(stdout); return 0;
    case LIE_OPT_VERSION: {
        char vr[512];
        lie_version_report(cli->tool, vr, sizeof vr);
        fputs(vr, stdout);
        return 0;
    }
    case ':': return lie_usage_error(cli->tool, "%s: missing value", argv[optind - 1]);
    default: return lie_usage_error(cli->tool, "unknown option '%s'", argv[optind - 1]);
    }
}

static int is_shared(const lie_cli *cli, int c)
{
    return c == LIE_OPT_EXTERNAL || c == LIE_OPT_STATS || c == LIE_OPT_STATS_FILE || c == LIE_OPT_VERSION || c == LIE_OPT_THREADS ||
           (c == 'o' && (cli->takes & LIE_CLI_OUTPUT)) || c == 'q' || c == 'v' || c == 'h' || c == ':' || c == '?';
}

/* The tool's table, then the shared options it takes, -q, -h, --version;
 * its short options, then the shared ones'.  0 when they do not fit (a
 * tool's table is fixed: tests/tools/t0520-cli-contract.sh runs them all). */
static int make_table(lie_cli *cli, const char *shortopts, const struct option *longopts)
{
    static const struct {
        unsigned bit;
        struct option opt;
        const char *shortopt;
    } shared[] = {
        {LIE_CLI_OUTPUT, {"output", required_argument, NULL, 'o'}, "o:"},
        {LIE_CLI_THREADS, {"threads", required_argument, NULL, LIE_OPT_THREADS}, ""},
        {LIE_CLI_EXTERNAL, {"allow-external-uris", no_argument, NULL, LIE_OPT_EXTERNAL}, ""},
        {LIE_CLI_STATS, {"stats", optional_argument, NULL, LIE_OPT_STATS}, ""},
        {LIE_CLI_STATS, {"stats-file", required_argument, NULL, LIE_OPT_STATS_FILE}, ""},
        {LIE_CLI_VERBOSE, {"verbose", no_argument, NULL, 'v'}, "v"},
        {0, {"quiet", no_argument, NULL, 'q'}, "q"},
        {0, {"help", no_argument, NULL, 'h'}, "h"},
        {0, {"version", no_argument, NULL, LIE_OPT_VERSION}, ""},
    };
    size_t n = 0, ns = 1 + strlen(shortopts);
    while (longopts[n].name)
        n++;
    if (n + sizeof shared / sizeof shared[0] + 1 > LIE_CLI_MAX_OPTIONS || ns + 8 > sizeof cli->shortopts)
        return 0;
    memcpy(cli->table, longopts, n * sizeof *longopts);
    snprintf(cli->shortopts, sizeof cli->shortopts, ":%s", shortopts);
    for (size_t i = 0; i < sizeof shared / sizeof shared[0]; i++)
        if (!shared[i].bit || (cli->takes & shared[i].bit)) {
            cli->table[n++] = shared[i].opt;
            strcat(cli->shortopts, shared[i].shortopt);
        }
    memset(&cli->table[n], 0, sizeof cli->table[n]);
    return 1;
}

int lie_cli_next(lie_cli *cli, int argc, char *const argv[], const char *shortopts, const struct option *longopts)
{
    if (!cli->table[0].name && !make_table(cli, shortopts, longopts)) {
        fprintf(stderr, "%s: too many options for tools/common/cli.c\n", cli->tool);
        cli->status = 2;
        return LIE_CLI_EXIT;
    }
    opterr = 0;
    int c;
    while ((c = getopt_long(argc, argv, cli->shortopts, cli->table, NULL)) != -1) {
        cli->name = NULL;
        for (const struct option *o = cli->table; o->name && !cli->name; o++)
            if (o->val == c)
                cli->name = o->name;
        if (!is_shared(cli, c))
            return c;
        if ((cli->status = shared_option(cli, c, optarg, argv)) >= 0)
            return LIE_CLI_EXIT;
    }
    if (cli->missing) {
        cli->status = 2;
        if (optind >= argc)
            return lie_usage_error(cli->tool, "%s", cli->missing), LIE_CLI_EXIT;
        if (optind + 1 < argc)
            return lie_usage_error(cli->tool, "unexpected argument '%s'", argv[optind + 1]), LIE_CLI_EXIT;
        cli->operand = argv[optind];
    }
    return -1;
}

int lie_cli_long(lie_cli *cli, long min, long max, long *out)
{
    if (lie_parse_long(optarg, min, max, out))
        return 1;
    cli->status = lie_usage_error(cli->tool, "--%s: expected an integer in %ld..%ld, got '%s'", cli->name, min, max,
                                  optarg);
    return 0;
}

int lie_cli_set_int(lie_cli *cli, int c, const lie_cli_int *table, size_t n, void *base)
{
    long v;
    for (size_t i = 0; i < n; i++)
        if (table[i].code == c) {
            if (!lie_cli_long(cli, table[i].min, table[i].max, &v))
                return -1;
            uint32_t u = (uint32_t)v; /* an int's bits too, as v >= 0 */
            memcpy((char *)base + table[i].offset, &u, sizeof u);
            return 1;
        }
    return 0;
}

int lie_cli_pick(lie_cli *cli, const lie_cli_choice *choices, int *out)
{
    char names[256] = "";
    size_t n = 0;
    while (choices[n].name)
        n++;
    for (size_t i = 0; i < n; i++) {
        if (strcmp(optarg, choices[i].name) == 0) {
            *out = choices[i].value;
            return 1;
        }
        size_t len = strlen(names);
        snprintf(names + len, sizeof names - len, "%s%s", i == 0 ? "" : i + 1 < n ? ", " : " or ", choices[i].name);
    }
    cli->status = lie_usage_error(cli->tool, "--%s: expected %s, got '%s'", cli->name, names, optarg);
    return 0;
}
