#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-inspect dump, patch, diff and image: the canonical text is stable and
# sorted, diff compares content by identity (provenance is a note), patch
# shows one patch's trees, image equals lie-render's complexity layer.
. "$ROOT/tests/tools/lib.sh"
I="$B/lie-inspect"
SMALL="--samples 8 --max-samples 16 --min-patch 0.01 -q --split-gain 0"

# shellcheck disable=SC2086
"$B/lie-build" "$S/cornell.gltf" $SMALL -o "$TMP/a.lie" --threads 1 || not_ok "build cornell"
# shellcheck disable=SC2086
"$B/lie-build" "$S/cornell.gltf" $SMALL -o "$TMP/a2.lie" --threads 2 || not_ok "build cornell again"
# shellcheck disable=SC2086
"$B/lie-build" "$S/cornell.gltf" $SMALL --max-samples 32 -o "$TMP/b.lie" || not_ok "build with other parameters"

# ---- dump
run "$I" dump "$TMP/a.lie"
expect_rc 0 "dump"
cp "$TMP/out" "$TMP/a.dump"
if [ ! -s "$TMP/err" ]; then ok "dump: nothing on stderr"; else not_ok "dump wrote to stderr"; fi
"$I" dump "$TMP/a2.lie" >"$TMP/a2.dump"
expect_same "$TMP/a.dump" "$TMP/a2.dump" "dumps of caches built with 1 and 2 threads are identical"
"$I" dump - <"$TMP/a.lie" >"$TMP/stdin.dump"
expect_same "$TMP/a.dump" "$TMP/stdin.dump" "dump of stdin = dump of the file (the cache's name is not in the dump)"
if head -1 "$TMP/a.dump" | grep -qx 'lie-inspect-dump 1' && grep -qx 'format-version 7' "$TMP/a.dump" &&
    grep -qx "scene-path $S/cornell.gltf" "$TMP/a.dump" && grep -Eqx 'scene-hash [0-9a-f]{16}' "$TMP/a.dump" &&
    grep -qx 'param samples 8' "$TMP/a.dump" && grep -qx 'param min-patch 0.00999999978' "$TMP/a.dump" &&
    grep -qx 'param whole-pixels 262144' "$TMP/a.dump" && grep -qx 'edits 0' "$TMP/a.dump" && grep -Eqx 'emitter 0 area node [0-9]+ first-tri [0-9]+ tris 2' "$TMP/a.dump"; then
    ok "dump header: version, scene, hashes, parameters (%.9g), edits, emitters"; else not_ok "dump header"; head -20 "$TMP/a.dump" | sed 's/^/# /'; fi
nodes=$(sed -n 's/^nodes //p' "$TMP/a.dump")
lines=$(grep -Ec '^[0-9]+(/[0-3]+)? [0-9]+ [a-z]+ ' "$TMP/a.dump")
if [ -n "$nodes" ] && [ "$nodes" -eq "$lines" ] && [ "$lines" -gt 36 ]; then ok "one line per node ($lines)"; else
    not_ok "node lines: header says '$nodes', found $lines"; fi
# sorted by triangle, then path as a string, then emitter
grep -E '^[0-9]+(/[0-3]+)? ' "$TMP/a.dump" | awk '{ split($1, p, "/"); printf "%010d %s %05d\n", p[1], (p[2] == "" ? "" : "/" p[2]), $2 }' >"$TMP/keys"
if LC_ALL=C sort -c "$TMP/keys" 2>/dev/null; then ok "node lines sorted by triangle, patch, emitter"; else not_ok "dump order"; fi
if grep -Eq '^[0-9]+(/[0-3]+)? 0 partial [0-9]+ [0-9]+ : [0-9]' "$TMP/a.dump" && grep -Eq '^[0-9]+(/[0-3]+)? 0 split ' "$TMP/a.dump"; then
    ok "partial leaves carry their lists, split nodes are marked"; else not_ok "dump node lines"; fi
bad=$(awk '$3 == "partial" { if ($6 != ":" || NF != 6 + $5) print }' "$TMP/a.dump" | head -3)
if [ -z "$bad" ]; then ok "every partial list has COUNT entries"; else not_ok "partial lists: $bad"; fi
"$I" dump "$TMP/b.lie" >"$TMP/b.dump"
if ! cmp -s "$TMP/a.dump" "$TMP/b.dump" && diff "$TMP/a.dump" "$TMP/b.dump" | grep -q '^> param max-samples 32$'; then
    ok "diff(1) of two dumps shows the parameter that changed"; else not_ok "dump diff"; fi
run "$I" dump "$TMP/a.lie" --json
expect_rc 0 "dump --json"
if command -v python3 >/dev/null 2>&1; then
    if python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["dump_version"] == 1 and d["triangles"] == 36 and d["emitters"] == 1
