/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/edit. */
#ifndef LIE_EDIT_INTERNAL_H
#define LIE_EDIT_INTERNAL_H

#include "edit/edit.h"

/* Write n_ops operations as an edit file (lie_edit_write); name_for_errors
 * names it in messages. */
lie_status lie_edit_write_ops(const lie_edit_op *ops, int n_ops, const char *name_for_errors, unsigned char **text,
                              size_t *size, lie_error *err);

#endif
