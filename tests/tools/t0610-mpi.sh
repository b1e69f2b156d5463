#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-build and lie-render under mpirun (Open MPI): the same bytes as one
# process for builds, frames and paths, for any ranks and threads; inputs
# read on rank 0 only and broadcast (ranks 1 and 2 run in an empty folder,
# the scene, cache or camera path may come on stdin); per-rank statistics;
# usage errors said once; failures (ranks given different inputs or options, a
# different binary, a rank killed mid-frame) end the job with an error,
# never a hang.  Every launch checks several things: MPI_Init costs about
# half a second a launch, four times that under ASan.
. "$ROOT/tests/tools/lib.sh"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# Open MPI keeps some of MPI_Init's memory to the end: ASan builds suppress
# it by module (tests/lsan-mpi.supp), with full stacks (Open MPI's libraries
# have no frame pointers); leaks in lie's own code are still reported.
# Unwinding every malloc the slow way costs about 2 s a launch under ASan,
# most of it in MPI_Init: launches whose lib/dist paths another launch
# covers run without the leak check ($MPI_NOLEAK).
export LSAN_OPTIONS="suppressions=$ROOT/tests/lsan-mpi.supp:fast_unwind_on_malloc=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
MPI="timeout 120 mpirun --oversubscribe -x LSAN_OPTIONS"
MPI_NOLEAK="env LSAN_OPTIONS=detect_leaks=0 $MPI"
# rank 0 in $A, which holds the scenes; ranks 1 and 2 in the empty $E
A="$TMP/a" E="$TMP/empty"
mkdir "$A" "$E"
cp "$S/museum1.gltf" "$S/museum1.bin" "$ROOT/tests/data/gltf/bent_light.gltf" "$A/"
split3() { # MPIRUN ARGS...: the same command, rank 0 in $A, ranks 1-2 in $E
    m=$1
    shift
    $m -np 1 --wdir "$A" "$@" : -np 2 --wdir "$E" "$@"
}
json_member() { tr ',' '\n' <"$TMP/err" | grep "\"$1\":" | head -1 | sed 's/.*://; s/[]}]//g'; }

# Build: museum1 on 3 ranks; only rank 0 can read the scene and its .bin
(cd "$A" && "$B/lie-build" museum1.gltf -q --min-patch 3e-3 -o "$A/m-1.lie") || not_ok "one-process build"
run split3 "$MPI" "$B/lie-build" museum1.gltf -q --min-patch 3e-3 --threads 1 -o "$A/m-3.lie" --stats=json
expect_rc 0 "build on 3 ranks, the scene readable by rank 0 only"
expect_same "$A/m-1.lie" "$A/m-3.lie" "3-rank cache = one process's"
if [ "$(json_member files_broadcast)" = 2 ] && [ "$(json_member bytes_broadcast)" -gt $((2 * 240872)) ]; then
    ok "--stats=json: the .gltf and its .bin broadcast ($(json_member bytes_broadcast) bytes)"
else
    not_ok "files broadcast: $(json_member files_broadcast), bytes $(json_member bytes_broadcast)"
fi
# bent_light has 2 emitters, so ranges split a triangle's units; 3 ranks x 2
# threads, conservative lists, built for the views of a camera path that
# only rank 0 can read
printf 'interpolation: linear\nkeys:\n  - {eye: [0, 1.5, 4], target: [0, 0.3, 0], frames: 2}\n  - {eye: [2, 1.5, 3], target: [0, 0.3, 0]}\n' >"$A/blp.yaml"
BL="-q --blockers conservative --path blp.yaml --view-size 64x64"
(cd "$A" && "$B/lie-build" bent_light.gltf $BL -o "$TMP/bl-1.lie") || not_ok "one-process bent_light build"
run split3 "$MPI_NOLEAK" "$B/lie-build" bent_light.gltf $BL --threads 2 -o "$TMP/bl-3.lie"
expect_rc 0 "bent_light: build on 3 ranks x 2 threads, the camera path on rank 0 only"
expect_same "$TMP/bl-1.lie" "$TMP/bl-3.lie" "bent_light, conservative, for a path's views: 3 ranks x 2 threads = one process"

