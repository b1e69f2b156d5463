#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-build --view: patches as fine as the views' pixels need (§4.3.3), a
# view added to a cache with --into equals one build for both views (and
# keeps the units it had), rst-update of a view-built cache equals its
# rebuild (also where an edit of the light turns what the cost model
# builds), and --stats reports the cost model's predictions.
. "$ROOT/tests/tools/lib.sh"

M="$S/museum1.gltf"
A="eye=0,1.5,4,target=0,1,0"
Bv="eye=3,2,-2,target=0,0.5,0"
V="--view-size 96x96 --min-patch 1e-3"
field() { tr ',{}' '\n\n\n' <"$1" | sed -n "s/^\"$2\":\"\{0,1\}\([^\"]*\)\"\{0,1\}$/\1/p" | head -1; }

# ---- the pixel rule
run "$B/lie-build" "$M" $V --view "$A" -q --stats=json --threads 2 -o "$TMP/a.lie"
expect_rc 0 "build for view A"
cp "$TMP/err" "$TMP/a.json"
px=$(field "$TMP/a.json" splits_pixels)
if [ "${px:-0}" -gt 0 ]; then ok "some splits are not tried: too few pixels ($px)"; else not_ok "no split left to pixels"; fi
for k in build_cpu_s_predicted build_cpu_s_measured split_saving_s_predicted split_saving_s_measured \
    frame_shadow_cpu_s_full frame_shadow_cpu_s_lie; do
    if [ -n "$(field "$TMP/a.json" $k)" ]; then ok "--stats=json model: $k $(field "$TMP/a.json" $k)"; else
        not_ok "--stats=json has no $k"; fi
done
run "$B/lie-build" "$M" $V --view "$A" -q --threads 1 -o "$TMP/a1.lie"
expect_same "$TMP/a.lie" "$TMP/a1.lie" "1 and 2 threads give the same cache"
run "$B/lie-build" "$M" $V --view "$A" --frames 0 -q --stats=json -o "$TMP/a0.lie"
if [ "$(field "$TMP/err" nodes)" -gt "$(field "$TMP/a.json" nodes)" ]; then
    ok "--frames 0 (no pixel rule) makes more nodes: $(field "$TMP/err" nodes) > $(field "$TMP/a.json" nodes)"
else not_ok "--frames 0 does not make more nodes"; fi
if "$B/lie-inspect" dump "$TMP/a.lie" | grep -qx 'views 1 96x96 depth 2'; then ok "the cache keeps its view"; else
    not_ok "no views line in the dump"; fi

# ---- --into: adding view B equals building A and B at once
cp "$TMP/a.lie" "$TMP/ab.lie"
run "$B/lie-build" --into "$TMP/ab.lie" --view "$Bv" -q --stats=json
expect_rc 0 "--into adds view B"
cp "$TMP/err" "$TMP/into.json"
run "$B/lie-build" "$M" $V --view "$A" --view "$Bv" -q --stats=json -o "$TMP/both.lie"
cp "$TMP/err" "$TMP/both.json"
expect_same "$TMP/ab.lie" "$TMP/both.lie" "A, then --into B = one build for A and B (cmp)"
kept=$(field "$TMP/into.json" units_kept); new=$(field "$TMP/into.json" units_new)
if [ "${kept:-0}" -gt 0 ] && [ "${new:-0}" -gt 0 ]; then ok "--into kept $kept units, built $new new"; else
    not_ok "--into: kept ${kept:-?}, new ${new:-?}"; fi
si=$(field "$TMP/into.json" segments); sb=$(field "$TMP/both.json" segments)
if [ "$si" -lt "$sb" ]; then ok "--into casts fewer segments than the joint build ($si < $sb)"; else
    not_ok "--into casts $si segments, the joint build $sb"; fi
