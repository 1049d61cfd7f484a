#!/usr/bin/env bash
# Issue #39: a sparse smoke sim's frames restyled from painted key frames with `volstyle animate`.
# Makes frames 0..2 of the plume (tests/tools/make_plume_vdb, one box, density/temperature/vel),
# paints key frames 0 and 2 (a render under a hotter sun: the solve must find emission that makes
# the plume look like that under the scene's own light), solves them jointly along the files' `vel`
# and fills frame 1, all stored sparse; prints the wall clock and peak RSS of the whole command and
# each key frame's views' RMS against their paint before and after, and checks that every RMS fell
# and that the written frames kept every grid of the sim. Usage:
#   bench/sparse_animation_e2e.sh BUILD_DIR [NX NY NZ [VIEW_SIZE [ITERATIONS]]]   (default 512 256 512 128 10)
set -euo pipefail
build=$(realpath "$1")
nx=${2:-512} ny=${3:-256} nz=${4:-512} size=${5:-128} iterations=${6:-10}
work=$(mktemp -d)
[ -n "${KEEP:-}" ] || trap 'rm -rf "$work"' EXIT; echo "work: $work"
for f in 0 1 2; do "$build/bin/make_plume_vdb" "$work/plume.$f.vdb" "$nx" "$ny" "$nz" 1 "$f"; done
# The box is 20 m wide whatever the resolution (make_plume_vdb): a camera in front, one to the side.
cams=('"eye": [10, 6, 42], "target": [10, 4, 10]' '"eye": [42, 7, 12], "target": [10, 4, 10]')
scene='"lights": [{"direction": [-0.55, 0.65, 0.55], "irradiance": [3, 3, 3]}], "background": [0, 0, 0]'
paint='"lights": [{"direction": [-0.55, 0.65, 0.55], "irradiance": [9, 5, 2]}], "background": [0, 0, 0]'
echo "{$scene}" > "$work/scene.json"
echo "{$paint}" > "$work/paint.json"
views=""
for f in 0 2; do
  for c in 0 1; do
    echo "{${cams[$c]}, \"width\": $size, \"height\": $size}" > "$work/cam$c.json"
    "$build/bin/volstyle" render --scene "$work/plume.$f.vdb" --camera "$work/cam$c.json" --lighting "$work/paint.json" \
      -o "$work/t$f$c.exr" > /dev/null
    views+="${views:+,}{\"frame\": $f, \"camera\": {${cams[$c]}, \"width\": $size, \"height\": $size}, \"target\": \"t$f$c.exr\"}"
  done
done
echo "{\"views\": [$views], \"lighting\": {$scene}}" > "$work/views.json"
/usr/bin/time -v "$build/bin/volstyle" animate --frames "$work/plume.%d.vdb" --range 0-2 --views "$work/views.json" \
  --iterations "$iterations" --sweeps 2 --storage "${STORAGE:-auto}" -o "$work/out.%d.vdb" 2> "$work/time.txt" > "$work/animate.log" \
  || { cat "$work/animate.log" "$work/time.txt"; echo "FAILED: volstyle animate"; exit 1; }
grep -v "^\s" "$work/time.txt" || true   # the progress lines (time -v's own are indented)
echo "wall clock: $(awk -F': ' '/Elapsed/ {print $2}' "$work/time.txt"); peak RSS: $(awk '/Maximum resident/ {printf "%.0f MiB", $NF / 1024}' "$work/time.txt")"
grep -q "stored sparse" "$work/time.txt" || { echo "FAILED: the frames were not stored sparse"; exit 1; }
awk '/^key frame [0-9]+: RMS per view/ { n++; sub(/.*RMS per view /, ""); k = split($0, v, ", ");
  for (i = 1; i <= k; i++) { split(v[i], ab, " -> "); if (ab[2] + 0 >= ab[1] + 0) { print "FAILED: a view'"'"'s RMS did not fall: " v[i]; bad = 1 } } }
  END { if (n != 2) { print "FAILED: expected the RMS of 2 key frames, got " n; bad = 1 } exit bad }' "$work/time.txt"
for f in 0 1 2; do
  "$build/bin/volstyle" info "$work/out.$f.vdb" > "$work/info.txt"
  for grid in density temperature vel emission; do
    grep -q "$grid" "$work/info.txt" || { echo "FAILED: frame $f lost '$grid'"; cat "$work/info.txt"; exit 1; }
  done
done
echo "sparse animation end to end: passed (dense, one RGB grid of this box would take $(( nx * ny * nz * 12 / 1048576 )) MiB a frame)"