assert d["params"]["samples"] == 8 and d["params"]["blockers"] == "sampled"
assert len(d["pairs"]) == d["nodes"] == int(sys.argv[2])
assert all(p["count"] == len(p["blockers"]) for p in d["pairs"] if "blockers" in p)
' "$TMP/out" "$nodes"; then ok "dump --json parses, one pair per node"; else not_ok "dump --json content"; fi
fi

# ---- patch
leaf=$(awk '$3 == "partial" && $1 ~ /\// { print $1; exit }' "$TMP/a.dump")
split=$(awk '$3 == "split" && $1 ~ /\// { print $1; exit }' "$TMP/a.dump")
run "$I" patch "$TMP/a.lie" "$leaf"
expect_rc 0 "patch $leaf (a leaf)"
if grep -q "^emitter 0 (area, node [0-9]*): the leaf at $leaf\$" "$TMP/out" && grep -q "^  $leaf partial " "$TMP/out"; then
    ok "patch: the leaf and its list"; else not_ok "patch leaf output"; sed 's/^/# /' "$TMP/out"; fi
run "$I" patch "$TMP/a.lie" "${leaf}0"
expect_rc 0 "patch below a leaf"
if grep -q "leaf $leaf covers ${leaf}0" "$TMP/out"; then ok "patch below a leaf: the covering leaf"; else
    not_ok "covering leaf"; sed 's/^/# /' "$TMP/out"; fi
run "$I" patch "$TMP/a.lie" "$split"
if grep -q "the subtree at $split" "$TMP/out" && grep -q "^    ${split}0 " "$TMP/out" && grep -q "^    ${split}3 " "$TMP/out"; then
    ok "patch of a split node: its subtree, indented"; else not_ok "patch subtree"; sed 's/^/# /' "$TMP/out"; fi
run "$I" patch "$TMP/a.lie" "$split" --json
expect_rc 0 "patch --json"
if command -v python3 >/dev/null 2>&1; then
    if python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
e = d["emitters"][0]
assert d["patch"] == sys.argv[2] and e["match"] == "node" and e["tree"]["class"] == "split"
assert [c["patch"] for c in e["tree"]["children"]] == [sys.argv[2] + str(k) for k in range(4)]
' "$TMP/out" "$split"; then ok "patch --json: the tree with its children"; else not_ok "patch --json content"; fi
fi
run "$I" patch "$TMP/a.lie" 36
expect_rc 1 "patch of a triangle beyond the cache"
expect_one_error_line "lie-inspect: $TMP/a.lie: patch 36: the cache has 36 triangles" "triangle beyond: one line"
for p in x 3/4 3/ -1 "3/0123012301230123012301230"; do
    run "$I" patch "$TMP/a.lie" "$p"
    expect_rc 2 "patch '$p' is a usage error"
done

# ---- diff
run "$I" diff "$TMP/a.lie" "$TMP/a2.lie"
expect_rc 0 "diff of equal caches"
if grep -qx 'units: 36 compared, 36 identical, 0 differing' "$TMP/out" && tail -1 "$TMP/out" | grep -qx same; then
    ok "diff: counts and 'same'"; else not_ok "diff same output"; sed 's/^/# /' "$TMP/out"; fi
"$I" diff - "$TMP/a.lie" <"$TMP/a2.lie" >"$TMP/out" 2>"$TMP/err"; rc=$?
expect_rc 0 "diff with A on stdin"
run "$I" diff "$TMP/a.lie" "$TMP/b.lie"
expect_rc 1 "diff of caches built with other parameters"
if grep -q '^  param max-samples: 16 vs 32$' "$TMP/out" && grep -Eq '^nodes: 0 only in A, [1-9][0-9]* only in B, [1-9][0-9]* different class' "$TMP/out" &&
    grep -q '^first 20 of [0-9]* differences' "$TMP/out" && tail -1 "$TMP/out" | grep -qx different; then
    ok "diff: header difference, node counts, the first 20 differences"; else not_ok "diff output"; sed 's/^/# /' "$TMP/out"; fi
total=$(sed -n 's/^first 20 of \([0-9]*\) differences.*/\1/p' "$TMP/out")
run "$I" diff --all "$TMP/a.lie" "$TMP/b.lie"
shown=$(grep -c '^  [0-9]' "$TMP/out")
if [ "$shown" = "$total" ]; then ok "diff --all lists all $total"; else not_ok "diff --all: $shown of $total"; fi
run "$I" diff -q "$TMP/a.lie" "$TMP/b.lie"
expect_rc 1 "diff -q"
if [ ! -s "$TMP/out" ] && [ ! -s "$TMP/err" ]; then ok "diff -q prints nothing"; else not_ok "diff -q printed"; fi
run "$I" diff --json "$TMP/a.lie" "$TMP/b.lie"
expect_rc 1 "diff --json"
if command -v python3 >/dev/null 2>&1; then
    if python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["same"] is False and d["units"]["compared"] == 36
