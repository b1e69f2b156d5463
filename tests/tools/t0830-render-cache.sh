#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-render SCENE --path P.yaml --cache C.lie: the cache is built as the
# frames need it and kept on disk; the frames and the cache equal lie-build
# --path + lie-render of that cache, byte for byte, whether the run goes
# through at once or is stopped after two frames and resumed
# (--skip-existing); a cache for other views is refused; usage errors.
. "$ROOT/tests/tools/lib.sh"

M1="$S/museum1.gltf"
cat >"$TMP/p.yaml" <<'YAML'
interpolation: smooth
keys:
  - eye: [3.5, 1.6, 2.9]
    target: [-0.6, 0.45, -0.5]
    fov: 50
    frames: 2
  - eye: [0.0, 2.0, 3.5]
    target: [0.0, 0.5, 0.0]
    frames: 2
  - eye: [-3.0, 1.6, 2.5]
    target: [0.5, 0.4, -0.5]
YAML
R="--size 64x64 --light-samples 8"
"$B/lie-build" "$M1" --path "$TMP/p.yaml" --view-size 96x96 -q -o "$TMP/batch.lie"

run "$B/lie-render" "$M1" --path "$TMP/p.yaml" --cache "$TMP/c.lie" --view-size 96x96 $R -q -o "$TMP/a_%d.exr"
expect_rc 0 "--path with --cache on a scene"
expect_same "$TMP/c.lie" "$TMP/batch.lie" "the cache equals lie-build --path's, byte for byte"
# the frames name their input (lie.input): lie-render of the same file
"$B/lie-render" "$TMP/c.lie" --path "$TMP/p.yaml" $R -q -o "$TMP/ref_%d.exr"
same=0
for i in 0 1 2 3 4; do cmp -s "$TMP/a_$i.exr" "$TMP/ref_$i.exr" && same=$((same + 1)); done
if [ $same = 5 ]; then ok "the 5 frames equal lie-render of lie-build --path's cache, byte for byte"; else
    not_ok "only $same of 5 frames equal"; fi

# stopped after two frames (a partial cache on disk), then resumed
run "$B/lie-render" "$M1" --path "$TMP/p.yaml" --cache "$TMP/r.lie" --view-size 96x96 $R -q --frames 0-1 \
    -o "$TMP/b_%d.exr"
expect_rc 0 "the first two frames"
if "$B/lie-inspect" summary "$TMP/r.lie" | grep -q '^partial *yes'; then ok "two frames in: a partial cache"; else
    not_ok "two frames in: not a partial cache"; fi
run "$B/lie-render" "$M1" --path "$TMP/p.yaml" --cache "$TMP/r.lie" --view-size 96x96 $R -q --skip-existing \
    -o "$TMP/b_%d.exr"
expect_rc 0 "resumed"
expect_same "$TMP/r.lie" "$TMP/batch.lie" "resumed: the cache equals lie-build --path's"
"$B/lie-render" "$TMP/r.lie" --path "$TMP/p.yaml" $R -q -o "$TMP/rref_%d.exr"
same=0
for i in 0 1 2 3 4; do cmp -s "$TMP/b_$i.exr" "$TMP/rref_$i.exr" && same=$((same + 1)); done
if [ $same = 5 ]; then ok "resumed: the 5 frames equal lie-render's"; else not_ok "resumed: only $same of 5 frames equal"; fi

# refusals
run "$B/lie-render" "$M1" --path "$TMP/p.yaml" --cache "$TMP/c.lie" --view-size 64x64 $R -q -o "$TMP/x_%d.exr"
expect_rc 1 "a cache of other views"
expect_one_error_line "lie-render: $TMP/c.lie: was built for another scene or other views" "other views: one line"
run "$B/lie-render" "$M1" --cache "$TMP/c.lie" $R -o "$TMP/x.exr"
expect_rc 2 "--cache without --path"
run "$B/lie-render" "$TMP/batch.lie" --path "$TMP/p.yaml" --cache "$TMP/c.lie" $R -o "$TMP/x_%d.exr"
expect_rc 2 "--cache with a cache as input"
finish
