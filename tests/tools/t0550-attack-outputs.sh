#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Issue 19, the output classes of an outsider's attack:
#   2. -o naming a character device, a FIFO or a symlink must not replace it
#      with a regular file: devices and FIFOs are written in place, a symlink
#      is followed and its target replaced atomically in the target's folder
#   6. all outputs of a run appear together or none do (rst-update
#      --write-scene with its cache, on a full disk); SIGINT and SIGTERM
#      remove the temporary and still end the process by the signal; stale
#      temporaries of our naming (SIGKILL) are removed by lie-inspect clean
# Device nodes and FIFOs are private ones in $TMP, never the system's.
. "$ROOT/tests/tools/lib.sh"
T=$TMP
cd "$T" || exit 1
BUILD="--samples 4 --max-samples 4 --min-patch 0.3 -q"

"$B/lie-build" "$S/cornell.gltf" $BUILD -o ref.lie || not_ok "build the reference cache"

# ---- 2. devices, FIFOs and symlinks as outputs ---------------------------------
if mknod null c 1 3 2>/dev/null && mknod full c 1 7 2>/dev/null; then
    run "$B/lie-build" "$S/cornell.gltf" $BUILD -o null
    expect_rc 0 "lie-build -o a private /dev/null node"
    if [ -c null ]; then ok "it is still a character device"; else not_ok "null was replaced: $(ls -l null)"; fi
    run "$B/lie-render" ref.lie -q --size 16x16 --light-samples 1 --format exr -o null
    expect_rc 0 "lie-render -o the null node (benchmarking)"
    [ -c null ] && ok "still a device after lie-render" || not_ok "null replaced by lie-render"
    ln -s null null.png
    run "$B/lie-render" ref.lie -q --size 16x16 --light-samples 1 -o null.png
    expect_rc 0 "a symlink to the device is written through"
    [ -c null ] && [ -L null.png ] && ok "device and link both kept" || not_ok "device or link replaced"
    run "$B/lie-build" "$S/cornell.gltf" $BUILD -o full
    expect_rc 1 "a full device fails"
    expect_one_error_line "lie-build: full: write failed: No space left on device" "one line for ENOSPC"
    [ -c full ] && ok "the full device is kept" || not_ok "full replaced"
    have_dev=1
else
    ok "# SKIP mknod not permitted here: device cases"
    have_dev=0
fi
expect_no_temp "$T" "no temporary beside the devices"

mkfifo out.fifo
cat out.fifo >from-fifo &
reader=$!
run timeout 20 "$B/lie-build" "$S/cornell.gltf" $BUILD -o out.fifo
expect_rc 0 "lie-build -o a FIFO with a reader"
wait $reader
[ -p out.fifo ] && ok "the FIFO is still a FIFO" || not_ok "FIFO replaced: $(ls -l out.fifo)"
expect_same from-fifo ref.lie "the reader got the cache"

mkdir real
ln -s real/target.lie link.lie
run "$B/lie-build" "$S/cornell.gltf" $BUILD -o link.lie
expect_rc 0 "-o a dangling symlink"
[ -L link.lie ] && ok "the symlink is kept" || not_ok "symlink replaced"
expect_same real/target.lie ref.lie "its target was created"
chmod 0640 real/target.lie
ln -s link.lie link2.lie
run "$B/lie-build" "$S/cornell.gltf" $BUILD -o link2.lie
expect_rc 0 "-o a chain of two symlinks"
[ -L link.lie ] && [ -L link2.lie ] && ok "both links kept" || not_ok "a link was replaced"
expect_same real/target.lie ref.lie "the final target replaced"
[ "$(stat -c %a real/target.lie)" = 640 ] && ok "the target keeps its mode" ||
    not_ok "mode now $(stat -c %a real/target.lie)"
expect_no_temp real "no temporary left in the target's folder"
expect_no_temp "$T" "nor in the link's"
ln -s "$T/real/abs.lie" abs.lie
run "$B/lie-build" "$S/cornell.gltf" $BUILD -o abs.lie
[ "$rc" -eq 0 ] && [ -L abs.lie ] && cmp -s real/abs.lie ref.lie && ok "an absolute symlink" || not_ok "absolute symlink"
# a symlink another user planted in a sticky world-writable folder (/tmp) is
# not followed, as the kernel's protected_symlinks does for open()
mkdir sticky && chmod 1777 sticky
ln -s ../victim.lie sticky/planted.lie
if chown -h nobody sticky/planted.lie 2>/dev/null; then
    run "$B/lie-build" "$S/cornell.gltf" $BUILD -o sticky/planted.lie
    expect_rc 1 "a planted symlink in a sticky folder"
    expect_one_error_line "a symlink of another user in a sticky world-writable folder" "one line"
    expect_no_file victim.lie "its target is not written"
    chown -h "$(id -u)" sticky/planted.lie
    run "$B/lie-build" "$S/cornell.gltf" $BUILD -o sticky/planted.lie
    expect_rc 0 "our own symlink there is followed"
else
    ok "# SKIP chown not permitted: the sticky-folder case"
fi
mkdir adir
run "$B/lie-build" "$S/cornell.gltf" $BUILD -o adir
expect_rc 1 "-o a directory"
expect_one_error_line "lie-build: adir: cannot write: is a directory" "one line"

# ---- 6. all outputs or none: --write-scene with its cache -----------------------------
printf '%s\n' '- move: {node: TallBlock, by: [0.1, 0, 0]}' >move.yaml
if [ "$have_dev" -eq 1 ]; then
    run "$B/rst-update" ref.lie move.yaml --write-scene scene-out.gltf -q -o full
    expect_rc 1 "rst-update --write-scene with the cache's disk full"
    expect_no_file scene-out.gltf "no .gltf written"
    expect_no_file scene-out.bin "no .bin written"
    expect_no_temp "$T" "no temporary left"
