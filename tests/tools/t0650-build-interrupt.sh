#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-build --partial and --resume (docs/tools.md, lie-build): SIGINT in the
# middle of a build writes a valid partial cache atomically, exits 130 with
# one line; lie-inspect calls it partial, lie-render completes it with the
# whole scene; --resume finishes it into the bytes of an uninterrupted
# build, for any thread count, and refuses other parameters or views.  --edit
# builds the edited scene.
. "$(dirname "$0")/lib.sh"
cd "$TMP" || exit 1
SC="$S/museum1.gltf"
# about 2 CPU seconds on one thread: a signal at 0.4 s lands mid-build
# (--frames 0: every unit built, as fine as its lists need; the cost
# model's whole build is far shorter)
ARGS="--min-patch 1e-5 --frames 0"

# bg_build OUT SECONDS SIG ARGS...: a build in the background (SIGINT reset
# to its default: a non-interactive shell's background job starts with it
# ignored, a tool in the foreground does not), signalled after SECONDS
bg_build() {
    out=$1 wait_s=$2 sig=$3
    shift 3
    env --default-signal=INT "$B/lie-build" "$SC" -q -o "$out" "$@" 2>"$TMP/err" &
    pid=$!
    sleep "$wait_s"
    kill -"$sig" $pid 2>/dev/null
    wait $pid
    rc=$?
}

run "$B/lie-build" "$SC" $ARGS -q --threads 2 -o ref.lie
expect_rc 0 "the uninterrupted build"

bg_build part.lie 0.4 INT --partial --threads 1 $ARGS
expect_rc 130 "SIGINT: exit 130"
expect_one_error_line "lie-build: part.lie: interrupted by SIGINT: wrote a partial cache," "SIGINT: one line"
expect_no_temp . "SIGINT: no temporary left"
run "$B/lie-inspect" verify part.lie
expect_rc 0 "the partial cache is valid"
run "$B/lie-inspect" summary part.lie
if grep -q '^partial  *yes' "$TMP/out"; then ok "lie-inspect summary: partial"; else
    not_ok "lie-inspect summary does not say partial"; fi
run "$B/lie-inspect" summary ref.lie
if grep -q '^partial' "$TMP/out"; then not_ok "a complete cache is called partial"; else
    ok "a complete cache is not called partial"; fi
run "$B/lie-render" part.lie --size 48x48 --light-samples 4 -q --stats=json -o part.exr
unbuilt=$(sed -n 's/.*"pairs_unbuilt":\([0-9]*\).*/\1/p' "$TMP/err")
if [ "$rc" -eq 0 ] && [ "${unbuilt:-0}" -gt 0 ]; then ok "lie-render answers $unbuilt unbuilt pairs with Embree"; else
    not_ok "lie-render on the partial cache: rc $rc, pairs_unbuilt '${unbuilt:-}'"; fi

# interrupted again while resuming (SIGTERM this time), then completed
bg_build part2.lie 0.4 TERM --partial --resume part.lie --threads 2
expect_rc 143 "SIGTERM while resuming: exit 143"
"$B/lie-inspect" summary part2.lie --json >sum.json
built=$(sed -n 's/.*"units":\([0-9]*\).*"units_none":\([0-9]*\).*/\1 \2/p' sum.json | awk '{ print $1 - $2 }')
run "$B/lie-build" "$SC" -q --stats=json --threads 2 --resume part2.lie -o done.lie
expect_rc 0 "--resume completes it"
copied=$(sed -n 's/.*"units_copied":\([0-9]*\).*/\1/p' "$TMP/err")
[ -n "$built" ] && [ "${copied:-x}" = "$built" ] && ok "the resume copied the $built units built before" ||
    not_ok "the resume copied '${copied:-}' units, the partial cache holds '${built:-}'"
expect_same done.lie ref.lie "resumed twice = uninterrupted, byte for byte"
run "$B/lie-inspect" summary done.lie
if grep -q '^partial' "$TMP/out"; then not_ok "the completed cache is still partial"; else
    ok "the completed cache is not partial"; fi

# a resume in place, on one thread
cp part2.lie inplace.lie
run "$B/lie-build" "$SC" -q --threads 1 --resume inplace.lie -o inplace.lie
expect_same inplace.lie ref.lie "resumed in place on 1 thread = uninterrupted"

# the partial cache's parameters, or none
run "$B/lie-build" "$SC" -q --resume part.lie --samples 64 -o bad.lie
expect_rc 2 "--resume with build parameters: a usage error"
expect_no_file bad.lie "--resume with build parameters: no output"
run "$B/lie-build" "$SC" -q --resume part.lie --view 0 -o bad.lie
expect_rc 1 "--resume for other views"
expect_one_error_line "lie-build: part.lie: was built for other views" "--resume for other views: one line"
run "$B/lie-build" "$S/cornell.gltf" -q --resume part.lie -o bad.lie
expect_rc 1 "--resume for another scene"

# --edit: the edited scene's build, its edits logged, = lie-build | rst-update
printf '%s\n' '- move: {node: TallBlock, by: [0.05, 0, 0]}' >e.yaml
"$B/lie-build" "$S/cornell.gltf" -q -o - | "$B/rst-update" - e.yaml -q -o upd.lie
run "$B/lie-build" "$S/cornell.gltf" --edit e.yaml -q -o ed.lie
expect_same ed.lie upd.lie "lie-build --edit = lie-build | rst-update"
finish
