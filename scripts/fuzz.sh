#!/usr/bin/env bash
# Fuzzes every parser at the door with libFuzzer (issue #9): request bodies, request targets
# (paths and query strings), uploaded images, VDBs and meshes (tests/fuzz/fuzz_*.cpp).
#   scripts/fuzz.sh [SECONDS] [HARNESS ...]     default: 600 s each, all seven; 0: the last run's report
# Builds the harnesses with clang + ASan + UBSan in build-fuzz/, runs each in fork mode for
# SECONDS (two at a time on this machine's cores), merges new coverage into tests/fuzz/corpus/,
# keeps crash inputs in build-fuzz/artifacts/, and prints a table of executions, coverage and
# crashes — split into crashes in our code and crashes inside libraries (OpenVDB's are contained by
# the `volstyle read-vdb` child process). Exits 1 if any crash is in our code.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-600}"
shift || true
harnesses=("$@")
[ ${#harnesses[@]} -gt 0 ] || harnesses=(requests query image vdb mesh_obj mesh_ply mesh_gltf)

bash scripts/install_deps.sh clang-14 libclang-rt-14-dev
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
if [ ! -f build-fuzz/CMakeCache.txt ]; then
  CC=clang-14 CXX=clang++-14 cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVOLSTYLE_FUZZ=ON "${launcher[@]}"
fi
cmake --build build-fuzz -j"$(nproc)"

export ASAN_OPTIONS="detect_leaks=0:allocator_may_return_null=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$PWD/tests/sanitizers/ubsan.supp:${UBSAN_OPTIONS:-}"
run_one() {
  local name="$1" work="build-fuzz/work/$1" art="build-fuzz/artifacts/$1/"
  rm -rf "$work" "$art"  # this run's findings only; the corpus below is what persists
  mkdir -p "$work" "$art"
  # Fork mode keeps going past a crash (OpenVDB's own bugs would otherwise end the vdb run at once).
  build-fuzz/bin/fuzz_"$name" "$work" "tests/fuzz/corpus/$name" -fork=1 -ignore_crashes=1 -ignore_ooms=1 \
    -ignore_timeouts=1 -max_total_time="$seconds" -rss_limit_mb=4096 -timeout=20 -max_len=65536 \
    -artifact_prefix="$art" > "build-fuzz/$name.log" 2>&1 || true
  # New coverage into the committed corpus (minimised: only inputs that add features).
  build-fuzz/bin/fuzz_"$name" -merge=1 "tests/fuzz/corpus/$name" "$work" > "build-fuzz/$name.merge.log" 2>&1 || true
}
pids=()
for name in "${harnesses[@]}"; do
  [ "$seconds" != 0 ] || break  # 0: only the report of the last run
  run_one "$name" &
  pids+=($!)
  if [ ${#pids[@]} -ge "$(nproc)" ]; then wait "${pids[0]}"; pids=("${pids[@]:1}"); fi
done
wait

# A crash input is ours unless the first frame of its stack outside the runtimes lies in a
# library (OpenVDB and its TBB/Blosc, OpenImageIO, OpenEXR); slow units are listed, not crashes.
status=0
printf '| harness | seconds | executions | exec/s | cov | ft | corpus | oom/timeout/crash | crash inputs in our code | in libraries | slow units |\n|---|---|---|---|---|---|---|---|---|---|---|\n'
for name in "${harnesses[@]}"; do
  line=$(grep -E '^#[0-9]+: cov:' "build-fuzz/$name.log" | tail -1 || true)
  execs=$(sed -E 's/^#([0-9]+):.*/\1/' <<<"$line")
  cov=$(sed -E 's/.* cov: ([0-9]+).*/\1/' <<<"$line")
  ft=$(sed -E 's/.* ft: ([0-9]+).*/\1/' <<<"$line")
  rate=$(sed -E 's/.* exec\/s:? ([0-9]+).*/\1/' <<<"$line")
  fails=$(sed -E 's/.* oom\/timeout\/crash: ([0-9]+\/[0-9]+\/[0-9]+).*/\1/' <<<"$line")
  corpus=$(find "tests/fuzz/corpus/$name" -type f | wc -l)
  ours=0 theirs=0 slow=0
  for crash in build-fuzz/artifacts/"$name"/*; do
    [ -f "$crash" ] || continue
    case "$(basename "$crash")" in slow-unit-*) slow=$((slow + 1)); continue ;; esac
    report=$(build-fuzz/bin/fuzz_"$name" -artifact_prefix=build-fuzz/replay- -rss_limit_mb=4096 -malloc_limit_mb=4096 -timeout=30 "$crash" 2>&1 || true)
    # The first frame outside the sanitizer and fuzzer runtimes, libc and libstdc++ decides.
    first=$(grep -E '^ +#[0-9]+ ' <<<"$report" |
      grep -vE '__sanitizer|fuzzer::|__asan|__ubsan|__interceptor|in (memcpy|memmove|memset|malloc|calloc|realloc|free|operator new|operator delete)|libstdc\+\+|libc\.so|ld-linux|nptl/|signal/|stdlib/abort|in (raise|abort|__pthread_kill)' |
      head -1 || true)
    if grep -qiE 'openvdb|tbb|blosc|OpenImageIO|OpenEXR|Imf_|Iex|libtiff|libpng|libjpeg|assimp|Assimp' <<<"$first"; then
      theirs=$((theirs + 1))
    else
      ours=$((ours + 1))
      echo "crash in our code: $crash (${first:-no stack})" >&2
    fi
  done
  [ "$ours" -eq 0 ] || status=1
  printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' "$name" "$seconds" "${execs:-?}" "${rate:-?}" \
    "${cov:-?}" "${ft:-?}" "$corpus" "${fails:-?}" "$ours" "$theirs" "$slow"
done
exit $status
