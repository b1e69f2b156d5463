#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-view under a real X server (Xvfb): a scripted session moves an object,
# waits for the constructor and takes a screenshot, which must equal
# lie-render of the recorded edits replayed by rst-update, from the printed
# camera; --save equals rst-update's cache; a real key press (xdotool) quits
# with exit 0; without a display, one line and exit 1.
. "$ROOT/tests/tools/lib.sh"

# X libraries keep a few allocations to the end of the process: not ours
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"

# usage and display errors need no X server
run "$B/lie-view"
expect_rc 2 "no input is a usage error"
run env -u DISPLAY -u WAYLAND_DISPLAY -u SDL_VIDEODRIVER "$B/lie-view" "$S/cornell.gltf"
expect_rc 1 "without a display"
expect_one_error_line "lie-view: cannot open a window: no display" "without a display: one line"
printf 'orbit 10\n' >"$TMP/bad.txt"
run "$B/lie-view" "$S/cornell.gltf" --script "$TMP/bad.txt"
expect_rc 1 "a bad script fails before a window opens"
expect_one_error_line "lie-view: $TMP/bad.txt:1:1: orbit: expected 2 numbers" "bad script: file:line and the command"

if ! command -v Xvfb >/dev/null 2>&1; then
    not_ok "Xvfb is missing (make deps installs xvfb)"
    finish
fi

"$B/lie-build" "$S/museum1.gltf" -q --min-patch 1e-2 -o "$TMP/m1.lie" || not_ok "build museum1"

# A scripted session: look around, move the cube, rotate a chair, change a
# material, undo and redo, remove a chair and undo that (restore), wait for
# the constructor, screenshot.
cat >"$TMP/s.txt" <<EOF
frames 2
orbit 15 -5
dolly 0.1
frames 1
select Cube
drag 0.4 0 -0.3
pick 64 96
select Chair2
rotate 0 1 0 30
set-material base-color: [0.8, 0.2, 0.1], roughness: 0.5
undo
redo
select Chair1
remove
undo
wait
screenshot $TMP/shot.png
quit
EOF
run xvfb_run "$B/lie-view" "$TMP/m1.lie" --size 128x128 --light-samples 16 --script "$TMP/s.txt" \
    --record "$TMP/edits.yaml" --save "$TMP/saved.lie" --stats=json -q
expect_rc 0 "scripted session"
expect_file "$TMP/shot.png" "the screenshot is written"
expect_file "$TMP/edits.yaml" "the edits are recorded"
if grep -q '^- move: {node: Cube, by: \[0.4' "$TMP/edits.yaml" && grep -q '^- set-material: {node: Chair2' "$TMP/edits.yaml" &&
    grep -q '^- rotate: {node: Chair2' "$TMP/edits.yaml" && grep -q '^- remove: {node: ' "$TMP/edits.yaml" &&
    grep -q '^- restore: {node: ' "$TMP/edits.yaml"; then
    ok "the record holds the move, the rotation, the material, the removal and its undo (restore)"
else
    not_ok "the record: $(cat "$TMP/edits.yaml")"
fi
cam=$(sed -n 's/.*"camera":"\([^"]*\)".*/\1/p' "$TMP/err")
if [ -n "$cam" ] && grep -q '"frames":[1-9]' "$TMP/err" && grep -Eq '"update_ms":\[[0-9.]+(,[0-9.]+){6}\]' "$TMP/err" &&
    grep -q '"pending_max":[1-9]' "$TMP/err" && grep -q '"fps_mean":' "$TMP/err"; then
    ok "--stats=json: frames, fps_mean, update_ms per edit, pending_max, camera"
else
    not_ok "--stats=json: $(cat "$TMP/err")"
fi
# replay: the same cache bytes, the same pixels
run "$B/rst-update" "$TMP/m1.lie" "$TMP/edits.yaml" -q -o "$TMP/replayed.lie"
expect_rc 0 "rst-update replays the record"
expect_same "$TMP/saved.lie" "$TMP/replayed.lie" "--save equals rst-update of the record, byte for byte"
run "$B/lie-render" "$TMP/replayed.lie" --camera "$cam" --size 128x128 --light-samples 16 -q -o "$TMP/ref.png"
expect_rc 0 "lie-render from the printed camera"
expect_same "$TMP/shot.png" "$TMP/ref.png" "the screenshot equals lie-render of the replayed edits, pixel for pixel"

# A real key event closes the window with exit 0, and P prints the camera.
cat >"$TMP/keys.sh" <<EOF
"$B/lie-view" "$S/cornell.gltf" --size 96x96 --light-samples 4 -q >"$TMP/keys.out" 2>"$TMP/keys.err" &
pid=\$!
for i in \$(seq 1 100); do
    xdotool search --name lie-view >/dev/null 2>&1 && break
    sleep 0.1
done
win=\$(xdotool search --name lie-view | head -1)
xdotool windowfocus --sync "\$win" 2>/dev/null
xdotool key --window "\$win" p
sleep 0.3
xdotool key --window "\$win" q
wait \$pid
echo \$? >"$TMP/keys.rc"
EOF
xvfb_run sh "$TMP/keys.sh" >/dev/null 2>&1
rc=$(cat "$TMP/keys.rc" 2>/dev/null || echo none)
if [ "$rc" = 0 ]; then ok "xdotool key q closes the window (exit 0)"; else
    not_ok "xdotool key q: exit $rc"; sed 's/^/# /' "$TMP/keys.err" | head -5; fi
if grep -q '^eye=.*,target=.*,up=0,1,0,fov=' "$TMP/keys.out"; then ok "P prints the camera: $(cat "$TMP/keys.out")"; else
    not_ok "P prints the camera: '$(cat "$TMP/keys.out" 2>/dev/null)'"; fi
finish
