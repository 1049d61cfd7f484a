#!/usr/bin/env bash
# Issue #39's end-to-end check: a sparse smoke sim through the server as a pipeline would use it.
# Makes a plume (tests/tools/make_plume_vdb: density, temperature, vel), serves, and runs
# docs/examples/pipeline.py against it — upload, two views rendered and painted, an emission solve,
# download — then prints the server's peak RSS (VmHWM) and checks the downloaded VDB kept every
# grid of the sim. Usage:
#   bench/sparse_plume_e2e.sh BUILD_DIR [NX NY NZ [VIEW_SIZE [ITERATIONS]]]   (default 1024 512 1024 256 10)
# The server runs with --max-voxels 1000000, so any box over a million voxels is stored sparse.
set -euo pipefail
build=$(realpath "$1")
nx=${2:-1024} ny=${3:-512} nz=${4:-1024} size=${5:-256} iterations=${6:-10}
root=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
start=$(date +%s%N)
"$build/bin/make_plume_vdb" "$work/plume.vdb" "$nx" "$ny" "$nz"
echo "file: $(du -m "$work/plume.vdb" | cut -f1) MiB, made in $(( ($(date +%s%N) - start) / 1000000 )) ms"
export PYTHONPATH="$root/clients/python"
VOLSTYLE_SERVE_ARGS="--max-voxels 1000000 --max-active-voxels 268435456 --max-upload-mib 4096 --session-memory-mib 16384 --memory-mib 16384" \
  bash "$root/tests/web/with_server.sh" "$build/bin/volstyle" bash -c "
    set -euo pipefail
    t0=\$(date +%s%N)
    python3 '$root/docs/examples/pipeline.py' --url \"\$VOLSTYLE_URL\" --vdb '$work/plume.vdb' --size $size \
      --unknowns emission --iterations $iterations -o '$work/solved.vdb' | tee '$work/pipeline.log'
    echo \"wall clock, upload to download: \$(( (\$(date +%s%N) - t0) / 1000000 )) ms\"
    echo \"server peak RSS: \$(awk '/VmHWM/ {printf \"%.0f MiB\", \$2 / 1024}' /proc/\$VOLSTYLE_SERVER_PID/status)\"
  "
grep -q "stored sparse" "$work/pipeline.log" || { echo "FAILED: the server did not store the plume sparse"; exit 1; }
"$build/bin/volstyle" info "$work/solved.vdb" > "$work/info.txt"
for grid in density temperature vel emission; do
  grep -q "$grid" "$work/info.txt" || { echo "FAILED: the downloaded VDB lost '$grid'"; cat "$work/info.txt"; exit 1; }
done
awk '/^solved:/ { split($0, a, "RMS "); split(a[2], b, " -> "); if (b[2] + 0 >= b[1] + 0) { print "FAILED: the solve did not lower the RMS"; exit 1 } }' "$work/pipeline.log"
echo "sparse plume end to end: passed (dense, one RGB grid of this box would take $(( nx * ny * nz * 12 / 1048576 )) MiB)"
