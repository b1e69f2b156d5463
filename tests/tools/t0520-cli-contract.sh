#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# The command-line contract (CONTRIBUTING.md, Tools), for every tool in bin/:
# --help and -h to stdout with exit 0 and nothing on stderr, --version as
# "TOOL VERSION (commit C)" then the libraries it was built with, usage errors exit 2 with one line and a hint to --help,
# and no output file after a usage error.
. "$ROOT/tests/tools/lib.sh"

tools=""
for t in "$B"/*; do [ -x "$t" ] && tools="$tools $(basename "$t")"; done
case "$tools" in *lie-build*lie-inspect*lie-render*rst-update*) ok "all four tools present:$tools" ;;
*) not_ok "tools found:$tools" ;; esac

usage_err() { # TOOL WHAT ARGS...
    tool=$1; what=$2; shift 2
    run "$B/$tool" "$@"
    if [ "$rc" -eq 2 ] && [ "$(wc -l <"$TMP/err")" -eq 1 ] && grep -q "^$tool: .*--help" "$TMP/err" && [ ! -s "$TMP/out" ]; then
        ok "$tool: $what: exit 2, one line: $(cat "$TMP/err")"; else
        not_ok "$tool: $what: exit $rc"; sed 's/^/# /' "$TMP/err" | head -3; fi
}

for tool in $tools; do
    for h in --help -h; do
        run "$B/$tool" $h
        if [ "$rc" -eq 0 ] && [ ! -s "$TMP/err" ] && grep -q "^Usage: $tool " "$TMP/out" && grep -q -- '--version' "$TMP/out"; then
            ok "$tool $h: Usage (help2man's SYNOPSIS) on stdout, exit 0"; else not_ok "$tool $h: exit $rc"; fi
    done
    run "$B/$tool" --version
    if [ "$rc" -eq 0 ] && head -1 "$TMP/out" | grep -Eqx "$tool [0-9]+\.[0-9]+\.[0-9]+ \(commit [^ ]+\)" &&
        sed -n 2p "$TMP/out" | grep -q 'Embree [0-9].*OpenEXR [0-9]' && [ ! -s "$TMP/err" ]; then
        ok "$tool --version: $(cat "$TMP/out")"; else not_ok "$tool --version: exit $rc, '$(cat "$TMP/out")'"; fi
    # --help wins over everything after it, like git
    run "$B/$tool" --help --frobnicate
    expect_rc 0 "$tool --help before a bad flag"
    usage_err "$tool" "no arguments"
    usage_err "$tool" "an unknown long option" --frobnicate
    usage_err "$tool" "an unknown short option" -Z
done

# Tool-specific usage errors: missing values, bad numbers, extra arguments.
usage_err lie-build "missing -o" "$S/cornell.gltf"
usage_err lie-build "-o without a value" "$S/cornell.gltf" -o
usage_err lie-build "two scenes" "$S/cornell.gltf" "$S/cornell.gltf" -o "$TMP/x.lie"
usage_err lie-build "--samples 1e3" "$S/cornell.gltf" -o "$TMP/x.lie" --samples 1e3
usage_err lie-build "--max-blockers 99999999999" "$S/cornell.gltf" -o "$TMP/x.lie" --max-blockers 99999999999
usage_err lie-build "--stats=xml" "$S/cornell.gltf" -o "$TMP/x.lie" --stats=xml
usage_err rst-update "missing -o" "$S/cornell.gltf" "$TMP/e.yaml"
usage_err rst-update "no edit files" "$TMP/c.lie" -o "$TMP/x.lie"
usage_err rst-update "--threads -1" "$TMP/c.lie" "$TMP/e.yaml" -o "$TMP/x.lie" --threads -1
usage_err lie-render "--size 0x10" "$S/cornell.gltf" -o "$TMP/x.exr" --size 0x10
usage_err lie-render "--size 100000x10" "$S/cornell.gltf" -o "$TMP/x.exr" --size 100000x10
usage_err lie-render "--emitter -1" "$S/cornell.gltf" -o "$TMP/x.exr" --emitter -1
usage_err lie-render "--aov colour" "$S/cornell.gltf" -o "$TMP/x.exr" --aov colour
usage_err lie-render "--path and --camera" "$S/cornell.gltf" -o "$TMP/x_%d.exr" --path p.yaml --camera 0
usage_err lie-inspect "verify without a cache" verify
usage_err lie-inspect "dump with two caches" dump a.lie b.lie
usage_err lie-inspect "patch without a patch" patch a.lie
usage_err lie-inspect "--emitter with dump" dump a.lie --emitter 0
usage_err lie-inspect "--strict with verify" verify a.lie --strict
usage_err lie-inspect "image --emitter x" image a.lie -o "$TMP/x.png" --emitter x
expect_no_file "$TMP/x.lie" "no cache after usage errors"
expect_no_file "$TMP/x.exr" "no image after usage errors"
expect_no_file "$TMP/x.png" "no PNG after usage errors"
finish
