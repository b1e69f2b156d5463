/* SPDX-License-Identifier: Apache-2.0 */
/* Reading YAML files with libyaml's document API, which keeps a line and
 * column for every node, so every error names FILE:LINE:COL and the key.
 * Shared by the edit-file and camera-path readers. */
#ifndef LIE_YAML_DOC_H
#define LIE_YAML_DOC_H

#include "core/core.h"

#include <yaml.h>

typedef struct lie_yaml {
    yaml_document_t doc;
    const char *name; /* the file, for messages */
    lie_error *err;
} lie_yaml;

/* Deepest nesting of sequences and mappings accepted (an edit file needs 4). */
#define LIE_YAML_MAX_DEPTH 64

/* Parse text into y->doc (exactly one document, nested at most
 * LIE_YAML_MAX_DEPTH deep); on a syntax error sets err at the problem's line
 * and column.  On success the caller frees with lie_yaml_free. */
lie_status lie_yaml_load(lie_yaml *y, const unsigned char *text, size_t size, const char *name, lie_error *err);
void lie_yaml_free(lie_yaml *y);

/* "KEY: WHAT" at node n's line and column; returns LIE_ERR_FORMAT. */
lie_status lie_yaml_error(lie_yaml *y, const yaml_node_t *n, const char *key, const char *what);
/* The node's text if it is a scalar, else NULL. */
const char *lie_yaml_scalar(const yaml_node_t *n);
/* A plain scalar that is a finite decimal number (no hex, inf or nan). */
lie_status lie_yaml_number(lie_yaml *y, const yaml_node_t *n, const char *key, double *out);
/* A sequence of exactly `count` such numbers. */
lie_status lie_yaml_numbers(lie_yaml *y, const yaml_node_t *n, const char *key, double *out, int count);

#endif
