#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Run the tool tests under tests/tools (t[0-9]*.sh), git t/ style: each
# prints "ok N - ..." or "not ok N - ..." lines and exits non-zero on failure.
# Scripts run JOBS at a time (default: the number of cores); their reports
# are printed in order.  BINDIR names where the binaries are (bin/ or
# build/asan/bin/), HELPERS where the test helpers are.
: "${BINDIR:=bin}"
: "${HELPERS:=build/release/tests}"
: "${JOBS:=$(nproc 2>/dev/null || echo 2)}"
BINDIR_ABS=$(cd "$BINDIR" && pwd)
HELPERS_ABS=$(cd "$HELPERS" 2>/dev/null && pwd)
ROOT=$(pwd)
export BINDIR BINDIR_ABS HELPERS_ABS ROOT
OUTS=$(mktemp -d "${TMPDIR:-/tmp}/lie-tools.XXXXXX")
trap 'rm -rf "$OUTS"' EXIT

SCRIPTS=$(ls tests/tools/t[0-9]*.sh)

# run the scripts, JOBS at a time; each leaves NAME.out and NAME.rc
running=0
for t in $SCRIPTS; do
    name=$(basename "$t" .sh)
    ( sh "$t" >"$OUTS/$name.out" 2>&1; echo $? >"$OUTS/$name.rc" ) &
    running=$((running + 1))
    if [ "$running" -ge "$JOBS" ]; then
        wait
        running=0
    fi
done
wait

pass=0; fail=0; failed=""
for t in $SCRIPTS; do
    name=$(basename "$t" .sh)
    out="$OUTS/$name.out"
    rc=$(cat "$OUTS/$name.rc" 2>/dev/null || echo 1)
    p=$(grep -c '^ok ' "$out")
    f=$(grep -c '^not ok ' "$out")
    pass=$((pass + p)); fail=$((fail + f))
    if [ "$rc" -ne 0 ] || [ "$f" -ne 0 ]; then
        [ "$f" -eq 0 ] && fail=$((fail + 1))
        failed="$failed $t"
        sed "s|^|$t: |" "$out"
    else
        echo "$t: $p ok"
    fi
done
echo "tools: $pass passed, $fail failed"
[ -z "$failed" ]
