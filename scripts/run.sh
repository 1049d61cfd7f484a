#!/usr/bin/env bash
# The main job: installs what is missing, builds Release into build/, and starts the server on
# 127.0.0.1:8080 (data in ./volstyle-data). Open the printed URL: the page starts with the built-in
# cloud ready to paint. Ctrl-C stops the server cleanly.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
echo "volstyle: open http://127.0.0.1:8080/ in a browser (Ctrl-C to stop)"
exec build/bin/volstyle serve --host 127.0.0.1 --port 8080 --data-dir volstyle-data --web-dir web
