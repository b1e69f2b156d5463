#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# --stats=json: every tool's record starts {"schema":1,"tool":...; --stats-file FILE writes it
# there (atomically, "-" stdout) and leaves stderr to the warnings; strings are valid UTF-8
# whatever the bytes of a path (an invalid byte becomes \udcXX, PEP 383's surrogateescape).
. "$(dirname "$0")/lib.sh"
utf8() { iconv -f UTF-8 -t UTF-8 "$1" >/dev/null 2>&1; }

run "$B/lie-build" "$S/cornell.gltf" -q -o "$TMP/c.lie" --stats-file "$TMP/build.json"
expect_rc 0 "lie-build --stats-file"
grep -q '^{"schema":1,"tool":"lie-build","input":".*cornell.gltf","triangles":36,' "$TMP/build.json" && [ "$(wc -l <"$TMP/build.json")" -eq 1 ] \
    && ok "lie-build: one record, schema 1" || not_ok "build.json: $(head -c 200 "$TMP/build.json")"
[ ! -s "$TMP/err" ] && ok "and nothing on stderr" || not_ok "stderr: $(cat "$TMP/err")"
printf -- '- set-transform: {node: "#0", matrix: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0.01,0,1]}\n' >"$TMP/e.yaml"
run "$B/rst-update" "$TMP/c.lie" "$TMP/e.yaml" -q -o "$TMP/u.lie" --stats-file "$TMP/update.json"
grep -q '^{"schema":1,"tool":"rst-update","input":' "$TMP/update.json" && ok "rst-update: schema 1" \
    || not_ok "rst-update: rc $rc, $(cat "$TMP/err") $(head -c 200 "$TMP/update.json")"
run "$B/lie-animate" "$D/gltf/animated.gltf" -q --fps 2 -o "$TMP/f_%d.yaml" --stats-file -
grep -q '^{"schema":1,"tool":"lie-animate","input":' "$TMP/out" && ok "lie-animate --stats-file -: the record on stdout" \
    || not_ok "lie-animate: $(cat "$TMP/out" "$TMP/err")"

# a path holding byte 0xFF (not UTF-8), and a scene without emitters: its warning on stderr
name=$(printf 'sc\377ene.gltf')
cp "$D/gltf/hierarchy.gltf" "$TMP/$name"
run "$B/lie-render" "$TMP/$name" --size 8x8 -o "$TMP/x.png" --stats=json
line=$(grep '^{' "$TMP/err")
echo "$line" >"$TMP/line.json"
utf8 "$TMP/line.json" && ok "--stats=json of a non-UTF-8 path is valid UTF-8" || not_ok "invalid UTF-8: $line"
grep -q '"input":"[^"]*sc\\udcffene.gltf"' "$TMP/line.json" && ok "byte 0xFF written as \\udcff" || not_ok "input: $line"
[ "$(grep -c . "$TMP/err")" -eq 2 ] && grep -q 'warning: no emitters' "$TMP/err" && [ "$(grep -c '^{' "$TMP/err")" -eq 1 ] \
    && ok "on stderr: the warning and the record, each a line of its own" || not_ok "stderr: $(cat "$TMP/err")"
run "$B/lie-render" "$TMP/$name" --size 8x8 -o "$TMP/x.png" --stats-file "$TMP/r.json"
grep -q 'warning: no emitters' "$TMP/err" && ! grep -q '{' "$TMP/err" && ok "--stats-file: stderr has the warning only" \
    || not_ok "stderr: $(cat "$TMP/err")"
grep -q '^{"schema":1,"tool":"lie-render",' "$TMP/r.json" && ! grep -q warning "$TMP/r.json" && utf8 "$TMP/r.json" \
    && ok "and the file the record only" || not_ok "r.json: $(cat "$TMP/r.json")"

run "$B/lie-render" "$S/cornell.gltf" --size 8x8 -o "$TMP/y.png" --stats --stats-file "$TMP/z.json"
expect_rc 2 "--stats (text) with --stats-file is a usage error"
expect_no_file "$TMP/z.json" "no statistics file then"
run "$B/lie-render" "$S/cornell.gltf" --size 8x8 -o "$TMP/y.png" --stats-file "$TMP/no/such/dir/s.json"
expect_rc 1 "a --stats-file that cannot be written: exit 1"
expect_one_error_line "lie-render: $TMP/no/such/dir/s.json" "one line naming it"
finish
