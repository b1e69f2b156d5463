#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-animate: an animated glTF (translation, rotation, scale; LINEAR, STEP,
# CUBICSPLINE; morph weights; a skin; a moving light and camera) becomes
# per-frame edits whose update equals a rebuild, from the base cache and
# chained; malformed animations get one line each; lights are edits;
# lie-render --frames and --skip-existing.
. "$ROOT/tests/tools/lib.sh"

cp "$D/gltf/animated.gltf" "$TMP/"
cd "$TMP" || exit 1
mkdir edits
run "$B/lie-animate" animated.gltf --fps 4 -o edits/frame_%04d.yaml --camera-path path.yaml -q
expect_rc 0 "lie-animate writes the frames and the camera path"
expect_file edits/frame_0008.yaml "frames 0-8 for 2 s at 4 fps"
expect_no_file edits/frame_0009.yaml "no frame past the animation's end"
grep -q 'set-weights: {node: "#6", weights: \[0.75\]}' edits/frame_0003.yaml &&
    ok "frame 3 (t = 0.75 s after the first key) weighs the sheet's target 0.75" ||
    not_ok "frame 3's weights: $(grep set-weights edits/frame_0003.yaml)"
grep -q '"#5", matrix: \[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -1, 0, 0.80000001192092896, 1\]' edits/frame_0003.yaml &&
    ok "STEP holds key 1's value between keys" || not_ok "STEP: $(grep '#5' edits/frame_0003.yaml)"
grep -q '"#4", matrix: \[1, 0, 0, 0, 0, 1.4125000201165676,' edits/frame_0003.yaml &&
    ok "CUBICSPLINE scale at u = 0.75 (Hermite with the keys' tangents)" || not_ok "CUBICSPLINE: $(grep '#4' edits/frame_0003.yaml)"
grep -q '"#3", matrix: \[0.38268343786369086, 0, -0.92387953023369163,' edits/frame_0003.yaml &&
    ok "slerp: 67.5 degrees a quarter of the way from 0 to 90... at u = 0.75" || not_ok "slerp: $(grep '#3' edits/frame_0003.yaml)"
grep -q '"#8"' edits/frame_0003.yaml && ok "the skin's animated joint is written" || not_ok "no joint transform"
grep -q '"#12"' edits/frame_0003.yaml && not_ok "a node outside the default scene was written" ||
    ok "the node outside the default scene is left out"
run "$B/lie-animate" animated.gltf --fps 4 -o edits/w_%d.yaml
grep -q "warning: animation 0 targets node #12 'Offstage', which is not in the default scene" "$TMP/err" &&
    ok "the animation of a node outside the default scene is reported" || not_ok "no report: $(cat "$TMP/err")"
keys=$(grep -c '  - eye:' path.yaml)
[ "$keys" -eq 9 ] && ok "the camera path has one key per frame" || not_ok "camera path: $keys keys"

"$B/lie-build" animated.gltf -q -o base.lie || not_ok "build the rest pose"
# update from the base cache = a full recomputation of the posed scene =
# the update chained from the previous frame
prev=base.lie
for f in 0 1 3 4 6 8; do
    e=$(printf 'edits/frame_%04d.yaml' "$f")
    run "$B/rst-update" base.lie "$e" -q -o "u$f.lie"
    [ "$rc" -eq 0 ] || { not_ok "frame $f: rst-update failed"; sed 's/^/# /' "$TMP/err"; continue; }
    "$B/rst-update" base.lie "$e" -q --full -o "f$f.lie" || not_ok "frame $f: full"
    expect_same "u$f.lie" "f$f.lie" "frame $f: update from the base cache = rebuild of the posed scene (bytes)"
    "$B/rst-update" "$prev" "$e" -q -o "c$f.lie" || not_ok "frame $f: chained"
    run "$B/lie-inspect" diff "c$f.lie" "f$f.lie"
    expect_rc 0 "frame $f: chained from the previous frame = rebuild (lie-inspect diff)"
    prev="c$f.lie"
done
run "$B/lie-inspect" verify c8.lie
expect_rc 0 "the chained cache of frame 8 replays its six-file edit log to the same scene (verify)"
# the posed scene written as glTF and built afresh gives the same environments
run "$B/rst-update" base.lie edits/frame_0004.yaml -q --write-scene posed.gltf -o p4.lie
"$B/lie-build" posed.gltf -q -o fresh4.lie || not_ok "build the exported posed scene"
run "$B/lie-inspect" diff fresh4.lie f4.lie
expect_rc 0 "frame 4 (the arm bent 45 degrees): lie-build of the exported posed scene, skin and all, = the update"
# the skinned arm is bent by frame 8: its triangles moved
"$B/lie-inspect" dump u8.lie >d8.txt 2>/dev/null
"$B/lie-inspect" dump base.lie >d0.txt 2>/dev/null
cmp -s d8.txt d0.txt && not_ok "frame 8 equals the rest pose" || ok "frame 8's cache differs from the rest pose"

