/* SPDX-License-Identifier: Apache-2.0 */
/* tools/common: what every tool's main shares and the library must not do
 * (it never prints): strict parsing of command-line values and the one-line
 * messages of the tool contract (CONTRIBUTING.md).  Linked into every tool
 * and test helper, not built as a tool (Makefile). */
#ifndef LIE_TOOLS_CLI_H
#define LIE_TOOLS_CLI_H

#include "core/core.h"

#include <getopt.h>
#include <stdio.h>

/* ---- command-line values (shared by the tools) ------------------------ */

/* Strict parses: the whole string must be the number, within [min, max]. */
int lie_parse_long(const char *s, long min, long max, long *out);
int lie_parse_float(const char *s, float min, float max, float *out);
/* A printf pattern with exactly one integer conversion: %d, %5d, %05d (frame names). */
int lie_frame_pattern_ok(const char *s);
/* "A-B" with min <= A <= B <= max (frame ranges). */
int lie_parse_range(const char *s, long min, long max, long *a, long *b);
/* Write s as a JSON string literal (with quotes) to fp, valid UTF-8 whatever s holds: a
 * byte that is not part of a well-formed UTF-8 sequence (a path in another encoding, say)
 * is written as the escape \udcXX of byte XX, the lone low surrogate of Python's
 * surrogateescape (PEP 383), so a reader can recover the bytes; the output is ASCII. */
void lie_json_string(FILE *fp, const char *s);

/* "WxH" with both in [1, max]. */
int lie_parse_size(const char *s, int max, int *w, int *h);
/* The value of --stats (arg NULL: 1) or --stats=json (2); 0 for another. */
int lie_parse_stats(const char *arg);

/* ---- the options every tool shares (design/CLI.md) -------------------- */

/* The options a tool may share with others, besides -q, -h and --version
 * that every tool takes: its lie_cli.takes names them, lie_cli_next adds
 * them to the tool's table and handles them. */
enum {
    LIE_CLI_EXTERNAL = 1, /* --allow-external-uris */
    LIE_CLI_STATS = 2,    /* --stats[=json], --stats-file FILE */
    LIE_CLI_VERBOSE = 4,  /* -v, --verbose */
    LIE_CLI_THREADS = 8,  /* --threads N, 0..4096 (0: all cores) */
    LIE_CLI_OUTPUT = 16,  /* -o, --output FILE */
};
/* getopt_long codes of the shared long options, above any tool's own. */
enum { LIE_OPT_EXTERNAL = 0x1000, LIE_OPT_STATS, LIE_OPT_VERSION, LIE_OPT_THREADS, LIE_OPT_STATS_FILE };
#define LIE_CLI_MAX_OPTIONS 64

/* A tool's command line: what it says about itself, and what the shared
 * options set. */
typedef struct lie_cli {
    const char *tool;        /* its name, first in every message */
    void (*usage)(FILE *fp); /* the tool's --help text */
    const char *missing;     /* a tool of one operand: the message when it is missing, and
                              * lie_cli_next checks there is exactly one (operand); NULL: the
                              * tool checks its operands itself */
    unsigned takes;          /* LIE_CLI_* bits: the shared options it takes */
    const char *operand;     /* that operand */
    int quiet;               /* -q */
    int verbose;             /* -v */
    int stats;               /* --stats: 1, --stats=json: 2 (also set by --stats-file) */
    const char *stats_file;  /* --stats-file: the JSON record goes there, not to stderr */
    int external;            /* --allow-external-uris */
    int threads;             /* --threads */
    const char *output;      /* -o */
    int status;              /* after LIE_CLI_EXIT or a failed lie_cli_long/choice: the exit status */
    /* lie_cli_next's own: the option being handled, the whole table */
    const char *name;
    struct option table[LIE_CLI_MAX_OPTIONS];
    char shortopts[32];
} lie_cli;
#define LIE_CLI_EXIT (-2)
/* getopt_long over the tool's table (its own options, ended by a NULL
 * name; shortopts: its own short options, e.g. "s:") and the shared ones it
 * takes, handling the shared options, getopt's errors and (with `missing`)
 * the operand: returns the next option of the tool's own, -1 at the end, or
 * LIE_CLI_EXIT when the tool must exit with cli->status: 0 after --help or
 * --version (printed to stdout), 2 after a usage error (its one line
 * printed). */
int lie_cli_next(lie_cli *cli, int argc, char *const argv[], const char *shortopts, const struct option *longopts);

/* The value of the option lie_cli_next just returned (optarg), parsed
 * strictly.  On a bad value the usage error "--NAME: expected ..., got
 * 'VALUE'" is printed, cli->status is 2 and 0 is returned. */
/* An integer in [min, max]. */
int lie_cli_long(lie_cli *cli, long min, long max, long *out);
/* An integer option that sets a 32-bit field (int or uint32_t, values >= 0)
 * of an options struct: the option, its range, the field's offset. */
typedef struct lie_cli_int {
    int code;
    long min, max;
    size_t offset;
} lie_cli_int;
/* When option c is one of the n of `table`: its value stored in its field
 * of *base (1), or its usage error (-1); 0 when c is not one of them. */
int lie_cli_set_int(lie_cli *cli, int c, const lie_cli_int *table, size_t n, void *base);
/* One of the names of `choices` (ended by a NULL name): its value. */
typedef struct lie_cli_choice {
    const char *name;
    int value;
} lie_cli_choice;
int lie_cli_pick(lie_cli *cli, const lie_cli_choice *choices, int *out);

/* ---- --stats=json ------------------------------------------------------ */

/* The version of the JSON records of --stats=json (every tool's "schema"): raised when a
 * member changes meaning or goes away; new members do not raise it. */
#define LIE_STATS_SCHEMA 1
/* A record is written into memory (NULL: out of memory) that starts
 * `{"schema":1,"tool":TOOL,"input":INPUT` (no input when NULL), the tool adds its members
 * (each after a comma) and the closing brace, and lie_stats_json_end writes it in one
 * piece: to stderr as one line no warning can split, or with --stats-file to that file
 * (atomically; "-" is stdout), or fails with err set (the file could not be written). */
typedef struct lie_stats_json {
    FILE *fp; /* where the tool prints its members (NULL: out of memory) */
    char *buf;
    size_t size;
} lie_stats_json;
FILE *lie_stats_json_begin(lie_stats_json *j, const char *tool, const char *input);
lie_status lie_stats_json_end(const lie_cli *cli, lie_stats_json *j, lie_error *err);

/* ---- tool messages: one line on stderr (CONTRIBUTING.md) -------------- */

/* "PROG: message (see --help)"; returns 2, the usage-error exit status.
 * Under mpirun only rank 0 prints it. */
int lie_usage_error(const char *prog, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* -v: one line per phase on stderr, "prog: phase: 1.234 s", when verbose;
 * returns lie_time_now() so phases chain: t = lie_phase(prog, v, "load", t). */
double lie_phase(const char *prog, int verbose, const char *phase, double since);
/* The scene's warnings (lie_scene.warnings), one "PROG: FILE: warning: ..."
 * line each, FILE the glTF (or `fallback` when the scene has no path). */
struct lie_scene;
void lie_print_scene_warnings(const char *prog, const struct lie_scene *s, const char *fallback);
/* "PROG: FILE: what is wrong" from err; returns `code`. */
int lie_report_error(const char *prog, const lie_error *err, int code);

#endif