assert d["header"] == [{"field": "param max-samples", "a": "16", "b": "32"}] and d["notes"] == []
assert d["differences_total"] == sum(d["nodes"].values()) and len(d["differences"]) == 20
assert {x["kind"] for x in d["differences"]} <= {"only_a", "only_b", "class", "list", "detail"}
' "$TMP/out"; then ok "diff --json parses, counts consistent"; else not_ok "diff --json content"; fi
fi

# A real edit changes lists; an edit that moves nothing, or the same scene
# elsewhere, changes only provenance: a note, not a difference (unless --strict).
printf '%s\n' '- rotate: {node: TallBlock, axis: [0, 1, 0], degrees: -20}' >"$TMP/tall.yaml"
printf '%s\n' '- move: {node: TallBlock, by: [0, 0, 0]}' >"$TMP/still.yaml"
"$B/rst-update" "$TMP/a.lie" "$TMP/tall.yaml" -q -o "$TMP/tall.lie" || not_ok "rst-update tall"
"$B/rst-update" "$TMP/a.lie" "$TMP/still.yaml" -q -o "$TMP/still.lie" || not_ok "rst-update still"
run "$I" diff --all "$TMP/a.lie" "$TMP/tall.lie"
expect_rc 1 "diff against an edited cache"
if grep -q '^  state hash: ' "$TMP/out" && grep -Eq 'different class, [1-9][0-9]* different list' "$TMP/out" &&
    grep -q "^  edit log: 0 edits vs 1 edit: $TMP/tall.yaml" "$TMP/out" && grep -Eq '^  [0-9/]+ 0: blockers [0-9]+ vs [0-9]+:( [-+][0-9]+)+$' "$TMP/out"; then
    ok "edited cache: state hash, classes and lists differ; lists shown as -removed +added"; else not_ok "edited diff"; sed 's/^/# /' "$TMP/out"; fi
run "$I" diff "$TMP/a.lie" "$TMP/still.lie"
expect_rc 0 "an edit that changes nothing: same"
if grep -q '^notes' "$TMP/out" && grep -q '^  edit log: 0 edits vs 1 edit' "$TMP/out"; then ok "the edit log is a note"; else
    not_ok "edit log note"; sed 's/^/# /' "$TMP/out"; fi
run "$I" diff --strict "$TMP/a.lie" "$TMP/still.lie"
expect_rc 1 "--strict counts the edit log"
# An edited cache against a fresh build of the edited scene: the same LIEs,
# three notes (scene path, the hash before edits, the edit log).
if "$B/rst-update" --help | grep -q -- --write-scene; then
    "$B/rst-update" "$TMP/a.lie" "$TMP/tall.yaml" -q -o "$TMP/tall2.lie" --write-scene "$TMP/edited.gltf" || not_ok "--write-scene"
    # shellcheck disable=SC2086
    "$B/lie-build" "$TMP/edited.gltf" $SMALL -o "$TMP/fresh.lie" || not_ok "build the edited scene"
    run "$I" diff "$TMP/tall2.lie" "$TMP/fresh.lie"
    expect_rc 0 "edited cache vs a fresh build of the edited scene: same"
    if [ "$(grep -c '^  \(scene path\|scene hash\|edit log\): ' "$TMP/out")" -eq 3 ] && ! grep -q '^header' "$TMP/out"; then
        ok "three provenance notes, no difference"; else not_ok "notes"; sed 's/^/# /' "$TMP/out"; fi
    run "$I" diff --strict --json "$TMP/tall2.lie" "$TMP/fresh.lie"
    expect_rc 1 "the same with --strict: different"
fi
mkdir -p "$TMP/elsewhere"
cp "$S/cornell.gltf" "$S/cornell.bin" "$TMP/elsewhere/"
# shellcheck disable=SC2086
"$B/lie-build" "$TMP/elsewhere/cornell.gltf" $SMALL -o "$TMP/moved.lie" || not_ok "build the moved scene"
run "$I" diff "$TMP/a.lie" "$TMP/moved.lie"
expect_rc 0 "the same scene at another path: same"
if grep -q "^  scene path: $S/cornell.gltf vs $TMP/elsewhere/cornell.gltf" "$TMP/out"; then ok "the scene path is a note"; else
    not_ok "scene path note"; sed 's/^/# /' "$TMP/out"; fi
