#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-render from caches: the oracle (conservative caches give the reference
# image; sampled ones within the stated tolerance), thread-count
# determinism, stdin, --scene, complexity layers, camera paths, errors.
. "$ROOT/tests/tools/lib.sh"
SIZE=${LIE_TEST_SIZE:-160x160}
SCENES=$S

compare() { # A B MAXFRAC_ANY MAXFRAC_2PCT WHAT
    if "$H/exr-compare" "$1" "$2" "$3" "$4" >"$TMP/cmp" 2>&1; then ok "$5: $(cat "$TMP/cmp")"; else
        not_ok "$5: $(cat "$TMP/cmp")"; fi
}

# panel_light: an emitter of 50 triangles (shafts bounded by an oriented box);
# alpha_mask: shadows through the holes of alphaMode MASK surfaces;
# bent_light: an emitter that is not planar, and a spot light (blocker
# tests in 3D, not in the emitter plane).  The oracle compares shadows from
# the same samples (--exact off); exact shadows are t0310's.
# light_strip: an emitter of 80 triangles down a corridor; dark_panel: an emissive
# texture black over part of the emitter, which is then two clusters
# (lib/scene/cluster.c): a dark one never built, and the lit one that each lit
# sample's shadow test goes to.
cp "$ROOT/tests/data/gltf/panel_light.gltf" "$ROOT/tests/data/gltf/alpha_mask.gltf" \
    "$ROOT/tests/data/gltf/bent_light.gltf" "$ROOT/tests/data/gltf/light_strip.gltf" \
    "$ROOT/tests/data/gltf/dark_panel.gltf" "$TMP/"
for scene in museum1 museum2 museum3 cornell panel_light alpha_mask bent_light light_strip dark_panel; do
    S=$SCENES; [ -f "$TMP/$scene.gltf" ] && S=$TMP
    run "$B/lie-build" "$S/$scene.gltf" -q -o "$TMP/$scene-c.lie" --blockers conservative
    expect_rc 0 "$scene: conservative build"
    run "$B/lie-build" "$S/$scene.gltf" -q -o "$TMP/$scene-s.lie"
    expect_rc 0 "$scene: sampled build"
    run "$B/lie-render" "$S/$scene.gltf" -q --size $SIZE --visibility=full -o "$TMP/$scene-full.exr"
    expect_rc 0 "$scene: reference render"
    run "$B/lie-render" "$TMP/$scene-c.lie" -q --size $SIZE --exact off -o "$TMP/$scene-c.exr"
    expect_rc 0 "$scene: render from the conservative cache"
    compare "$TMP/$scene-full.exr" "$TMP/$scene-c.exr" 0.0001 0.0001 "$scene: conservative LIE image = reference (<= 0.01% pixels differ)"
    run "$B/lie-render" "$TMP/$scene-s.lie" -q --size $SIZE --exact off -o "$TMP/$scene-s.exr"
    expect_rc 0 "$scene: render from the sampled cache"
    compare "$TMP/$scene-full.exr" "$TMP/$scene-s.exr" 1 0.001 "$scene: sampled LIE image within 2% on >= 99.9% of pixels"
    run "$B/lie-render" "$TMP/$scene-c.lie" -q --size $SIZE --visibility=full -o "$TMP/$scene-cf.exr"
    compare "$TMP/$scene-full.exr" "$TMP/$scene-cf.exr" 0 0 "$scene: --visibility=full from a cache = from the scene, pixel for pixel"
done
S=$SCENES

# an orthographic camera (bent_light's "Top"): parallel eye rays, the same
# oracle; lie-build --view builds what it sees; --write-scene keeps it
run "$B/lie-render" "$TMP/bent_light.gltf" -q --size 96x72 --camera Top --visibility=full -o "$TMP/top-full.exr"
expect_rc 0 "orthographic camera: reference render"
run "$B/lie-render" "$TMP/bent_light-c.lie" -q --size 96x72 --camera Top --exact off -o "$TMP/top-c.exr"
compare "$TMP/top-full.exr" "$TMP/top-c.exr" 0.0001 0.0001 "orthographic camera: conservative LIE image = reference"
run "$B/lie-render" "$TMP/bent_light.gltf" -q --size 96x72 --camera 0 --visibility=full -o "$TMP/persp.exr"
if "$H/exr-compare" "$TMP/persp.exr" "$TMP/top-full.exr" 0.5 1 >/dev/null 2>&1; then
    not_ok "the orthographic view differs from the perspective one"; else ok "the orthographic view differs from the perspective one"; fi
