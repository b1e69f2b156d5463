#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-view on a glTF scene, under a real X server (Xvfb): the asynchronous
# constructor (§4.3.1).  Its saved cache equals lie-build --view for the
# same camera, byte for byte, whether it caught up (wait) or not (pause:
# a partial cache, which lie-build --resume finishes and --into extends to
# the batch build's bytes); its screenshot equals lie-render of the saved
# cache; a drag during construction saves the cache lie-build --edit gives
# (update = rebuild for units built asynchronously); a partial cache opened
# again is finished; SIGTERM quits with --save written; --exposure as
# lie-render's.
. "$ROOT/tests/tools/lib.sh"

need_viewer

M1="$S/museum1.gltf"
VIEW="-q --size 96x96 --light-samples 8 --view-size 128x128"
VS="--view-size 128x128"
camera_of() { sed -n 's/.*"camera":"\([^"]*\)".*/\1/p' "$1"; }

# 1. caught up: the cache of one build for the view, and its frame
cat >"$TMP/wait.txt" <<EOF
frames 1
wait
screenshot $TMP/shot.png
quit
EOF
run xvfb_run "$B/lie-view" "$M1" $VIEW --exposure 1 --script "$TMP/wait.txt" --save "$TMP/saved.lie" --stats=json
expect_rc 0 "a scene opened, the constructor waited for"
cp "$TMP/err" "$TMP/wait.json"
cam=$(camera_of "$TMP/wait.json")
"$B/lie-build" "$M1" $VS --view "$cam" -q -o "$TMP/batch.lie"
expect_same "$TMP/saved.lie" "$TMP/batch.lie" "the saved cache equals lie-build --view of the same camera"
"$B/lie-render" "$TMP/saved.lie" --camera "$cam" --size 96x96 --light-samples 8 --exposure 1 -q -o "$TMP/ref.png"
expect_same "$TMP/shot.png" "$TMP/ref.png" "the screenshot equals lie-render of the saved cache (--exposure 1)"
if grep -q '"first_frame_ms":[0-9]' "$TMP/wait.json" && grep -q '"units_over_time":\[\[' "$TMP/wait.json" &&
    grep -q '"full_frame_after_ms":[0-9]' "$TMP/wait.json" && grep -q '"units_pending":0,' "$TMP/wait.json" &&
    grep -q '"views":1,' "$TMP/wait.json"; then
    ok "--stats=json: time to the first frame, units over time, frame times, nothing pending"
else
    not_ok "--stats=json: $(cat "$TMP/wait.json")"
fi

# 2. paused before catching up: a partial cache, the frame of what landed
cat >"$TMP/pause.txt" <<EOF
frames 1
wait-units 20
pause
screenshot $TMP/pshot.png
quit
EOF
run xvfb_run "$B/lie-view" "$M1" $VIEW --script "$TMP/pause.txt" --save "$TMP/partial.lie" --stats=json
expect_rc 0 "paused during construction"
if grep -q '"units_pending":[1-9]' "$TMP/err" && "$B/lie-inspect" summary "$TMP/partial.lie" | grep -q "^partial  *yes"; then
    ok "paused after 20 units: a partial cache"
else
    not_ok "paused after 20 units, the cache is not partial: $(grep -o '"units_pending":[0-9]*' "$TMP/err")"
fi
"$B/lie-render" "$TMP/partial.lie" --camera "$cam" --size 96x96 --light-samples 8 -q -o "$TMP/pref.png"
expect_same "$TMP/pshot.png" "$TMP/pref.png" "the screenshot equals lie-render of the saved (partial) cache"
run "$B/lie-inspect" verify "$TMP/partial.lie"
expect_rc 0 "the partial cache is valid"
run "$B/lie-build" "$M1" $VS --view "$cam" --resume "$TMP/partial.lie" -q -o "$TMP/resumed.lie"
expect_rc 0 "lie-build --resume the viewer's cache"
expect_same "$TMP/resumed.lie" "$TMP/batch.lie" "--resume of the viewer's cache equals one build, byte for byte"
cam2="eye=3,2,3,target=0,0.5,0"
"$B/lie-build" "$M1" $VS --view "$cam" --view "$cam2" -q -o "$TMP/batch2.lie"
run "$B/lie-build" --into "$TMP/partial.lie" --view "$cam2" -q -o "$TMP/into.lie"
expect_rc 0 "lie-build --into the viewer's partial cache"
expect_same "$TMP/into.lie" "$TMP/batch2.lie" "--into of the viewer's cache equals one build for both views"

# 3. the partial cache opened again: the constructor finishes it
cat >"$TMP/finish.txt" <<EOF
wait
quit
EOF
run xvfb_run "$B/lie-view" "$TMP/partial.lie" $VIEW --script "$TMP/finish.txt" --save "$TMP/finished.lie"
expect_rc 0 "a partial cache opened"
expect_same "$TMP/finished.lie" "$TMP/batch.lie" "the viewer finishes a partial cache into one build's bytes"

