#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Damaged caches against every tool that reads caches (lie-inspect verify,
# lie-render, rst-update): bit flips in every region, truncation at every
# section boundary, sizes, counts and offsets pointing outside the file,
# wrong versions and flags.  Each must be refused with exit 1 and one line
# "TOOL: FILE: ...", leave no output and no temporary file, and never crash.
# Damage behind the checksums is made by recomputing them ("resealed").
. "$ROOT/tests/tools/lib.sh"
P="$H/cache-poke"

"$B/lie-build" "$S/cornell.gltf" --samples 8 --max-samples 16 --min-patch 0.01 -q -o "$TMP/base.lie" ||
    not_ok "build cornell"
# The base cache has an edit in its log, so EDITS is not empty.
printf '%s\n' '- move: {node: TallBlock, by: [0, 0, 0]}' >"$TMP/still.yaml"
"$B/rst-update" "$TMP/base.lie" "$TMP/still.yaml" -q -o "$TMP/good.lie" || not_ok "rst-update"
run "$B/lie-inspect" verify "$TMP/good.lie"
expect_rc 0 "the undamaged cache is valid"
cp "$TMP/good.lie" "$TMP/keep.lie"
"$P" sections "$TMP/good.lie" >"$TMP/regions" || not_ok "cache-poke sections"
if [ "$(wc -l <"$TMP/regions")" -eq 10 ]; then ok "10 regions: header, table, 7 sections, checksum"; else
    not_ok "regions"; sed 's/^/# /' "$TMP/regions"; fi
size=$(wc -c <"$TMP/good.lie")
off() { awk -v r="$1" '$1 == r { print $2 }' "$TMP/regions"; }
len() { awk -v r="$1" '$1 == r { print $3 }' "$TMP/regions"; }

# try FILE WHAT [maybe]: every tool refuses FILE (exit 1, one line naming it,
# no output).  With "maybe", damage behind the checksums may have left a
# valid cache: accepting it is fine too, and so is one line about another
# file (the recorded scene path or an edit's text may be what changed).
try() {
    f=$1; what=$2; maybe=${3:-}
    bad=""
    rm -f "$TMP/o.exr" "$TMP/o.lie"
    # the three tools at once (they write to different places)
    "$B/lie-inspect" verify "$f" >/dev/null 2>"$TMP/err.lie-inspect" & p1=$!
    "$B/lie-render" "$f" -q --size 8x8 --light-samples 1 -o "$TMP/o.exr" >/dev/null 2>"$TMP/err.lie-render" & p2=$!
    "$B/rst-update" "$f" "$TMP/still.yaml" -q -o "$TMP/o.lie" >/dev/null 2>"$TMP/err.rst-update" & p3=$!
    wait $p1; rc1=$?
    wait $p2; rc2=$?
    wait $p3; rc3=$?
    for tool in lie-inspect lie-render rst-update; do
        case $tool in lie-inspect) rc=$rc1 ;; lie-render) rc=$rc2 ;; rst-update) rc=$rc3 ;; esac
        err="$TMP/err.$tool"
        lines=$(wc -l <"$err")
        out=""
        case $tool in lie-render) [ -e "$TMP/o.exr" ] && out=1 ;; rst-update) [ -e "$TMP/o.lie" ] && out=1 ;; esac
        if [ "$rc" -eq 1 ] && [ "$lines" -eq 1 ] && grep -q "^$tool: $f: " "$err" && [ -z "$out" ]; then
            :
        elif [ -n "$maybe" ] && { [ "$rc" -eq 0 ] || { [ "$rc" -eq 1 ] && [ "$lines" -eq 1 ] && grep -q "^$tool: " "$err"; }; }; then
            : # still a valid cache, or one whose scene or edit no longer loads
        else
            bad="$bad $tool (exit $rc, $lines lines: $(head -c 300 "$err" | tr '\n' '|'))"
        fi
    done
    cp "$TMP/err.rst-update" "$TMP/err"
    if ls -a "$TMP" | grep -q '\.tmp'; then bad="$bad temporary file left"; fi
    if [ -z "$bad" ]; then ok "$what: $(cat "$TMP/err")"; else not_ok "$what:$bad"; fi
}

# poke WHAT [--reseal] OP... (on good.lie) then try; MAYBE=1 allows acceptance
n_case=0
poke() {
    what=$1; shift
    n_case=$((n_case + 1))
    "$P" edit "$TMP/good.lie" "$TMP/bad$n_case.lie" "$@" || { not_ok "$what: cache-poke $*"; return; }
    try "$TMP/bad$n_case.lie" "$what" "${MAYBE:-}"
    rm -f "$TMP/bad$n_case.lie"
}

# Bit flips: one in the middle of every region (the file checksum catches
# them), then first, middle and last byte of every section resealed.
while read -r name o l; do
    poke "bit flip in $name" "flip:$((o + l / 2)):3"
done <"$TMP/regions"
for name in META PARM EDIT EMIT ROOT NODE POOL; do
    o=$(off $name); l=$(len $name)
    bit=0
    for at in $o $((o + l / 2)) $((o + l - 1)); do
        MAYBE=1 poke "$name: bit $bit flipped at $at, resealed" --reseal "flip:$at:$bit"
        bit=$((bit + 3))
    done
done

# Truncation at every region boundary, plain and resealed.
while read -r name o l; do
    [ "$o" -gt 0 ] && poke "truncated where $name starts ($o bytes)" "truncate:$o"
    [ $((o + l)) -lt "$size" ] && poke "truncated where $name ends ($((o + l)) bytes)" --reseal "truncate:$((o + l))"
done <"$TMP/regions"
poke "one byte short" "truncate:$((size - 1))"
poke "one byte short, resealed" --reseal "truncate:$((size - 1))"