run "$B/lie-build" --into "$TMP/ab.lie" --view "$Bv" -q -o "$TMP/abb.lie"
run "$B/lie-build" "$M" $V --view "$A" --view "$Bv" --view "$Bv" -q -o "$TMP/bothb.lie"
expect_same "$TMP/abb.lie" "$TMP/bothb.lie" "adding B again = a build for A, B, B"
"$B/lie-build" "$M" -q --min-patch 1e-2 -o "$TMP/whole.lie"
run "$B/lie-build" --into "$TMP/whole.lie" --view "$Bv"
expect_rc 1 "--into a cache built for the whole scene"
expect_one_error_line "lie-build: $TMP/whole.lie: built for the whole scene" "one error line"
run "$B/lie-build" --into "$TMP/ab.lie" --view "$Bv" --samples 64
expect_rc 2 "--into with a build parameter"
run "$B/lie-build" --into "$TMP/ab.lie" --view "$Bv" --view-size 64x64
expect_rc 1 "--into with another view size"

# ---- rst-update of a view-built cache = its rebuild
printf '%s\n' '- move: {node: Cube, by: [0.4, 0, -0.3]}' >"$TMP/move.yaml"
run "$B/rst-update" "$TMP/a.lie" "$TMP/move.yaml" -q --stats=json -o "$TMP/u.lie" --write-scene "$TMP/moved.gltf"
expect_rc 0 "rst-update of a view-built cache"
uv=$(field "$TMP/err" units_views)
if [ "${uv:-0}" -gt 0 ]; then ok "units whose pixels changed are rebuilt ($uv)"; else not_ok "no unit rebuilt for its pixels"; fi
run "$B/rst-update" "$TMP/a.lie" "$TMP/move.yaml" -q --full -o "$TMP/f.lie"
expect_same "$TMP/u.lie" "$TMP/f.lie" "update = full recomputation (cmp)"
run "$B/lie-build" "$TMP/moved.gltf" $V --view "$A" -q -o "$TMP/r.lie"
run "$B/lie-inspect" diff "$TMP/u.lie" "$TMP/r.lie"
expect_rc 0 "update = lie-build --view of the edited scene (lie-inspect diff)"

# ---- units that cannot pay: a frame's light samples are shared among the
# emitters by their light, so a unit of a dim emitter on a small triangle is
# left to Embree; brightening the spot turns such a decision, which the
# update follows though no shaft of the edit's moved anything
L="$ROOT/tests/data/gltf/bent_light.gltf"
run "$B/lie-build" "$L" $V --view 0 -q --stats=json -o "$TMP/l.lie"
cp "$TMP/err" "$TMP/l.json"
unpaid=$(field "$TMP/l.json" units_unpaid)
if [ "${unpaid:-0}" -gt 0 ]; then ok "units left to Embree by the cost model ($unpaid)"; else not_ok "no unit left unpaid"; fi
for k in units_unseen saving_s_per_frame_predicted break_even_frames_predicted; do
    if [ -n "$(field "$TMP/l.json" $k)" ]; then ok "--stats=json model: $k $(field "$TMP/l.json" $k)"; else
        not_ok "--stats=json has no $k"; fi
done
printf '%s\n' '- set-light: {node: Spot, intensity: 20}' >"$TMP/light.yaml"
run "$B/rst-update" "$TMP/l.lie" "$TMP/light.yaml" -q --stats=json -o "$TMP/lu.lie" --write-scene "$TMP/lit.gltf"
expect_rc 0 "rst-update of the light"
uv=$(field "$TMP/err" units_views)
if [ "${uv:-0}" -gt 0 ]; then ok "units whose decision the light turned are rebuilt ($uv)"; else
    not_ok "no unit's decision turned"; fi
run "$B/lie-build" "$TMP/lit.gltf" $V --view 0 -q --stats=json -o "$TMP/lr.lie"
if [ "$(field "$TMP/err" units_unpaid)" != "$unpaid" ]; then ok "the edit changes what pays"; else
    not_ok "the edit changes nothing the model decides"; fi
run "$B/lie-inspect" diff "$TMP/lu.lie" "$TMP/lr.lie"
expect_rc 0 "update of the light = lie-build --view of the edited scene (lie-inspect diff)"
finish
