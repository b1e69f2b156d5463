#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# A scene without emitters: a warning that names --default-light; headlight (a point light at
# the camera) or sun (a directional light from above) light its geometry; a scene with
# emitters is left as it is; a cache cannot take one (its environments know no such light).
. "$(dirname "$0")/lib.sh"
G="$D/gltf/hierarchy.gltf"
maxof() { iinfo --stats "$1" 2>/dev/null | sed -n 's/.*Stats Max: *//p' | head -1 | awk '{print $1 + $2 + $3}'; }

run "$B/lie-render" "$G" --size 48x48 -o "$TMP/none.exr"
expect_rc 0 "no emitters, no --default-light"
expect_one_error_line "lie-render: $G: warning: no emitters" "one warning"
grep -q -- '--default-light headlight or sun' "$TMP/err" && ok "which names --default-light" || not_ok "$(cat "$TMP/err")"
[ "$(maxof "$TMP/none.exr")" = 0 ] && ok "and the image is black" || not_ok "max $(maxof "$TMP/none.exr")"
for l in headlight sun; do
    run "$B/lie-render" "$G" --size 48x48 --default-light $l -o "$TMP/$l.exr"
    expect_rc 0 "--default-light $l"
    [ ! -s "$TMP/err" ] && ok "$l: no warning" || not_ok "$l: $(cat "$TMP/err")"
    m=$(maxof "$TMP/$l.exr")
    awk -v m="$m" 'BEGIN { exit !(m > 0) }' && ok "$l lights the geometry (max $m, R+G+B)" || not_ok "$l: max '$m'"
done
cmp -s "$TMP/headlight.exr" "$TMP/sun.exr" && not_ok "headlight and sun give the same image" || ok "headlight and sun differ"
run "$B/lie-render" "$G" --size 48x48 --default-light headlight --visibility=full --threads 1 -o "$TMP/h1.exr"
expect_same "$TMP/h1.exr" "$TMP/headlight.exr" "the headlight's image is the same on 1 thread"

run "$B/lie-render" "$S/cornell.gltf" --size 24x24 -o "$TMP/c0.exr"
run "$B/lie-render" "$S/cornell.gltf" --size 24x24 --default-light sun -o "$TMP/c1.exr"
expect_same "$TMP/c0.exr" "$TMP/c1.exr" "a scene with emitters is left as it is"
"$B/lie-build" -q "$S/cornell.gltf" -o "$TMP/c.lie"
run "$B/lie-render" "$TMP/c.lie" --size 24x24 --default-light headlight -o "$TMP/c2.exr"
expect_rc 2 "--default-light with a cache is a usage error"
expect_no_file "$TMP/c2.exr" "no image then"
run "$B/lie-render" "$G" --size 24x24 --default-light moon -o "$TMP/m.exr"
expect_rc 2 "--default-light moon: usage error"
finish
