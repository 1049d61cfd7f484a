#!/usr/bin/env bash
# The main job: installs what is missing, builds Release into build/, renders the built-in cloud
# to out/cloud.png and prints its path.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
mkdir -p out
build/bin/volstyle render --scene builtin:cloud:128 --camera docs/examples/camera.json \
    --lighting docs/examples/lighting.json -o out/cloud.png
echo "$(pwd)/out/cloud.png"