# Header: versions, flags, sizes (resealed, so only the field is wrong).
poke "version 8 (newer)" --reseal "set32:8:8"
grep -q "format version 8 is newer" "$TMP/err" && ok "version 8: named as newer" || not_ok "version message: $(cat "$TMP/err")"
poke "version 0" --reseal "set32:8:0"
poke "version 2^32-1" --reseal "set32:8:4294967295"
poke "version 8, not resealed" "set32:8:8"
poke "unknown required flag" --reseal "set32:12:1"
MAYBE=1 poke "unknown optional flag (may be ignored)" --reseal "set32:16:1"
poke "file_size 2^50" --reseal "set64:24:1125899906842624"
poke "file_size one less" --reseal "set64:24:$((size - 1))"
poke "n_sections 0" --reseal "set32:20:0"
poke "n_sections 1000" --reseal "set32:20:1000"
poke "n_sections 2^32-1" --reseal "set32:20:4294967295"
poke "n_sections 6 (a required section dropped from the table)" --reseal "set32:20:6"

# The section table: offsets and sizes outside the file.
for i in 0 2 5 6; do # META, EDIT, NODE, POOL
    t=$((32 + 32 * i))
    name=$(sed -n "$((i + 3))p" "$TMP/regions" | cut -d' ' -f1)
    poke "$name: offset 2^40" --reseal "set64:$((t + 8)):1099511627776"
    poke "$name: size 2^63" --reseal "set64:$((t + 16)):9223372036854775808"
    poke "$name: size past the end of the file" --reseal "set64:$((t + 16)):$size"
done
poke "META: offset 0" --reseal "set64:40:0"
poke "NODE: size one less" --reseal "set64:$((32 + 32 * 5 + 16)):$(($(len NODE) - 1))"
poke "PARM: reserved field set" --reseal "set32:68:1"
poke "a section id repeated" --reseal "set32:64:$(od -An -tu4 -j32 -N4 "$TMP/good.lie" | tr -d ' ')"

# Counts inside the sections pointing beyond the data.
M=$(off META); E=$(off EDIT); R=$(off ROOT); N=$(off NODE); Q=$(off POOL); F=$(off PARM); X=$(off EMIT)
poke "META n_tris 2^32-1" --reseal "set32:$((M + 16)):4294967295"
poke "META n_emitters 2^31" --reseal "set32:$((M + 20)):2147483648"
poke "META n_units 2^63" --reseal "set64:$((M + 24)):9223372036854775808"
poke "META n_nodes 2^32-1" --reseal "set32:$((M + 32)):4294967295"
poke "META n_pool 2^32-1" --reseal "set32:$((M + 36)):4294967295"
poke "META path_len 2^32-1" --reseal "set32:$((M + 40)):4294967295"
poke "META path_len one less" --reseal "set32:$((M + 40)):$(($(len META) - 49))"
poke "PARAMS samples 0" --reseal "set32:$F:0"
poke "PARAMS min_patch NaN" --reseal "set32:$((F + 16)):2143289344"
poke "PARAMS blocker mode 9" --reseal "set32:$((F + 20)):9"
poke "EDITS n_edits 2^32-1" --reseal "set32:$E:4294967295"
poke "EDITS name_len 2^32-1" --reseal "set32:$((E + 4)):4294967295"
poke "EDITS text_len 2^32-1" --reseal "set32:$((E + 8)):4294967295"
poke "EMITTERS type 7" --reseal "set32:$X:7"
poke "EMITTERS node -1" --reseal "set32:$((X + 4)):4294967295"
poke "EMITTERS triangles beyond the scene" --reseal "set32:$((X + 8)):4294967200"
poke "ROOTS root 2^32-1" --reseal "set32:$R:4294967295"
poke "ROOTS two units share a root" --reseal "set32:$((R + 4)):$(od -An -tu4 -j"$R" -N4 "$TMP/good.lie" | tr -d ' ')"
poke "NODES child 2^32-1" --reseal "set32:$N:4294967295"
poke "NODES class 99" --reseal "set32:$((N + 4)):99"
poke "NODES list 2^32-16" --reseal "set32:$((N + 12)):4294967280"
MAYBE=1 poke "NODES count 2^32-1 (informational for some classes)" --reseal "set32:$((N + 16)):4294967295"
poke "POOL entry 2^32-1" --reseal "set32:$Q:4294967295"

# Foreign files and stdin.
: >"$TMP/empty.lie"
try "$TMP/empty.lie" "empty file"
head -c 4096 /dev/urandom >"$TMP/random.lie"
try "$TMP/random.lie" "random bytes"
printf 'LIECACHE' >"$TMP/magic.lie"
try "$TMP/magic.lie" "the magic alone"
try "$S/museum2_floor.png" "a PNG"
head -c 200 "$TMP/good.lie" >"$TMP/trunc.lie"
for tool in lie-inspect lie-render rst-update; do
    case $tool in
    lie-inspect) "$B/lie-inspect" verify - <"$TMP/trunc.lie" >"$TMP/out" 2>"$TMP/err"; rc=$? ;;
    lie-render) "$B/lie-render" - -q --size 8x8 -o "$TMP/o.exr" <"$TMP/trunc.lie" >"$TMP/out" 2>"$TMP/err"; rc=$? ;;
    rst-update) "$B/rst-update" - "$TMP/still.yaml" -q -o "$TMP/o.lie" <"$TMP/trunc.lie" >"$TMP/out" 2>"$TMP/err"; rc=$? ;;
    esac
    expect_rc 1 "$tool: a truncated cache on stdin"
    expect_one_error_line "$tool: -: truncated" "$tool: stdin named '-'"
done
expect_same "$TMP/good.lie" "$TMP/keep.lie" "the undamaged cache was never touched"
finish
