#!/bin/sh
# lie-build and lie-render under mpirun (Open MPI): the same bytes as one
# process for builds, frames and paths, for any ranks and threads; per-rank
# statistics; failures (a scene missing on one rank, a different binary, a
# rank killed mid-frame) end the job with an error, never a hang.
. "$ROOT/tests/tools/lib.sh"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# Open MPI keeps some of MPI_Init's memory to the end: ASan builds suppress
# it by module (tests/lsan-mpi.supp), with full stacks (Open MPI's libraries
# have no frame pointers); leaks in lie's own code are still reported
export LSAN_OPTIONS="suppressions=$ROOT/tests/lsan-mpi.supp:fast_unwind_on_malloc=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
MPI="timeout 120 mpirun --oversubscribe -x LSAN_OPTIONS"

# Builds: bent_light has 2 emitters, so ranges split a triangle's units.
cp "$S/museum1.gltf" "$S/museum1.bin" "$ROOT/tests/data/gltf/bent_light.gltf" "$TMP/"
for scene in museum1 bent_light; do
    run "$B/lie-build" "$TMP/$scene.gltf" -q -o "$TMP/$scene-1.lie"
    expect_rc 0 "$scene: one-process build"
    run $MPI -np 3 "$B/lie-build" "$TMP/$scene.gltf" -q --threads 1 -o "$TMP/$scene-3.lie"
    expect_rc 0 "$scene: build on 3 ranks"
    expect_same "$TMP/$scene-1.lie" "$TMP/$scene-3.lie" "$scene: 3-rank cache = one process's"
done
run $MPI -np 2 "$B/lie-build" "$S/cornell.gltf" -q --threads 2 --blockers conservative -o "$TMP/cc-2.lie"
"$B/lie-build" "$S/cornell.gltf" -q --blockers conservative -o "$TMP/cc-1.lie"
expect_same "$TMP/cc-1.lie" "$TMP/cc-2.lie" "conservative cornell: 2 ranks x 2 threads = one process"

# A frame, with AOVs, from a cache read once on rank 0 (stdin) and broadcast
OPTS="-q --size 96x80 --light-samples 16 --aov depth,complexity"
"$B/lie-render" "$TMP/museum1-1.lie" $OPTS -o "$TMP/f1.exr"
run sh -c "$MPI -np 3 '$B/lie-render' - $OPTS --threads 1 -o - <'$TMP/museum1-1.lie' >'$TMP/f3.exr'"
expect_rc 0 "frame on 3 ranks, cache from stdin, EXR to stdout"
"$B/lie-render" - $OPTS -o "$TMP/f1s.exr" <"$TMP/museum1-1.lie"
expect_same "$TMP/f1s.exr" "$TMP/f3.exr" "3-rank frame = one process's"
run $MPI -np 2 "$B/lie-render" "$TMP/museum1-1.lie" $OPTS --threads 2 -o "$TMP/f2.exr" --stats=json
expect_same "$TMP/f1.exr" "$TMP/f2.exr" "2 ranks x 2 threads = one process"
tiles=$(( ((96 + 15) / 16) * ((80 + 15) / 16) ))
if grep -q '"ranks":\[{"rank":0,"items":[0-9]*,"tiles":[0-9]*,"seconds":[0-9.]*,"bytes_sent":[0-9]*},{"rank":1,' "$TMP/err" &&
    [ $(( $(grep -o '"tiles":[0-9]*' "$TMP/err" | sed 's/.*://' | paste -sd+) )) -eq "$tiles" ]; then
    ok "--stats=json: per-rank tiles (summing to $tiles) and seconds"
else
    not_ok "--stats=json per-rank tiles: $(cat "$TMP/err")"
fi

# A path: 5 frames on 3 ranks (whole frames, then the last ones by tiles)
cat >"$TMP/path.yaml" <<'YAML'
interpolation: smooth
keys:
  - {eye: [3.5, 1.6, 2.9], target: [-0.6, 0.45, -0.5], fov: 50, frames: 2}
  - {eye: [0.0, 2.0, 3.5], target: [0.0, 0.5, 0.0], frames: 2}
  - {eye: [-3.0, 1.6, 2.5], target: [0.5, 0.4, -0.5]}
