#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-render on bad input: one line "lie-render: FILE: what is wrong", exit 1,
# no output file; usage errors exit 2.
. "$ROOT/tests/tools/lib.sh"
G="$D/gltf"

bad_input() { # FILE WHAT
    run "$B/lie-render" "$1" -q --size 8x8 --light-samples 1 -o "$TMP/out.exr"
    expect_rc 1 "$2"
    expect_one_error_line "lie-render: $1:" "$2: one error line naming the file"
    expect_no_file "$TMP/out.exr" "$2: no output written"
    expect_no_temp "$TMP" "$2: no temporary file left"
}

bad_input "$TMP/does-not-exist.gltf" "missing file"
bad_input "$G/bad_json.gltf" "invalid JSON"
size=$(wc -c <"$G/triangle.glb")
head -c $((size - 9)) "$G/triangle.glb" >"$TMP/truncated.glb"
bad_input "$TMP/truncated.glb" "truncated .glb"
bad_input "$G/missing_bin.gltf" "missing .bin"
bad_input "$G/accessor_oob.gltf" "accessor out of range"
bad_input "$G/index_oob.gltf" "index beyond the vertex count"
bad_input "$G/no_position.gltf" "primitive without positions"
: >"$TMP/empty.gltf"
bad_input "$TMP/empty.gltf" "empty file"

# Usage errors: exit 2, one line, a hint to --help.
usage() { # WHAT ARGS...
    what=$1; shift
    run "$B/lie-render" "$@"
    expect_rc 2 "$what"
    if [ "$(wc -l <"$TMP/err")" -eq 1 ] && grep -q -- "--help" "$TMP/err"; then ok "$what: one line with a hint"; else
        not_ok "$what: usage message"; sed 's/^/# /' "$TMP/err"; fi
}
usage "unknown flag" "$S/cornell.gltf" --frobnicate -o "$TMP/x.exr"
usage "bad --light-samples" "$S/cornell.gltf" --light-samples many -o "$TMP/x.exr"
usage "negative --spp" "$S/cornell.gltf" --spp -3 -o "$TMP/x.exr"
usage "bad --size" "$S/cornell.gltf" --size 10by10 -o "$TMP/x.exr"
usage "bad --visibility" "$S/cornell.gltf" --visibility some -o "$TMP/x.exr"
usage "bad --lie-skip" "$S/cornell.gltf" --lie-skip everything -o "$TMP/x.exr"
usage "bad --compression" "$S/cornell.gltf" --compression lzma -o "$TMP/x.exr"
usage "missing -o" "$S/cornell.gltf"
usage "missing input" -o "$TMP/x.exr"
usage "missing option value" "$S/cornell.gltf" -o
expect_no_file "$TMP/x.exr" "no output after usage errors"

# An unwritable output directory: exit 1, one line naming the output.
run "$B/lie-render" "$S/cornell.gltf" --size 8x8 --light-samples 1 -q -o "$TMP/no/such/dir/x.exr"
expect_rc 1 "unwritable output"
expect_one_error_line "lie-render: $TMP/no/such/dir/x.exr: " "unwritable output: one line"
# A full disk: exit 1, nothing left behind.
if [ -w /dev/full ]; then
    "$B/lie-render" "$S/cornell.gltf" --size 8x8 --light-samples 1 -q -o - >/dev/full 2>"$TMP/err"; rc=$?
    expect_rc 1 "stdout on a full disk"
fi
finish
