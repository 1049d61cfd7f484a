#!/usr/bin/env bash
# Builds the Blender add-on zip: clients/blender/volstyle_blender with the Python client
# (clients/python/volstyle_client) inside it, so the add-on needs nothing else.
# Usage: build_addon.sh [OUT.zip] (default build/clients/volstyle_blender.zip)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out=$(realpath -m "${1:-$root/build/clients/volstyle_blender.zip}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp -r "$root/clients/blender/volstyle_blender" "$work/"
cp -r "$root/clients/python/volstyle_client" "$work/volstyle_blender/"
find "$work" -name __pycache__ -prune -exec rm -rf {} +
mkdir -p "$(dirname "$out")"
rm -f "$out"
(cd "$work" && python3 -m zipfile -c "$out" volstyle_blender)
echo "$out"
