#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# make test-valgrind: the tools under valgrind's memcheck, release builds
# (bin/), on small settings: the pipeline lie-build | rst-update | lie-render
# through pipes, then each tool on its own (files, lie-inspect's commands,
# error paths).  Every run must exit as it does natively with no memcheck
# error and no definite or indirect leak.  Slow (minutes), so it is not part
# of `make test`, whose ASan + UBSan run covers the same ground faster.
set -u
: "${BINDIR:=bin}"
B=$(cd "$BINDIR" && pwd)
ROOT=$(pwd)
S="$ROOT/tests/scenes"
command -v valgrind >/dev/null 2>&1 || { echo "test-valgrind: valgrind not found (make deps)" >&2; exit 2; }
TMP=$(mktemp -d "${TMPDIR:-/tmp}/lie-valgrind.XXXXXX")
trap 'rm -rf "$TMP"' EXIT
VG="valgrind -q --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=definite,indirect
    --show-leak-kinds=definite,indirect --track-origins=yes --suppressions=$ROOT/tests/valgrind.supp"
n=0
failures=0
ok() { n=$((n + 1)); echo "ok $n - $1"; }
not_ok() { n=$((n + 1)); failures=$((failures + 1)); echo "not ok $n - $1"; }

# vg WHAT EXPECTED-EXIT CMD...: run CMD under memcheck
vg() {
    what=$1; want=$2; shift 2
    # shellcheck disable=SC2086
    $VG --log-file="$TMP/vg.log" "$@" >"$TMP/out" 2>"$TMP/err"
    rc=$?
    if [ "$rc" -eq "$want" ] && [ ! -s "$TMP/vg.log" ]; then ok "$what (exit $rc, memcheck clean)"; else
        not_ok "$what: exit $rc (expected $want)"; sed 's/^/# /' "$TMP/vg.log" "$TMP/err" | head -40; fi
}

SMALL="--samples 8 --max-samples 16 --min-patch 0.05 -q --threads 2"
printf '%s\n' '- rotate: {node: TallBlock, axis: [0, 1, 0], degrees: -20}' '- set-emission: {node: Light, strength: 9}' >"$TMP/edit.yaml"

# The pipeline, each stage under memcheck, statuses collected from the pipe.
# shellcheck disable=SC2086
{ $VG --log-file="$TMP/vg1.log" "$B/lie-build" "$S/cornell.gltf" $SMALL -o - 2>"$TMP/e1"; echo $? >"$TMP/s1"; } |
    { $VG --log-file="$TMP/vg2.log" "$B/rst-update" - "$TMP/edit.yaml" -q --threads 2 -o - 2>"$TMP/e2"; echo $? >"$TMP/s2"; } |
    { $VG --log-file="$TMP/vg3.log" "$B/lie-render" - -q --threads 2 --size 48x48 --light-samples 8 --aov complexity -o "$TMP/pipe.exr" 2>"$TMP/e3"; echo $? >"$TMP/s3"; }
stage=1
for what in "lie-build -o -" "rst-update - -o -" "lie-render -"; do
    rc=$(cat "$TMP/s$stage")
    if [ "$rc" -eq 0 ] && [ ! -s "$TMP/vg$stage.log" ]; then ok "pipeline: $what (memcheck clean)"; else
        not_ok "pipeline: $what: exit $rc"; sed 's/^/# /' "$TMP/vg$stage.log" "$TMP/e$stage" | head -40; fi
    stage=$((stage + 1))
done
if [ -s "$TMP/pipe.exr" ]; then ok "pipeline: image written"; else not_ok "pipeline: no image"; fi

# Each tool on files, and the other commands.
# shellcheck disable=SC2086
vg "lie-build museum1" 0 "$B/lie-build" "$S/museum1.gltf" $SMALL --min-patch 0.2 -o "$TMP/m1.lie"
# shellcheck disable=SC2086
vg "lie-build cornell, conservative" 0 "$B/lie-build" "$S/cornell.gltf" $SMALL --blockers conservative -o "$TMP/c.lie"
vg "rst-update" 0 "$B/rst-update" "$TMP/c.lie" "$TMP/edit.yaml" -q --threads 2 -o "$TMP/e.lie"
vg "lie-render, LIE visibility" 0 "$B/lie-render" "$TMP/m1.lie" -q --threads 2 --size 40x40 --light-samples 4 -o "$TMP/m1.png"
vg "lie-render, full visibility, AOVs" 0 "$B/lie-render" "$S/museum2.gltf" -q --threads 2 --size 32x32 --light-samples 4 \
    --aov albedo,normal,depth -o "$TMP/m2.exr"
vg "lie-inspect verify --scene" 0 "$B/lie-inspect" verify "$TMP/e.lie" --scene "$S/cornell.gltf"
vg "lie-inspect summary --json" 0 "$B/lie-inspect" summary --json "$TMP/m1.lie"
vg "lie-inspect dump" 0 "$B/lie-inspect" dump "$TMP/e.lie"
vg "lie-inspect patch" 0 "$B/lie-inspect" patch "$TMP/e.lie" 5/0 --json
vg "lie-inspect diff (different)" 1 "$B/lie-inspect" diff --all "$TMP/c.lie" "$TMP/e.lie"
vg "lie-inspect image" 0 "$B/lie-inspect" image "$TMP/e.lie" -q --threads 2 --size 32x32 -o "$TMP/fig10.png"

# Error paths free what they allocated too.
head -c 300 "$TMP/c.lie" >"$TMP/trunc.lie"
vg "lie-render: truncated cache" 1 "$B/lie-render" "$TMP/trunc.lie" -q -o "$TMP/x.exr"
printf '%s\n' '- move: {node: NoSuchNode, by: [1, 0, 0]}' >"$TMP/bad.yaml"
vg "rst-update: an edit naming no node" 1 "$B/rst-update" "$TMP/c.lie" "$TMP/bad.yaml" -q -o "$TMP/x.lie"
vg "lie-build: a glTF with an out-of-range index" 1 "$B/lie-build" "$ROOT/tests/data/gltf/index_oob.gltf" -q -o "$TMP/x.lie"
vg "lie-inspect diff: damaged B" 2 "$B/lie-inspect" diff "$TMP/c.lie" "$TMP/trunc.lie"

echo "valgrind: $((n - failures)) passed, $failures failed"
[ "$failures" -eq 0 ]
