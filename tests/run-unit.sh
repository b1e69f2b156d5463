#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Run every cmocka unit-test binary given; print a summary line.
pass=0; fail=0; failed=""
for t in "$@"; do
    if "$t"; then pass=$((pass + 1)); else fail=$((fail + 1)); failed="$failed $t"; fi
done
echo "unit: $pass passed, $fail failed"
[ -n "$failed" ] && echo "unit: failed:$failed"
[ "$fail" -eq 0 ]