run "$I" diff --strict "$TMP/a.lie" "$TMP/moved.lie"
expect_rc 1 "--strict counts the scene path"
"$B/lie-build" "$S/museum1.gltf" -q --samples 4 --max-samples 4 --min-patch 0.5 -o "$TMP/m1.lie" || not_ok "build museum1"
run "$I" diff "$TMP/a.lie" "$TMP/m1.lie"
expect_rc 1 "diff of caches of different scenes"
if grep -Eq '^units: 36 compared, [0-9]+ identical, [0-9]+ differing; [0-9]+ only in A, [1-9][0-9]* only in B' "$TMP/out" &&
    grep -q '^  triangles: 36 vs ' "$TMP/out"; then ok "different scenes: units only in B, triangle counts"; else
    not_ok "different scenes"; sed 's/^/# /' "$TMP/out"; fi
head -c 100 "$TMP/a.lie" >"$TMP/trunc.lie"
run "$I" diff "$TMP/a.lie" "$TMP/trunc.lie"
expect_rc 2 "diff with a damaged cache: exit 2"
expect_one_error_line "lie-inspect: $TMP/trunc.lie: " "diff with a damaged cache: one line"
run "$I" diff - -
expect_rc 2 "diff - -: usage error"
run "$I" diff "$TMP/a.lie"
expect_rc 2 "diff with one cache: usage error"

# ---- image: the same colours as lie-render's complexity layer
run "$I" image "$TMP/a.lie" -q --size 64x48 -o "$TMP/fig10.png"
expect_rc 0 "image"
expect_file "$TMP/fig10.png" "image written"
if [ "$(head -c 8 "$TMP/fig10.png" | od -An -c | tr -d ' ')" = '211PNG\r\n032\n' ]; then ok "image is a PNG"; else not_ok "PNG signature"; fi
"$B/lie-render" "$TMP/a.lie" -q --size 64x48 --light-samples 1 --aov complexity -o "$TMP/aov.exr" || not_ok "render the complexity layer"
"$H/exr-layer-png" "$TMP/aov.exr" complexity "$TMP/aov.png" || not_ok "convert the layer"
expect_same "$TMP/fig10.png" "$TMP/aov.png" "image = lie-render --aov complexity, byte for byte"
"$B/lie-build" "$S/museum3.gltf" -q --samples 4 --max-samples 4 --min-patch 0.5 -o "$TMP/m3.lie" || not_ok "build museum3"
run "$I" image "$TMP/m3.lie" -q --size 48x32 --emitter 2 --camera 'eye=0,2,6,target=0,0.5,0,fov=60' -o "$TMP/m3e2.png"
expect_rc 0 "image --emitter 2 --camera eye=...,target=..."
"$B/lie-render" "$TMP/m3.lie" -q --size 48x32 --light-samples 1 --aov complexity --emitter 2 \
    --camera 'eye=0,2,6,target=0,0.5,0,fov=60' -o "$TMP/m3e2.exr" || not_ok "render museum3 emitter 2"
"$H/exr-layer-png" "$TMP/m3e2.exr" complexity "$TMP/m3e2ref.png"
expect_same "$TMP/m3e2.png" "$TMP/m3e2ref.png" "image --emitter = lie-render --aov complexity --emitter"
"$I" image "$TMP/a.lie" -q --size 16x16 -o - >"$TMP/stdout.png" 2>"$TMP/err"; rc=$?
expect_rc 0 "image -o - writes to stdout"
run "$I" image "$TMP/a.lie" -q --emitter 1 -o "$TMP/e1.png"
expect_rc 1 "image --emitter beyond the emitters"
expect_one_error_line "lie-inspect: $TMP/a.lie: --emitter 1: the scene has 1 emitters" "--emitter beyond: one line"
run "$I" image "$TMP/a.lie" -q --camera nosuch -o "$TMP/e1.png"
expect_rc 1 "image --camera with an unknown name"
expect_no_file "$TMP/e1.png" "no image after errors"
run "$I" image "$TMP/a.lie" -q -o "$TMP/no/such/dir/x.png"
expect_rc 1 "image into a missing folder"
expect_one_error_line "lie-inspect: $TMP/no/such/dir/x.png: " "missing folder: one line naming the output"
run "$I" image "$TMP/a.lie"
expect_rc 2 "image without -o"
run "$I" image "$TMP/a.lie" -o "$TMP/x.png" --size 0x3
expect_rc 2 "image --size 0x3"
run "$I" dump "$TMP/a.lie" -o "$TMP/x.png"
expect_rc 2 "-o with dump"
run "$I" summary "$TMP/a.lie" --all
expect_rc 2 "--all with summary"
expect_no_temp "$TMP" "no temporary files left"
finish