# malformed animations: one clear line each, exit 1
for bad in input:"input times are not strictly increasing" count:"output has 2 elements, 3 input keys need 3" \
           node:"target node 99 does not exist" path:"target path 'position' does not exist"; do
    f=${bad%%:*}
    msg=${bad#*:}
    run "$B/lie-animate" "$D/gltf/anim_bad_$f.gltf" --fps 4 -o "$TMP/bad_%d.yaml"
    expect_rc 1 "anim_bad_$f"
    expect_one_error_line "lie-animate: $D/gltf/anim_bad_$f.gltf: animation 0 'Show'" "anim_bad_$f: one line"
    grep -qF "$msg" "$TMP/err" && ok "anim_bad_$f says: $msg" || not_ok "anim_bad_$f: $(cat "$TMP/err")"
done
run "$B/lie-animate" animated.gltf --fps 4 --animation Nope -o x_%d.yaml
expect_rc 1 "an unknown animation"
run "$B/lie-animate" animated.gltf --fps 4 -o x.yaml
expect_rc 2 "-o without %d is a usage error"
run "$B/lie-animate" animated.gltf --fps 2 --animation Idle --frames 1-2 -o idle_%d.yaml
expect_rc 0 "--animation by name, --frames 1-2"
[ -s idle_1.yaml ] && [ -s idle_2.yaml ] && [ ! -e idle_0.yaml ] && [ "$(grep -c set- idle_1.yaml)" -eq 1 ] &&
    ok "Idle: frames 1 and 2 only, one operation each" || not_ok "Idle frames: $(ls idle_*)"

# lights are edits: set-light changes a punctual light, a move of its node moves it
printf -- '- set-light: {node: Bulb, color: [1, 0.2, 0.2], intensity: 5, range: 6}\n' >light.yaml
run "$B/rst-update" base.lie light.yaml -q -o l.lie
expect_rc 0 "set-light on a point light"
"$B/rst-update" base.lie light.yaml -q --full -o lf.lie
expect_same l.lie lf.lie "set-light: update = rebuild"
printf -- '- set-emission: {node: Bulb, strength: 3}\n' >noop.yaml
run "$B/rst-update" base.lie noop.yaml -q -o n.lie
expect_rc 1 "set-emission on a punctual light is an error, not a silent no-op"
expect_one_error_line "rst-update: noop.yaml:1:3: set-emission: node 'Bulb' has no mesh in its subtree (it holds a KHR_lights_punctual light: use set-light)" "set-emission on a light"
# refused EDIT WHAT: the update of base.lie by the one-line EDIT exits 1
refused() { printf -- '%s\n' "$1" >refused.yaml; run "$B/rst-update" base.lie refused.yaml -q -o n.lie; expect_rc 1 "$2"; }
refused '- set-light: {node: Bulb, inner-cone: 10}' "a cone on a point light is an error"
refused '- set-light: {node: Floor, intensity: 2}' "set-light on a node without a light is an error"
refused '- set-weights: {node: Floor, weights: [1]}' "set-weights on a mesh without targets is an error"
refused '- move: {node: Arm, by: [1, 0, 0]}' "moving a skinned mesh's own node (ignored by skinning) is an error"
printf -- '- rotate: {node: Bone0, axis: [0, 0, 1], degrees: 30}\n- move: {node: Bulb, by: [0.5, 0, 0.5]}\n- move: {node: Light, by: [0.3, -0.2, 0]}\n' >joint.yaml
run "$B/rst-update" base.lie joint.yaml -q -o j.lie
expect_rc 0 "a joint, a point light and an area light moved"
"$B/rst-update" base.lie joint.yaml -q --full -o jf.lie
expect_same j.lie jf.lie "joint and light moves: update = rebuild"

# lie-render: the frames of one range, resumable
run "$B/lie-render" u3.lie --path path.yaml --frames 3-4 -q --size 32x24 --light-samples 4 -o img_%04d.png
expect_rc 0 "lie-render --frames 3-4"
[ -s img_0003.png ] && [ -s img_0004.png ] && [ ! -e img_0002.png ] && ok "frames 3 and 4 named by their numbers" ||
    not_ok "frames: $(ls img_*)"
rm img_0004.png
run "$B/lie-render" u3.lie --path path.yaml --frames 3-4 --skip-existing -q --size 32x24 --light-samples 4 \
    --stats=json -o img_%04d.png
grep -q '"frames":1,"frames_skipped":1' "$TMP/err" && ok "--skip-existing renders only the missing frame" ||
    not_ok "--skip-existing: $(cat "$TMP/err")"
run "$B/lie-render" u3.lie --path path.yaml --frames 5-12 -q -o img_%04d.png
expect_rc 1 "--frames beyond the path"
run "$B/lie-render" u3.lie --frames 1-2 -q -o img.png
expect_rc 2 "--frames without --path"
finish