run "$B/lie-build" "$TMP/bent_light.gltf" -q --view Top -o "$TMP/top-view.lie"
expect_rc 0 "lie-build --view with an orthographic camera"
printf -- '- move: {node: Box, by: [0.1, 0, 0]}\n' >"$TMP/nudge.yaml"
run "$B/rst-update" "$TMP/bent_light-s.lie" "$TMP/nudge.yaml" -q -o "$TMP/nudge.lie" --write-scene "$TMP/nudged.gltf"
expect_rc 0 "rst-update --write-scene with an orthographic camera"
if grep -q '"orthographic"' "$TMP/nudged.gltf" && grep -q '"ymag"' "$TMP/nudged.gltf"; then
    ok "the written scene keeps the orthographic camera"; else not_ok "the written scene lost the orthographic camera"; fi
run "$B/lie-render" "$TMP/nudged.gltf" -q --size 96x72 --camera Top --visibility=full -o "$TMP/top-nudged.exr"
expect_rc 0 "the written scene renders from its orthographic camera"

run "$B/lie-render" "$TMP/museum1-s.lie" -q --size 96x64 --threads 1 -o "$TMP/t1.exr"
run "$B/lie-render" "$TMP/museum1-s.lie" -q --size 96x64 --threads 2 -o "$TMP/t2.exr"
expect_same "$TMP/t1.exr" "$TMP/t2.exr" "LIE frames identical for 1 and 2 threads"
run "$B/lie-render" "$TMP/dark_panel-s.lie" -q --size 96x64 --threads 1 -o "$TMP/s1.exr"
run "$B/lie-render" "$TMP/dark_panel-s.lie" -q --size 96x64 --threads 2 -o "$TMP/s2.exr"
expect_same "$TMP/s1.exr" "$TMP/s2.exr" "LIE frames of a clustered emitter identical for 1 and 2 threads"
run "$B/lie-build" "$TMP/dark_panel.gltf" -q --threads 1 -o "$TMP/dark_panel-1.lie"
expect_same "$TMP/dark_panel-s.lie" "$TMP/dark_panel-1.lie" "clustered caches identical for 1 and 2 threads"
"$B/lie-render" - -q --size 96x64 --threads 2 -o "$TMP/t3.exr" <"$TMP/museum1-s.lie" 2>"$TMP/err"; rc=$?
expect_rc 0 "cache from stdin"
compare "$TMP/t1.exr" "$TMP/t3.exr" 0 0 "stdin cache renders the same pixels"
"$B/lie-build" "$S/cornell.gltf" -q -o - | "$B/lie-render" - -q --size 32x32 -o "$TMP/pipe.png" 2>"$TMP/err"; rc=$?
expect_rc 0 "lie-build | lie-render pipeline"

# --scene: the right scene elsewhere works, a different scene is refused naming both hashes
cp "$S/cornell.gltf" "$S/cornell.bin" "$TMP/"
run "$B/lie-render" "$TMP/cornell-s.lie" --scene "$TMP/cornell.gltf" -q --size 32x32 -o "$TMP/sc.exr"
expect_rc 0 "--scene with the same content"
run "$B/lie-render" "$TMP/cornell-s.lie" --scene "$S/museum1.gltf" -q --size 32x32 -o "$TMP/wrong.exr"
expect_rc 1 "--scene with another scene"
if grep -q "content hash" "$TMP/err" && [ "$(wc -l <"$TMP/err")" -eq 1 ]; then ok "hash mismatch: one line naming the hashes"; else not_ok "hash mismatch message"; sed 's/^/# /' "$TMP/err"; fi
expect_no_file "$TMP/wrong.exr" "hash mismatch: no image"