fi
# the same on a full disk for regular files: a file size limit (SIGXFSZ
# ignored, so writes fail with EFBIG) that the scene's files fit in and the
# cache of a finer build does not
"$B/lie-build" "$S/cornell.gltf" --samples 4 --max-samples 4 --max-blockers 0 --min-patch 0.0001 -q -o fine.lie ||
    not_ok "build fine.lie"
mkdir probe fsz
"$B/rst-update" fine.lie move.yaml --write-scene probe/s.gltf -q -o probe/c.lie || not_ok "probe sizes"
big=$(wc -c <probe/s.gltf)
[ "$(wc -c <probe/s.bin)" -gt "$big" ] && big=$(wc -c <probe/s.bin)
blocks=$((big / 512 + 1)) # ulimit -f counts 512-byte blocks in sh
printf 'keep' >fsz/scene-out.gltf
(trap '' XFSZ; ulimit -f $blocks && "$B/rst-update" fine.lie move.yaml --write-scene fsz/scene-out.gltf -q \
    -o fsz/big.lie 2>"$T/err") && rc=0 || rc=$?
if [ "$(wc -c <probe/c.lie)" -gt $((blocks * 512)) ]; then
    expect_rc 1 "rst-update --write-scene, the cache beyond the file size limit"
    expect_one_error_line "rst-update: fsz/big.lie: write failed: File too large" "one line"
    [ "$(cat fsz/scene-out.gltf)" = keep ] && ok "the old .gltf is untouched" || not_ok "the .gltf was replaced"
    expect_no_file fsz/scene-out.bin "no .bin appeared"
    expect_no_file fsz/big.lie "no cache appeared"
    expect_no_temp fsz "no temporary left"
else
    not_ok "the cache is only $(wc -c <probe/c.lie) bytes: the limit of $blocks blocks does not bite"
fi
run "$B/rst-update" ref.lie move.yaml --write-scene fsz/scene-out.gltf -q -o fsz/new.lie
expect_rc 0 "without the limit all three appear"
expect_file fsz/scene-out.bin "the .bin"
expect_file fsz/new.lie "the cache"

# ---- 6. signals -------------------------------------------------------------------
for sig in TERM INT HUP; do
    rm -f hold.out
    "$H/tmp-hold" "$T/held.lie" >hold.out &
    pid=$!
    i=0
    while [ ! -s hold.out ] && [ $i -lt 100 ]; do sleep 0.05; i=$((i + 1)); done
    tmp=$(cat hold.out)
    [ -n "$tmp" ] && [ -f "$tmp" ] && ok "SIG$sig: a temporary is open ($(basename "$tmp"))" ||
        not_ok "SIG$sig: no temporary seen"
    kill -$sig $pid
    wait $pid 2>/dev/null
    st=$?
    case $sig in TERM) want=143 ;; INT) want=130 ;; HUP) want=129 ;; esac
    [ "$st" -eq "$want" ] && ok "SIG$sig: the process still ends by the signal ($st)" ||
        not_ok "SIG$sig: exit status $st, expected $want"
    expect_no_file "$tmp" "SIG$sig: the temporary is removed"
    expect_no_file held.lie "SIG$sig: no output"
done
# a real tool killed while it runs leaves nothing either
"$B/lie-render" ref.lie -q --size 1024x1024 --light-samples 64 -o sig.exr 2>/dev/null &
pid=$!
sleep 0.5
kill -TERM $pid
wait $pid 2>/dev/null
expect_no_temp "$T" "lie-render killed by SIGTERM leaves no temporary"

# ---- 6. SIGKILL cannot be caught: lie-inspect clean ----------------------------------
mkdir stale
: >stale/.a.lie.tmpAbC123
printf 'xxxxx' >stale/.b.exr.tmpZZ9zz9
: >stale/.young.lie.tmpQwErTy
: >stale/.other.tmp
: >stale/keep.lie
ln -s keep.lie stale/.link.lie.tmp123456
touch -d '2 hours ago' stale/.a.lie.tmpAbC123 stale/.b.exr.tmpZZ9zz9 stale/.other.tmp stale/keep.lie
run "$B/lie-inspect" clean stale --dry-run
expect_rc 0 "clean --dry-run"
[ "$(wc -l <"$T/out")" -eq 2 ] && grep -q 'would remove stale/.b.exr.tmpZZ9zz9 (5 bytes)' "$T/out" &&
    ok "lists the two stale temporaries" || { not_ok "dry run listed"; sed 's/^/# /' "$T/out"; }
[ -e stale/.a.lie.tmpAbC123 ] && ok "and removes nothing" || not_ok "dry run removed"
run "$B/lie-inspect" clean stale
expect_rc 0 "clean"
expect_no_file stale/.a.lie.tmpAbC123 "a stale temporary removed"
expect_no_file stale/.b.exr.tmpZZ9zz9 "another removed"
[ -e stale/.young.lie.tmpQwErTy ] && [ -e stale/.other.tmp ] && [ -e stale/keep.lie ] && [ -L stale/.link.lie.tmp123456 ] &&
    ok "young temporaries, other names and symlinks are spared" || { not_ok "spared"; ls -la stale | sed 's/^/# /'; }
run "$B/lie-inspect" clean stale --min-age 0 -q
expect_rc 0 "clean --min-age 0 -q"
expect_no_file stale/.young.lie.tmpQwErTy "--min-age 0 takes the young one too"
[ ! -s "$T/out" ] && ok "-q prints nothing" || not_ok "-q printed"
run "$B/lie-inspect" clean "$T/none"
expect_rc 1 "clean of a missing folder"
expect_one_error_line "lie-inspect: $T/none: cannot open directory" "one line"

finish
