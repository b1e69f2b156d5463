#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-inspect verify and summary on caches from lie-build: valid caches,
# scene checks, damaged and foreign files, stdin, the command-line contract.
. "$ROOT/tests/tools/lib.sh"

run "$B/lie-inspect" --help
expect_rc 0 "--help exits 0"
if grep -q -- 'verify' "$TMP/out" && grep -q -- 'summary' "$TMP/out"; then ok "--help goes to stdout"; else
    not_ok "--help output"; fi
run "$B/lie-inspect" --version
expect_rc 0 "--version exits 0"

run "$B/lie-build" "$S/cornell.gltf" --samples 8 --max-samples 16 --min-patch 0.01 -q -o "$TMP/c.lie"
expect_rc 0 "lie-build cornell (small settings)"
expect_file "$TMP/c.lie" "cache written"

# verify
run "$B/lie-inspect" verify "$TMP/c.lie"
expect_rc 0 "verify a fresh cache"
if [ "$(cat "$TMP/out")" = "$TMP/c.lie: valid" ]; then ok "verify prints 'CACHE: valid'"; else
    not_ok "verify output: $(cat "$TMP/out")"; fi
run "$B/lie-inspect" verify -q "$TMP/c.lie"
expect_rc 0 "verify -q"
if [ ! -s "$TMP/out" ] && [ ! -s "$TMP/err" ]; then ok "verify -q prints nothing"; else not_ok "verify -q printed"; fi
run "$B/lie-inspect" verify "$TMP/c.lie" --scene "$S/cornell.gltf"
expect_rc 0 "verify --scene with the scene it was built for"
run "$B/lie-inspect" verify "$TMP/c.lie" --scene "$S/museum1.gltf"
expect_rc 1 "verify --scene with another scene"
expect_one_error_line "lie-inspect: $TMP/c.lie: scene $S/museum1.gltf has content hash" "another scene: one line"
if grep -Eq '[0-9a-f]{16}.*[0-9a-f]{16}' "$TMP/err"; then ok "both hashes in hex"; else not_ok "hashes in message"; fi
run "$B/lie-inspect" verify "$TMP/c.lie" --scene "$TMP/no-such.gltf"
expect_rc 1 "verify --scene with a missing scene"
expect_one_error_line "lie-inspect: $TMP/no-such.gltf:" "missing scene: one line naming it"

# An edited cache (rst-update): verify --scene replays the edit log.
if [ -x "$B/rst-update" ]; then
    printf '%s\n' '- rotate: {node: TallBlock, axis: [0, 1, 0], degrees: -20}' >"$TMP/tall.yaml"
    run "$B/rst-update" "$TMP/c.lie" "$TMP/tall.yaml" -q -o "$TMP/e.lie"
    expect_rc 0 "rst-update cornell"
    run "$B/lie-inspect" verify "$TMP/e.lie" --scene "$S/cornell.gltf"
    expect_rc 0 "verify --scene on an edited cache (edit log replayed)"
    run "$B/lie-inspect" summary "$TMP/e.lie" --json
    if grep -q '"edits":\[{"name":"[^"]*tall.yaml","bytes":' "$TMP/out" && ! grep -q '"scene_hash":"\([0-9a-f]*\)","state_hash":"\1"' "$TMP/out"; then
        ok "summary of an edited cache: the edit, two hashes"; else not_ok "edited summary"; sed 's/^/# /' "$TMP/out"; fi
    run "$B/lie-inspect" verify "$TMP/e.lie" --scene "$S/museum1.gltf"
    expect_rc 1 "verify --scene on an edited cache with another scene"
fi

# stdin
"$B/lie-inspect" verify - <"$TMP/c.lie" >"$TMP/out" 2>"$TMP/err"; rc=$?
expect_rc 0 "verify - reads stdin"
if [ "$(cat "$TMP/out")" = "-: valid" ]; then ok "stdin named '-'"; else not_ok "stdin output: $(cat "$TMP/out")"; fi
"$B/lie-build" "$S/cornell.gltf" --samples 8 --max-samples 16 --min-patch 0.01 -q -o - 2>"$TMP/err" |
    "$B/lie-inspect" summary - >"$TMP/piped.txt" 2>>"$TMP/err"; rc=$?
expect_rc 0 "lie-build -o - | lie-inspect summary -"
"$B/lie-build" "$S/cornell.gltf" --samples 8 --max-samples 16 --min-patch 0.01 -q -o - >"$TMP/stdout.lie" 2>"$TMP/err"
expect_same "$TMP/stdout.lie" "$TMP/c.lie" "cache to stdout equals cache to file"