# 4. drags during construction: the cache lie-build --edit gives
cat >"$TMP/drag.txt" <<EOF
frames 1
redraw 4
select Cube
drag 0.4 0 -0.3
redraw 2
drag 0.1 0 0
wait
screenshot $TMP/dshot.png
quit
EOF
run xvfb_run "$B/lie-view" "$M1" $VIEW --script "$TMP/drag.txt" --record "$TMP/edits.yaml" --save "$TMP/dragged.lie"
expect_rc 0 "drags during construction"
"$B/lie-build" "$M1" $VS --view "$cam" --edit "$TMP/edits.yaml" -q -o "$TMP/dbatch.lie"
expect_same "$TMP/dragged.lie" "$TMP/dbatch.lie" "after drags, the saved cache equals lie-build --edit of the record"
"$B/lie-render" "$TMP/dragged.lie" --camera "$cam" --size 96x96 --light-samples 8 -q -o "$TMP/dref.png"
expect_same "$TMP/dshot.png" "$TMP/dref.png" "after drags, the screenshot equals lie-render of the saved cache"

# 5. SIGTERM: the session ends as Q ends it, --save written without waiting
cat >"$TMP/long.txt" <<EOF
frames 1000000
EOF
cat >"$TMP/term.sh" <<EOF
"$B/lie-view" "$M1" $VIEW --script "$TMP/long.txt" --save "$TMP/term.lie" 2>"$TMP/term.err" &
pid=\$!
sleep 1
kill -TERM \$pid
wait \$pid
echo \$? >"$TMP/term.rc"
EOF
xvfb_run sh "$TMP/term.sh" >/dev/null 2>&1
rc=$(cat "$TMP/term.rc" 2>/dev/null || echo none)
if [ "$rc" = 0 ]; then ok "SIGTERM ends the session (exit 0)"; else
    not_ok "SIGTERM: exit $rc"; sed 's/^/# /' "$TMP/term.err" | head -5; fi
run "$B/lie-inspect" verify "$TMP/term.lie"
expect_rc 0 "SIGTERM: the saved cache is valid"

# 6. a partial cache of an edited scene (an add, its file relative to the
# edit file's folder) opened and saved into another folder: the saved log
# keeps the edit, named relative to the saved cache's folder as
# rst-update's is, so the cache opens from anywhere and the constructor
# finishes it into lie-build --edit's units
mkdir -p "$TMP/edits" "$TMP/assets" "$TMP/elsewhere" "$TMP/saved"
cp "$S/cornell.gltf" "$S/cornell.bin" "$TMP/assets/"
printf '%s\n' '- add: {file: ../assets/cornell.gltf, node: TallBlock, as: Tower, transform: {translation: [0.5, 0, 1.0], scale: [0.5, 0.5, 0.5]}}' >"$TMP/edits/add.yaml"
# (--frames 0: every unit built, a build long enough for the signal to land in)
"$B/lie-build" "$M1" --edit "$TMP/edits/add.yaml" --min-patch 1e-5 --frames 0 --threads 1 -q -o "$TMP/addref.lie"
(cd "$TMP" && env --default-signal=INT "$B/lie-build" "$M1" --edit edits/add.yaml --min-patch 1e-5 --frames 0 --threads 1 \
    --partial -q -o addpart.lie 2>/dev/null & pid=$!; sleep 0.4; kill -INT $pid 2>/dev/null; wait $pid)
if "$B/lie-inspect" summary "$TMP/addpart.lie" | grep -q '^partial  *yes'; then
    printf 'pause\nquit\n' >"$TMP/pauseq.txt"
    run xvfb_run "$B/lie-view" "$TMP/addpart.lie" $VIEW --script "$TMP/pauseq.txt" --save "$TMP/saved/addsaved.lie"
    expect_rc 0 "a partial cache with an add opened and saved into another folder"
    if "$B/lie-inspect" dump "$TMP/saved/addsaved.lie" | grep -q '^edit 0 .* name \.\./edits/add\.yaml$'; then
        ok "the saved log keeps the add, named relative to the saved cache's folder"
    else
        not_ok "the saved log: $("$B/lie-inspect" dump "$TMP/saved/addsaved.lie" | grep '^edit')"
    fi
    (cd "$TMP/elsewhere" && xvfb_run "$B/lie-view" ../saved/addsaved.lie $VIEW --script "$TMP/finish.txt" \
        --save "$TMP/addfinished.lie" >/dev/null 2>&1)
    run "$B/lie-inspect" diff "$TMP/addfinished.lie" "$TMP/addref.lie"
    expect_rc 0 "opened from another folder, the constructor finishes it into lie-build --edit's units"
else
    not_ok "the interrupted build left no partial cache"
fi
finish
