#!/usr/bin/env bash
# Installs the Debian packages volstyle builds and runs with, only those that are missing.
# Idempotent: a second run installs nothing. Needs root (or sudo) when something is missing.
set -euo pipefail

packages=(
  build-essential cmake pkg-config ccache
  libegl-dev libepoxy-dev libegl-mesa0 libgl1-mesa-dri   # headless GL: EGL + Mesa llvmpipe
  libopenvdb-dev libboost-iostreams-dev libtbb-dev         # OpenVDB (FindOpenVDB needs boost-iostreams)
  libnanovdb-dev                                           # NanoVDB and PNanoVDB.h (bench/sparse_sampling, issue #39)
  libopenimageio-dev                                       # images (found with pkg-config)
  libturbojpeg0-dev                                        # live frames as JPEG without a file round trip (issue #40)
  libassimp-dev                                            # occluder meshes: OBJ, PLY, glTF (pkg-config)
  libspdlog-dev libfmt-dev nlohmann-json3-dev libcpp-httplib-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  chromium                                                 # the browser end-to-end test
  ffmpeg                                                   # stylizer sequences as video files
  python3 iproute2 strace                                  # the hostile probe; ss reads a listen backlog; strace traces fsyncs in a test
  python3-venv python3-setuptools python3-wheel            # the Python client, pip-installed into a fresh venv offline
  python3-numpy                                            # the client's fast EXR path (Blender's and Houdini's Pythons have numpy)
  blender xvfb xauth                                       # the Blender add-on's tests (headless, and one in a window under Xvfb)
  postgresql libpqxx-dev haproxy                           # serve --store postgresql://… and the cluster tests (issue #41)
)
packages+=("$@")  # extra packages a script needs (scripts/fuzz.sh: clang)
# Node and npm for the browser test: the machine's own if present (Debian's would clash with it).
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then packages+=(nodejs npm); fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "install_deps: installing ${missing[*]}" >&2
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