# summary
run "$B/lie-inspect" summary "$TMP/c.lie"
expect_rc 0 "summary"
if grep -q '^triangles  *36$' "$TMP/out" && grep -q '^units  *36$' "$TMP/out" && grep -q 'partial' "$TMP/out" &&
    grep -q 'NODES' "$TMP/out" && grep -q 'samples 8, max-samples 16' "$TMP/out" &&
    grep -q 'min-patch 0.01,' "$TMP/out" && grep -q "cornell.gltf" "$TMP/out"; then ok "summary holds counts, classes, sections, parameters"; else
    not_ok "summary content"; sed 's/^/# /' "$TMP/out"; fi
if [ ! -s "$TMP/err" ]; then ok "summary: nothing on stderr"; else not_ok "summary wrote to stderr"; fi
run "$B/lie-inspect" summary "$TMP/c.lie" --json
expect_rc 0 "summary --json"
if [ "$(wc -l <"$TMP/out")" -eq 1 ]; then ok "--json prints one line"; else not_ok "--json lines"; fi
if command -v python3 >/dev/null 2>&1; then
    if python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["triangles"] == 36 and d["units"] == 36 and d["emitters"] == 1
assert d["params"]["samples"] == 8 and d["params"]["max_samples"] == 16 and d["params"]["min_patch"] == 0.01
assert d["params"]["blockers"] == "sampled" and d["edits"] == []
assert sum(v["count"] for v in d["pairs"].values()) == d["leaves"]
assert sum(d["patches_per_depth"]) == d["nodes"]
assert sum(d["blocker_lists"]["histogram"].values()) == d["pairs"]["partial"]["count"]
assert [s["name"] for s in d["sections"]] == ["META", "PARAMS", "EDITS", "EMITTERS", "ROOTS", "NODES", "POOL"]
assert len(d["scene_hash"]) == 16 and d["scene_hash"] == d["state_hash"]
' "$TMP/out"; then ok "--json parses, keys consistent"; else not_ok "--json content"; fi
fi
if grep -q '^triangles  *36$' "$TMP/piped.txt"; then ok "summary of a piped cache"; else not_ok "piped summary"; fi

# Damaged and foreign files: exit 1, one line naming the file.
bad_cache() { # FILE WHAT [NEEDLE]
    run "$B/lie-inspect" verify "$1"
    expect_rc 1 "$2"
    expect_one_error_line "lie-inspect: $1: ${3:-}" "$2: one error line"
    run "$B/lie-inspect" summary "$1"
    expect_rc 1 "$2 (summary)"
}
size=$(wc -c <"$TMP/c.lie")
head -c $((size / 2)) "$TMP/c.lie" >"$TMP/trunc.lie"
bad_cache "$TMP/trunc.lie" "truncated cache" "truncated"
head -c $((size - 1)) "$TMP/c.lie" >"$TMP/trunc1.lie"
bad_cache "$TMP/trunc1.lie" "cache short by one byte" "truncated"
head -c 200 /dev/urandom >"$TMP/garbage.lie"
bad_cache "$TMP/garbage.lie" "garbage" "not a LIE cache"
: >"$TMP/empty.lie"
bad_cache "$TMP/empty.lie" "empty file"
bad_cache "$S/cornell.gltf" "a glTF file" "not a LIE cache"
bad_cache "$TMP/no-such.lie" "missing file" "cannot open"
# one byte flipped in the middle of the NODES section
cp "$TMP/c.lie" "$TMP/flip.lie"
printf '\377' | dd of="$TMP/flip.lie" bs=1 seek=$((size - 100)) conv=notrunc 2>/dev/null
bad_cache "$TMP/flip.lie" "a damaged byte" "file checksum mismatch"
"$B/lie-inspect" verify - <"$TMP/trunc.lie" >"$TMP/out" 2>"$TMP/err"; rc=$?
expect_rc 1 "truncated cache on stdin"
expect_one_error_line "lie-inspect: -: truncated" "stdin: one error line naming -"

# Usage errors: exit 2, one line, a hint to --help.
usage() { # WHAT ARGS...
    what=$1; shift
    run "$B/lie-inspect" "$@"
    expect_rc 2 "$what"
    if [ "$(wc -l <"$TMP/err")" -eq 1 ] && grep -q -- "--help" "$TMP/err"; then ok "$what: one line with a hint"; else
        not_ok "$what: usage message"; sed 's/^/# /' "$TMP/err"; fi
}
usage "no command"
usage "unknown command" frobnicate "$TMP/c.lie"
usage "verify without a cache" verify
usage "two caches" verify "$TMP/c.lie" "$TMP/c.lie"
usage "unknown flag" verify "$TMP/c.lie" --frobnicate
usage "--scene without a value" verify "$TMP/c.lie" --scene
usage "--json with verify" verify "$TMP/c.lie" --json
usage "--scene with summary" summary "$TMP/c.lie" --scene "$S/cornell.gltf"
finish