YAML
mkdir "$TMP/p1" "$TMP/p3"
"$B/lie-render" "$TMP/museum1-1.lie" -q --size 48x40 --light-samples 16 --path "$TMP/path.yaml" -o "$TMP/p1/f_%02d.exr"
run $MPI -np 3 "$B/lie-render" "$TMP/museum1-1.lie" -q --size 48x40 --light-samples 16 --threads 1 \
    --path "$TMP/path.yaml" -o "$TMP/p3/f_%02d.exr"
expect_rc 0 "path on 3 ranks"
same=0
for f in "$TMP"/p1/*.exr; do cmp -s "$f" "$TMP/p3/$(basename "$f")" && same=$((same + 1)); done
if [ "$same" -eq 5 ]; then ok "path: 5 frames = one process's"; else not_ok "path: $same of 5 frames equal"; fi

# A scene missing on one rank: one line naming it, no output
run $MPI -np 2 "$B/lie-render" "$TMP/museum1-1.lie" -q --size 32x32 -o "$TMP/miss.exr" : \
    -np 1 "$B/lie-render" "$TMP/museum1-1.lie" -q --size 32x32 --scene "$TMP/nowhere.gltf" -o "$TMP/miss.exr"
if [ "$rc" -ne 0 ] && [ "$(grep -c '^lie-render: ' "$TMP/err")" -eq 1 ] &&
    grep -q "^lie-render: rank 2: .*nowhere.gltf" "$TMP/err"; then
    ok "a scene missing on rank 2: $(grep '^lie-render' "$TMP/err")"
else
    not_ok "a scene missing on rank 2 (exit $rc):"; sed 's/^/# /' "$TMP/err" | head -8
fi
expect_no_file "$TMP/miss.exr" "no output when a rank fails"

# A different binary on one rank is refused
cp "$B/lie-build" "$TMP/lie-build-other" && printf 'x' >>"$TMP/lie-build-other"
run $MPI -np 1 "$B/lie-build" "$S/cornell.gltf" -q -o "$TMP/mix.lie" : -np 1 "$TMP/lie-build-other" "$S/cornell.gltf" -q -o "$TMP/mix.lie"
if [ "$rc" -ne 0 ] && grep -q "^lie-build: rank 1: runs a different binary" "$TMP/err"; then
    ok "a different binary on rank 1 refused: $(grep '^lie-build' "$TMP/err")"
else
    not_ok "different binaries (exit $rc):"; sed 's/^/# /' "$TMP/err" | head -8
fi
expect_no_file "$TMP/mix.lie" "no cache when binaries differ"

# A rank killed mid-frame: mpirun ends the job, naming the rank; no hang, no output
mkdir "$TMP/kill"
$MPI -np 3 "$B/lie-render" "$TMP/museum1-1.lie" -q --size 1024x1024 --spp 16 --threads 1 \
    -o "$TMP/kill/k.exr" >"$TMP/out" 2>"$TMP/err" &
mp=$!
victim=""
for i in $(seq 100); do
    for p in $(pgrep -f "$B/lie-render" 2>/dev/null); do
        if tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qx 'OMPI_COMM_WORLD_RANK=1' &&
            tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -q "^PWD=" &&
            grep -q "$TMP/kill" "/proc/$p/cmdline" 2>/dev/null; then victim=$p; fi
    done
    [ -n "$victim" ] && break
    sleep 0.1
done
sleep 1.5 # setup done (load, BVH): rank 1 is rendering tiles
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
run "$B/lie-render" "$TMP/museum1-1.lie" --size 16x16 -q -o "$TMP/plain.exr"
if [ "$rc" -eq 0 ] && [ ! -s "$TMP/err" ]; then ok "a plain run prints nothing"; else
    not_ok "a plain run: exit $rc, $(cat "$TMP/err")"; fi
finish