# AOVs
run "$B/lie-render" "$TMP/museum1-s.lie" -q --size 48x48 --aov complexity,patch,albedo -o "$TMP/aov.exr"
expect_rc 0 "complexity and patch layers"
if grep -a -q 'complexity.R' "$TMP/aov.exr" && grep -a -q 'patch.G' "$TMP/aov.exr"; then ok "complexity/patch channels present"; else not_ok "complexity channels"; fi
run "$B/lie-render" "$TMP/museum3-s.lie" -q --size 32x32 --aov complexity --emitter 5 -o "$TMP/aov5.exr"
expect_rc 0 "--emitter 5 on museum3"
run "$B/lie-render" "$TMP/museum1-s.lie" -q --size 32x32 --aov complexity --emitter 3 -o "$TMP/aov3.exr"
expect_rc 1 "--emitter beyond the emitters"
run "$B/lie-render" "$S/museum1.gltf" -q --size 32x32 --aov complexity -o "$TMP/x.exr"
expect_rc 2 "complexity layer without a cache"

# Camera paths
# three keys, 2 + 2 + 1 frames
printf '%s\n' 'interpolation: smooth' 'keys: [{eye: [3.5, 1.6, 2.9], target: [-0.6, 0.45, -0.5], fov: 50, frames: 2},' \
    '  {eye: [0.0, 2.0, 3.5], target: [0.0, 0.5, 0.0], frames: 2}, {eye: [-3.0, 1.6, 2.5], target: [0.5, 0.4, -0.5]}]' \
    >"$TMP/path.yaml"
run "$B/lie-render" "$TMP/museum1-s.lie" -q --size 32x32 --path "$TMP/path.yaml" -o "$TMP/frame_%03d.exr"
expect_rc 0 "camera path renders"
n=$(ls "$TMP"/frame_*.exr 2>/dev/null | wc -l)
if [ "$n" -eq 5 ]; then ok "camera path: 5 frames"; else not_ok "camera path: $n frames, expected 5"; fi
run "$B/lie-render" "$TMP/museum1-s.lie" -q --size 32x32 --path "$TMP/path.yaml" -o "$TMP/frame.exr"
expect_rc 2 "camera path without %d in -o"
printf 'keys:\n  - eye: [1, 2, 3]\n    target: [0, 0, 0]\n    zoom: 3\n' >"$TMP/bad.yaml"
run "$B/lie-render" "$TMP/museum1-s.lie" -q --size 32x32 --path "$TMP/bad.yaml" -o "$TMP/bad_%d.exr"
expect_rc 1 "camera path with an unknown key"
expect_one_error_line "lie-render: $TMP/bad.yaml:4:5: keys[0].zoom" "unknown key: file:line:col and the key"
printf 'keys:\n  - eye: [1, 2]\n    target: [0, 0, 0]\n' >"$TMP/bad2.yaml"
run "$B/lie-render" "$TMP/museum1-s.lie" -q --size 32x32 --path "$TMP/bad2.yaml" -o "$TMP/bad_%d.exr"
expect_one_error_line "lie-render: $TMP/bad2.yaml:2:10: keys[0].eye" "short vector: file:line:col and the key"
printf 'keys: [\n' >"$TMP/bad3.yaml"
run "$B/lie-render" "$TMP/museum1-s.lie" -q --size 32x32 --path "$TMP/bad3.yaml" -o "$TMP/bad_%d.exr"
expect_rc 1 "camera path with a YAML syntax error"
expect_no_file "$TMP/bad_0.exr" "no frames from bad paths"

# Bad caches
head -c 100 "$TMP/cornell-s.lie" >"$TMP/trunc.lie"
run "$B/lie-render" "$TMP/trunc.lie" -q --size 8x8 -o "$TMP/t.exr"
expect_rc 1 "truncated cache"
expect_one_error_line "lie-render: $TMP/trunc.lie:" "truncated cache: one line"
printf 'garbage' >"$TMP/garbage.lie"
run "$B/lie-render" "$TMP/garbage.lie" -q --size 8x8 -o "$TMP/t.exr"
expect_rc 1 "garbage cache"
expect_no_file "$TMP/t.exr" "no image from bad caches"
finish
