#!/usr/bin/env bash
# Packs what a check on a GPU machine needs into .device-bundle/ (git-ignored, about 9 MB): the GL
# tests that need no file libraries (gl_tests_device) and the GL benchmarks, the three small
# libraries they link beside libc and libstdc++ (spdlog, fmt, epoxy; turbojpeg for live frames), glvnd's EGL/GL loaders as
# Debian packages (for a machine that has the NVIDIA driver but no libEGL.so.1), and
# device_check.sh, which runs it all there. Build first (scripts/build.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
build="${VOLSTYLE_BUILD_DIR:-build}"
binaries=(gl_tests_device stylizer_bench render_bench translucent_bench lights_bench)
cmake --build "$build" -j"$(nproc)" --target "${binaries[@]}"
out=.device-bundle
rm -rf "$out"
mkdir -p "$out/bin" "$out/lib" "$out/deb"
for b in "${binaries[@]}"; do cp "$build/bin/$b" "$out/bin/"; done
# Every library the binaries need beyond the C and C++ runtimes travels with them; anything
# else (OpenImageIO, OpenVDB…) would mean a binary picked up a dependency it should not have.
for b in "${binaries[@]}"; do
  if ldd "$out/bin/$b" | grep -q "not found"; then echo "device_bundle: $b has libraries ldd cannot find" >&2; exit 1; fi
  ldd "$out/bin/$b" | awk '/=> \//{print $1, $3}' | while read -r name path; do
    case "$name" in
      libc.so*|libm.so*|libdl.so*|libpthread.so*|librt.so*|libgcc_s.so*|libstdc++.so*|ld-linux*) ;;
      libspdlog.so*|libfmt.so*|libepoxy.so*|libturbojpeg.so*) cp -Lu "$path" "$out/lib/$name" ;;
      *) echo "device_bundle: $b needs $name, which does not travel; only spdlog, fmt, epoxy and turbojpeg may" >&2; exit 1 ;;
    esac
  done
done
(cd "$out/deb" && apt-get -o APT::Sandbox::User=root download libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2 >/dev/null) ||
  echo "device_bundle: could not download glvnd's packages; the GPU machine must have libEGL.so.1" >&2
cp scripts/device_check.sh "$out/"
du -sh "$out"
echo "bundle ready: on the GPU machine run 'bash $out/device_check.sh' from the repository root"
