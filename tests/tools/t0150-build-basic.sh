#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-build: caches from the bundled scenes, determinism across thread
# counts and runs, stdout, statistics, bad input.
. "$ROOT/tests/tools/lib.sh"

run "$B/lie-build" --help
expect_rc 0 "--help exits 0"
if grep -q -- '--max-blockers' "$TMP/out"; then ok "--help lists the options"; else not_ok "--help"; fi

run "$B/lie-build" "$S/cornell.gltf" -q -o "$TMP/c1.lie" --threads 1
expect_rc 0 "build cornell"
expect_file "$TMP/c1.lie" "cache written"
run "$B/lie-build" "$S/cornell.gltf" -q -o "$TMP/c2.lie" --threads 2
expect_same "$TMP/c1.lie" "$TMP/c2.lie" "cornell: identical caches for 1 and 2 threads"
run "$B/lie-build" "$S/museum1.gltf" -q -o "$TMP/m1a.lie" --threads 1 --min-patch 1e-2
run "$B/lie-build" "$S/museum1.gltf" -q -o "$TMP/m1b.lie" --threads 2 --min-patch 1e-2
expect_same "$TMP/m1a.lie" "$TMP/m1b.lie" "museum1: identical caches for 1 and 2 threads"
run "$B/lie-build" "$S/museum1.gltf" -q -o "$TMP/m1c.lie" --threads 2 --min-patch 1e-2 --blockers conservative
expect_rc 0 "conservative build"
"$B/lie-build" "$S/cornell.gltf" -q -o - >"$TMP/stdout.lie" 2>"$TMP/err"; rc=$?
expect_rc 0 "cache to stdout"
expect_same "$TMP/c1.lie" "$TMP/stdout.lie" "stdout cache equals file cache"

run "$B/lie-build" "$S/cornell.gltf" -q -o "$TMP/s.lie" --stats=json
if [ "$(wc -l <"$TMP/err")" -eq 1 ] && grep -q '"pairs":{"unlit"' "$TMP/err" && grep -q '"bytes":' "$TMP/err"; then
    ok "--stats=json: one JSON line with pairs and bytes"; else not_ok "--stats=json"; sed 's/^/# /' "$TMP/err"; fi
run "$B/lie-build" "$S/cornell.gltf" -q -o "$TMP/s.lie" --stats
if grep -q 'patches per depth' "$TMP/err" && grep -q 'time:' "$TMP/err"; then ok "--stats human"; else not_ok "--stats"; fi

# --view: only what the camera sees is built; the rest is 'none' and renders with full visibility
# (the oracle's mode, --exact off: the same samples as the reference).
run "$B/lie-build" "$S/museum2.gltf" -q --view Camera --view-size 128x128 --stats=json -o "$TMP/view.lie"
expect_rc 0 "--view Camera"
if grep -q '"none":[1-9]' "$TMP/err"; then ok "--view leaves unseen triangles unbuilt"; else not_ok "--view: no 'none' pairs"; sed 's/^/# /' "$TMP/err"; fi
run "$B/lie-inspect" verify "$TMP/view.lie"
expect_rc 0 "a view-limited cache verifies"
run "$B/lie-render" "$TMP/view.lie" -q --size 64x64 --exact off -o "$TMP/view.exr"
run "$B/lie-render" "$S/museum2.gltf" -q --size 64x64 -o "$TMP/viewref.exr"
if "$H/exr-compare" "$TMP/viewref.exr" "$TMP/view.exr" 1 0.002 >"$TMP/cmp"; then ok "view-limited cache renders like the reference: $(cat "$TMP/cmp")"; else
    not_ok "view-limited render: $(cat "$TMP/cmp")"; fi
run "$B/lie-build" "$S/museum2.gltf" -q --view NoSuchCamera -o "$TMP/view2.lie"
expect_rc 1 "--view with an unknown camera"
expect_no_file "$TMP/view2.lie" "--view with an unknown camera: no cache"

# Bad input: one line, exit 1, nothing written.
run "$B/lie-build" "$TMP/nope.gltf" -q -o "$TMP/bad.lie"
expect_rc 1 "missing scene"
expect_one_error_line "lie-build: $TMP/nope.gltf:" "missing scene: one line"
expect_no_file "$TMP/bad.lie" "missing scene: no cache"
run "$B/lie-build" "$D/gltf/bad_json.gltf" -q -o "$TMP/bad.lie"
expect_rc 1 "invalid glTF"
expect_no_file "$TMP/bad.lie" "invalid glTF: no cache"
cp "$TMP/c1.lie" "$TMP/keep.lie"
run "$B/lie-build" "$D/gltf/bad_json.gltf" -q -o "$TMP/keep.lie"
expect_same "$TMP/c1.lie" "$TMP/keep.lie" "a failed build leaves the previous cache untouched"
expect_no_temp "$TMP" "no temporary files left"
for bad in "--samples 0" "--samples x" "--min-patch 0" "--min-patch 2" "--blockers some" "--max-blockers -1" "--threads many" \
           "--split-gain 1" "--split-gain -0.1" "--split-gain nan"; do
    # shellcheck disable=SC2086
    run "$B/lie-build" "$S/cornell.gltf" -q -o "$TMP/u.lie" $bad
    expect_rc 2 "usage error: $bad"