# A frame with AOVs, from a cache on stdin (read once on rank 0 and
# broadcast, the scene too), 3 ranks x 2 threads, EXR to stdout
OPTS="-q --size 96x80 --light-samples 16 --aov depth,complexity"
(cd "$A" && "$B/lie-render" - $OPTS -o "$TMP/f1.exr" <"$A/m-1.lie") || not_ok "one-process frame"
split3 "$MPI_NOLEAK" "$B/lie-render" - $OPTS --threads 2 --stats=json -o - <"$A/m-1.lie" >"$TMP/f3.exr" 2>"$TMP/err"; rc=$?
expect_rc 0 "frame on 3 ranks x 2 threads, cache from stdin, EXR to stdout"
expect_same "$TMP/f1.exr" "$TMP/f3.exr" "3-rank frame = one process's"
tiles=$(( ((96 + 15) / 16) * ((80 + 15) / 16) ))
if grep -q '"ranks":\[{"rank":0,"items":[0-9]*,"tiles":[0-9]*,"seconds":[0-9.]*,"bytes_sent":[0-9]*},{"rank":1,' "$TMP/err" &&
    [ $(( $(grep -o '"tiles":[0-9]*' "$TMP/err" | sed 's/.*://' | paste -sd+) )) -eq "$tiles" ]; then
    ok "--stats=json: per-rank tiles (summing to $tiles) and seconds"
else
    not_ok "--stats=json per-rank tiles: $(cat "$TMP/err")"
fi

# PNG has no chunks: a frame's pieces are ranges of tiles, sent as floats
# and copied into rank 0's frame (the tiles' rows and columns, the last ones short)
"$B/lie-render" "$A/m-1.lie" -q --size 90x70 --light-samples 4 -o "$TMP/t1.png" || not_ok "one-process PNG"
run $MPI_NOLEAK -np 3 "$B/lie-render" "$A/m-1.lie" -q --size 90x70 --light-samples 4 --threads 1 --stats=json \
    -o "$TMP/t3.png"
if [ "$rc" -eq 0 ] && cmp -s "$TMP/t1.png" "$TMP/t3.png" && [ "$(json_member exr_chunks_gathered)" = 0 ] &&
    [ "$(json_member items)" -gt 3 ]; then
    ok "a PNG frame in ranges of tiles on 3 ranks: one process's bytes"
else
    not_ok "PNG frame in tiles (exit $rc): $(head -c 300 "$TMP/err")"
fi

# A frame in bands of rows, each band's EXR chunks compressed by the rank
# that rendered it and written by rank 0: zip (16-line chunks, one per row
# of tiles; the last band short) with half colour and AOVs, and piz
# (32-line chunks, two rows of tiles each)
for c in "zip 64x104 7 --half" "piz 48x200 7"; do
    set -- $c
    BOPTS="-q --size $2 --light-samples 4 --aov depth,normal --compression $1 ${4:-}"
    "$B/lie-render" "$A/m-1.lie" $BOPTS -o "$TMP/b1.exr" || not_ok "one-process frame ($1)"
    run $MPI_NOLEAK -np 3 "$B/lie-render" "$A/m-1.lie" $BOPTS --threads 1 --stats=json -o "$TMP/b3.exr"
    if [ "$rc" -eq 0 ] && cmp -s "$TMP/b1.exr" "$TMP/b3.exr" && [ "$(json_member exr_chunks_gathered)" = "$3" ]; then
        ok "$1 chunks compressed by the ranks that rendered their rows: one process's bytes ($3 chunks)"
    else
        not_ok "$1 chunks compressed apart (exit $rc, chunks $(json_member exr_chunks_gathered)):"; sed 's/^/# /' "$TMP/err" | head -5
    fi
done

# A path: 5 frames on 3 ranks (whole frames, each written by its rank, then the last ones in bands),
# the glTF on stdin, its .bin and the camera path readable by rank 0 only
cat >"$A/path.yaml" <<'YAML'
interpolation: smooth
keys:
  - {eye: [3.5, 1.6, 2.9], target: [-0.6, 0.45, -0.5], fov: 50, frames: 2}
  - {eye: [0.0, 2.0, 3.5], target: [0.0, 0.5, 0.0], frames: 2}
  - {eye: [-3.0, 1.6, 2.5], target: [0.5, 0.4, -0.5]}
