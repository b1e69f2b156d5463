#!/bin/sh
# make bench-mpi: lie-render and lie-build under mpirun against one process,
# measured side by side in one run on this machine: 1 process x 2 threads
# against 2 ranks x 1 thread, a 12-frame camera path and a build, with the
# bytes each sends.  Times are wall clock of the whole command (mpirun's
# start included) and the tool's own (load to last write, from --stats);
# REPEAT runs each, the best kept.  Writes out/bench-mpi.json.  docs/mpi.md
# turns these costs into a model for 64 nodes.
set -e
cd "$(dirname "$0")/.."
SCENE=${SCENE:-tests/scenes/museum1.gltf}
SIZE=${SIZE:-320x240}
REPEAT=${REPEAT:-3}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
MPI="mpirun --oversubscribe -np 2"
mkdir -p out
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT

field() { sed -n "s/.*\"$1\":\"\{0,1\}\([^,\"}]*\).*/\1/p" | head -1; }
now() { date +%s.%N; }
best() { awk -v a="$1" -v b="$2" 'BEGIN { if (a == "" || b < a) print b; else print a }'; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { if (b > 0) printf "%.3f", a / b; else print "inf" }'; }

cat >"$TMP/path.yaml" <<'YAML'
interpolation: smooth
keys:
  - {eye: [3.5, 1.6, 2.9], target: [-0.6, 0.45, -0.5], fov: 50, frames: 4}
  - {eye: [0.0, 2.0, 3.5], target: [0.0, 0.5, 0.0], frames: 4}
  - {eye: [-3.0, 1.6, 2.5], target: [0.5, 0.4, -0.5], frames: 4}
  - {eye: [-3.5, 1.8, -1.0], target: [0.0, 0.5, 0.0]}
YAML

# run LABEL CMD... -> best wall seconds in $w, best tool seconds in $t, stats in $TMP/LABEL.json
run() {
    label=$1; shift
    w=""; t=""; i=0
    while [ $i -lt "$REPEAT" ]; do
        a=$(now); "$@" 2>"$TMP/$label.json" >/dev/null; b=$(now)
        w=$(best "$w" "$(awk -v a="$a" -v b="$b" 'BEGIN { print b - a }')")
        tt=$(awk -v l="$(field seconds_load <"$TMP/$label.json")" -v v="$(field seconds_bvh <"$TMP/$label.json")" \
            -v r="$(field seconds_render <"$TMP/$label.json")$(field seconds_build <"$TMP/$label.json")" \
            -v x="$(field seconds_write <"$TMP/$label.json")" 'BEGIN { print l + v + r + x }')
        t=$(best "$t" "$tt")
        i=$((i + 1))
    done
}

echo "bench-mpi: $SCENE, a 12-frame path at $SIZE; best of $REPEAT (the machine may be shared: compare ratios)"
bin/lie-build "$SCENE" -q -o "$TMP/c.lie"
mkdir -p "$TMP/a" "$TMP/b"
run path1 bin/lie-render "$TMP/c.lie" -q --size "$SIZE" --threads 2 --path "$TMP/path.yaml" -o "$TMP/a/f_%02d.exr" --stats=json
pw1=$w; pt1=$t
run path2 $MPI bin/lie-render "$TMP/c.lie" -q --size "$SIZE" --threads 1 --path "$TMP/path.yaml" -o "$TMP/b/f_%02d.exr" --stats=json
pw2=$w; pt2=$t
same=yes; for f in "$TMP"/a/*.exr; do cmp -s "$f" "$TMP/b/$(basename "$f")" || same=no; done
fb=$(field bytes_gathered_per_frame <"$TMP/path2.json"); fbc=$(field bytes_broadcast <"$TMP/path2.json")

# one frame, shared out by tiles
run frame1 bin/lie-render "$TMP/c.lie" -q --size "$SIZE" --threads 2 -o "$TMP/one1.exr" --stats=json
fw1=$w; ft1=$t
run frame2 $MPI bin/lie-render "$TMP/c.lie" -q --size "$SIZE" --threads 1 -o "$TMP/one2.exr" --stats=json
fw2=$w; ft2=$t
t_tiles=$(field items <"$TMP/frame2.json")

run build1 bin/lie-build "$SCENE" -q --threads 2 -o "$TMP/b1.lie" --stats=json
bw1=$w; bt1=$t
run build2 $MPI bin/lie-build "$SCENE" -q --threads 1 -o "$TMP/b2.lie" --stats=json
bw2=$w; bt2=$t
cmp -s "$TMP/b1.lie" "$TMP/b2.lie" && bsame=yes || bsame=no
bb=$(field bytes_gathered <"$TMP/build2.json"); cache=$(stat -c %s "$TMP/b1.lie")

# mpirun's own start: a run that does nothing (--version exits before MPI)
run start $MPI bin/lie-render --version
sw=$w

printf '%-34s %12s %12s %8s\n' "" "1 x 2 thr" "2 ranks x 1" "ratio"
printf '%-34s %12.3f %12.3f %8s\n' "path, 12 frames: tool seconds" "$pt1" "$pt2" "$(ratio "$pt2" "$pt1")"
printf '%-34s %12.3f %12.3f %8s\n' "path, 12 frames: wall seconds" "$pw1" "$pw2" "$(ratio "$pw2" "$pw1")"
printf '%-34s %12.3f %12.3f %8s\n' "one frame ($t_tiles items): tool s" "$ft1" "$ft2" "$(ratio "$ft2" "$ft1")"
printf '%-34s %12.3f %12.3f %8s\n' "build: tool seconds" "$bt1" "$bt2" "$(ratio "$bt2" "$bt1")"
printf '%-34s %12.3f %12.3f %8s\n' "build: wall seconds" "$bw1" "$bw2" "$(ratio "$bw2" "$bw1")"
echo "mpirun -np 2 start and stop: $sw s"
echo "bytes: per frame gathered $fb, cache broadcast $fbc (to 1 other rank), per build gathered $bb (cache $cache)"
echo "identical to one process: path $same, build $bsame"
cat >out/bench-mpi.json <<JSON
{"scene":"$SCENE","size":"$SIZE","frames":12,
 "path":{"one_process_2_threads":{"tool_seconds":$pt1,"wall_seconds":$pw1},"two_ranks_1_thread":{"tool_seconds":$pt2,"wall_seconds":$pw2},"ratio_tool":$(ratio "$pt2" "$pt1"),"identical":"$same"},
 "frame":{"one_process_2_threads":{"tool_seconds":$ft1},"two_ranks_1_thread":{"tool_seconds":$ft2},"items":$t_tiles},
 "build":{"one_process_2_threads":{"tool_seconds":$bt1,"wall_seconds":$bw1},"two_ranks_1_thread":{"tool_seconds":$bt2,"wall_seconds":$bw2},"ratio_tool":$(ratio "$bt2" "$bt1"),"identical":"$bsame"},
 "bytes_per_frame":$fb,"bytes_broadcast":$fbc,"bytes_per_build":$bb,"cache_bytes":$cache,"mpirun_start_seconds":$sw}
JSON
echo "wrote out/bench-mpi.json"