done
# --path: the frames of a camera path are the views; what none of them sees is left unbuilt,
# and the cache renders those frames as the scene does.
cat >"$TMP/tour.yaml" <<'YAML'
interpolation: linear
keys:
  - eye: [3.5, 1.6, 2.9]
    target: [-0.6, 0.45, -0.5]
    fov: 40
    frames: 2
  - eye: [2.5, 1.2, 3.5]
    target: [0.0, 0.5, -1.0]
    fov: 40
YAML
run "$B/lie-build" "$S/museum1.gltf" -q --path "$TMP/tour.yaml" --view-size 64x64 --stats=json -o "$TMP/tour.lie"
expect_rc 0 "--path: a build for the frames of a camera path"
none=$(sed -n 's/.*"none":\([0-9]*\).*/\1/p' "$TMP/err")
run "$B/lie-build" "$S/museum1.gltf" -q --view "eye=3.5,1.6,2.9,target=-0.6,0.45,-0.5,fov=40" --view-size 64x64 \
    --stats=json -o "$TMP/one.lie"
none1=$(sed -n 's/.*"none":\([0-9]*\).*/\1/p' "$TMP/err")
if [ "${none:-0}" -gt 0 ] && [ "${none1:-0}" -ge "$none" ]; then
    ok "--path leaves $none units unbuilt, no more than its first view alone ($none1)"
else not_ok "--path: none $none, first view alone $none1"; fi
run "$B/lie-render" "$TMP/tour.lie" -q --size 32x32 --camera "eye=-3,1.5,-3,target=0,0.5,0" --stats=json -o "$TMP/away.exr"
pu=$(sed -n 's/.*"points_unbuilt":\([0-9]*\).*/\1/p' "$TMP/err")
run "$B/lie-render" "$TMP/tour.lie" -q --size 32x32 --path "$TMP/tour.yaml" --stats=json -o "$TMP/tour_%d.exr"
pt=$(sed -n 's/.*"points_unbuilt":\([0-9]*\).*/\1/p' "$TMP/err")
if [ "${pu:-0}" -gt 0 ] && [ -n "$pt" ] && [ "$pt" -lt "$pu" ]; then
    ok "--stats=json counts the shading points whose units were not built: $pu from elsewhere, $pt on the path"
else not_ok "points_unbuilt: elsewhere '$pu', on the path '$pt'"; fi
run "$B/lie-build" "$S/museum1.gltf" -q --path "$TMP/missing.yaml" -o "$TMP/u.lie"
expect_rc 1 "--path naming a missing file"
expect_no_file "$TMP/u.lie" "no cache after a bad --path"

# --split-gain: kept in the cache; 0 keeps every split (more nodes than the default)
"$B/lie-build" "$S/museum1.gltf" -q --min-patch 1e-3 --split-gain 0 -o "$TMP/g0.lie" || not_ok "build --split-gain 0"
"$B/lie-build" "$S/museum1.gltf" -q --min-patch 1e-3 -o "$TMP/gd.lie" || not_ok "build with the default gain"
"$B/lie-inspect" dump "$TMP/g0.lie" >"$TMP/g0.dump"
"$B/lie-inspect" dump "$TMP/gd.lie" >"$TMP/gd.dump"
n0=$(sed -n 's/^nodes //p' "$TMP/g0.dump"); nd=$(sed -n 's/^nodes //p' "$TMP/gd.dump")
if grep -qx 'param split-gain 0' "$TMP/g0.dump" && grep -qx 'param split-gain 0.25' "$TMP/gd.dump" && [ "$nd" -lt "$n0" ]; then
    ok "--split-gain is recorded; the default keeps fewer nodes ($nd) than 0 ($n0)"
else not_ok "split-gain: $(grep split-gain "$TMP/g0.dump" "$TMP/gd.dump") nodes $nd vs $n0"; fi
run "$B/lie-build" "$S/cornell.gltf"
expect_rc 2 "missing -o"
expect_no_file "$TMP/u.lie" "no cache after usage errors"
# the scene on stdin ("-"): its relative URIs resolve from the working
# folder; the cache records "-", so rendering it needs --scene
(cd "$S" && "$B/lie-build" - -q -o "$TMP/stdin.lie" <cornell.gltf) && ok "lie-build - reads the scene from stdin" ||
    not_ok "lie-build -"
run "$B/lie-render" "$TMP/stdin.lie" -q --size 8x8 -o "$TMP/stdin.exr"
expect_rc 1 "a cache built from stdin names no scene"
expect_one_error_line "lie-render: $TMP/stdin.lie: the cache was built from a scene read from stdin: name its file (--scene)" "one line"
run "$B/lie-render" "$TMP/stdin.lie" -q --size 8x8 --scene "$S/cornell.gltf" -o "$TMP/stdin.exr"
expect_rc 0 "with --scene it renders"
finish