YAML
mkdir "$TMP/p1" "$TMP/p3"
POPTS="-q --size 48x40 --light-samples 16 --visibility full --path path.yaml"
(cd "$A" && "$B/lie-render" - $POPTS -o "$TMP/p1/f_%02d.exr" <museum1.gltf) || not_ok "one-process path"
split3 "$MPI" "$B/lie-render" - $POPTS --threads 1 -o "$TMP/p3/f_%02d.exr" --stats=json <"$A/museum1.gltf" >"$TMP/out" 2>"$TMP/err"
rc=$?
expect_rc 0 "path on 3 ranks, glTF on stdin"
same=0
for f in "$TMP"/p1/*.exr; do cmp -s "$f" "$TMP/p3/$(basename "$f")" && same=$((same + 1)); done
if [ "$same" -eq 5 ]; then ok "path: 5 frames = one process's"; else not_ok "path: $same of 5 frames equal"; fi
# each rank writes the whole frames it rendered; rank 0 the ones it assembled
written=$(grep -o '"written":\[[^]]*\]' "$TMP/err")
wf=$(( $(printf '%s' "$written" | grep -o '"frames":[0-9]*' | sed 's/.*://' | paste -sd+) ))
wb=$(( $(printf '%s' "$written" | grep -o '"bytes":[0-9]*' | sed 's/.*://' | paste -sd+) ))
others=$(printf '%s' "$written" | grep -o '"rank":[12],"frames":[1-9]' | wc -l)
# the last 2 frames (3 ranks) in bands of one row of tiles: 2 x 3 chunks
# compressed by the ranks that rendered them
if [ "$wf" -eq 5 ] && [ "$wb" -eq "$(cat "$TMP"/p3/*.exr | wc -c)" ] && [ "$others" -ge 1 ] &&
    [ "$(json_member exr_chunks_gathered)" = 6 ]; then
    ok "--stats=json: frames and bytes written per rank ($written), the last 2 frames' 6 chunks from bands"
else
    not_ok "frames written per rank: $written; chunks from bands $(json_member exr_chunks_gathered)"
fi

[ "$(json_member files_broadcast)" = 3 ] && ok "the glTF from stdin, its .bin and the path broadcast" ||
    not_ok "files broadcast for the path: $(json_member files_broadcast)"
# --frames and --skip-existing under mpirun: only the frames asked for, and
# only the missing ones, each written by the rank that rendered it
rm "$TMP/p3/f_01.exr" "$TMP/p3/f_03.exr"
split3 "$MPI_NOLEAK" "$B/lie-render" - $POPTS --threads 1 --skip-existing -o "$TMP/p3/f_%02d.exr" --stats=json \
    <"$A/museum1.gltf" >"$TMP/out" 2>"$TMP/err"
rc=$?
same=0
for f in "$TMP"/p1/*.exr; do cmp -s "$f" "$TMP/p3/$(basename "$f")" && same=$((same + 1)); done
if [ "$rc" -eq 0 ] && [ "$same" -eq 5 ] && grep -q '"frames_skipped":3' "$TMP/err"; then
    ok "--skip-existing on 3 ranks: the 2 missing frames written again, the same bytes"
else
    not_ok "--skip-existing on 3 ranks (exit $rc, $same of 5 equal): $(grep -o '"frames_[a-z]*":[0-9]*' "$TMP/err" | paste -sd' ')"
fi
mkdir "$TMP/p4"
split3 "$MPI_NOLEAK" "$B/lie-render" - $POPTS --threads 1 --frames 1-3 -o "$TMP/p4/f_%02d.exr" <"$A/museum1.gltf" \
    >"$TMP/out" 2>"$TMP/err"
rc=$?
if [ "$rc" -eq 0 ] && [ "$(ls "$TMP/p4" | paste -sd' ')" = "f_01.exr f_02.exr f_03.exr" ] &&
    cmp -s "$TMP/p1/f_02.exr" "$TMP/p4/f_02.exr" && cmp -s "$TMP/p1/f_03.exr" "$TMP/p4/f_03.exr"; then
    ok "--frames 1-3 on 3 ranks: those frames, one process's bytes"
else
    not_ok "--frames 1-3 on 3 ranks (exit $rc): $(ls "$TMP/p4")"
fi

# A usage error: said once (by rank 0), every rank exits 2
run $MPI -np 3 "$B/lie-render" "$A/m-1.lie" --size 0x0 -o "$TMP/u.exr"
if [ "$rc" -eq 2 ] && [ "$(grep -c '^lie-render: ' "$TMP/err")" -eq 1 ] && grep -q '(see --help)$' "$TMP/err"; then
    ok "a usage error under mpirun: one line, exit 2"
else
    not_ok "usage error under mpirun (exit $rc):"; sed 's/^/# /' "$TMP/err" | head -8
fi

# Ranks given different inputs (rank 2 another scene than rank 0 read):
# one line naming the rank, no output
run $MPI -np 2 "$B/lie-render" "$A/m-1.lie" -q --size 32x32 -o "$TMP/miss.exr" : \
    -np 1 "$B/lie-render" "$A/m-1.lie" -q --size 32x32 --scene "$TMP/nowhere.gltf" -o "$TMP/miss.exr"
if [ "$rc" -ne 0 ] && [ "$(grep -c '^lie-render: ' "$TMP/err")" -eq 1 ] &&
    grep -q "^lie-render: rank 2: .*nowhere.gltf" "$TMP/err"; then
    ok "rank 2 asked for another scene: $(grep '^lie-render' "$TMP/err")"
else
    not_ok "another scene on rank 2 (exit $rc):"; sed 's/^/# /' "$TMP/err" | head -8
fi
expect_no_file "$TMP/miss.exr" "no output when a rank fails"

# Ranks started with different options (mpirun's A : B form) would mix two
# images or caches: refused, one line naming the option, every rank exits 1
refused() { # TOOL PATTERN WHAT
    if [ "$rc" -eq 1 ] && [ "$(grep -c "^$1: " "$TMP/err")" -eq 1 ] && grep -q "^$1: $2" "$TMP/err"; then
        ok "$3: $(grep "^$1" "$TMP/err")"
    else
        not_ok "$3 (exit $rc):"; sed 's/^/# /' "$TMP/err" | head -8
    fi
}
run $MPI_NOLEAK -np 1 "$B/lie-render" "$A/m-1.lie" -q --size 32x32 -o "$TMP/opt.exr" : \
    -np 2 "$B/lie-render" "$A/m-1.lie" -q --size 32x24 -o "$TMP/opt.exr"
refused lie-render "rank 1: started with --size 32x24 where rank 0 has --size 32x32" "ranks with another --size"
expect_no_file "$TMP/opt.exr" "no image when options differ"
run $MPI_NOLEAK -np 1 "$B/lie-build" "$A/bent_light.gltf" -q --samples 16 -o "$TMP/opt.lie" : \
    -np 1 "$B/lie-build" "$A/bent_light.gltf" -q -o "$TMP/opt.lie"
refused lie-build "rank 1: started with -o .* where rank 0 has --samples 16" "a rank without --samples"
expect_no_file "$TMP/opt.lie" "no cache when options differ"

# A different binary on one rank is refused
cp "$B/lie-build" "$TMP/lie-build-other" && printf 'x' >>"$TMP/lie-build-other"
run $MPI_NOLEAK -np 1 "$B/lie-build" "$A/bent_light.gltf" -q -o "$TMP/mix.lie" : -np 1 "$TMP/lie-build-other" "$A/bent_light.gltf" -q -o "$TMP/mix.lie"
if [ "$rc" -ne 0 ] && grep -q "^lie-build: rank 1: runs a different binary" "$TMP/err"; then
    ok "a different binary on rank 1 refused: $(grep '^lie-build' "$TMP/err")"
else
    not_ok "different binaries (exit $rc):"; sed 's/^/# /' "$TMP/err" | head -8
fi
expect_no_file "$TMP/mix.lie" "no cache when binaries differ"

# A rank killed mid-frame: mpirun ends the job, naming the rank and the
# signal (Open MPI 4.1 tells the other ranks nothing: docs/mpi.md); no hang,
# no output.  -v's "bvh" line comes after every rank's setup check: rank 1
# is rendering tiles from then on.
mkdir "$TMP/kill"
$MPI_NOLEAK -np 3 "$B/lie-render" "$A/m-1.lie" -q -v --size 1024x1024 --spp 16 --threads 1 \
    -o "$TMP/kill/k.exr" >"$TMP/out" 2>"$TMP/err" &
mp=$!
victim=""
for i in $(seq 400); do
    if [ -z "$victim" ]; then
        for p in $(pgrep -f "$B/lie-render" 2>/dev/null); do
            if tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qx 'OMPI_COMM_WORLD_RANK=1' &&
                grep -q "$TMP/kill" "/proc/$p/cmdline" 2>/dev/null; then victim=$p; fi
        done
    fi
    [ -n "$victim" ] && grep -q ': bvh: ' "$TMP/err" && break
    sleep 0.05
done
t0=$(date +%s)
[ -n "$victim" ] && kill -9 "$victim"
wait $mp; rc=$?
t1=$(date +%s)
if [ -n "$victim" ] && [ "$rc" -ne 0 ] && [ "$rc" -ne 124 ] && [ $((t1 - t0)) -lt 60 ] &&
    grep -q "rank 1 .*signal 9" "$TMP/err"; then
    ok "rank 1 killed mid-frame: exit $rc after $((t1 - t0)) s: $(grep 'rank 1' "$TMP/err" | head -1)"
else
    not_ok "rank 1 killed (pid '$victim', exit $rc, $((t1 - t0)) s):"; sed 's/^/# /' "$TMP/err" | head -8
fi
expect_no_file "$TMP/kill/k.exr" "no output after a killed rank"
expect_no_temp "$TMP/kill" "no temporary file after a killed rank"

# Without mpirun: no MPI at all (no Open MPI variables, nothing printed)
run "$B/lie-render" "$A/m-1.lie" --size 16x16 -q -o "$TMP/plain.exr"
if [ "$rc" -eq 0 ] && [ ! -s "$TMP/err" ]; then ok "a plain run prints nothing"; else
    not_ok "a plain run: exit $rc, $(cat "$TMP/err")"; fi
finish
