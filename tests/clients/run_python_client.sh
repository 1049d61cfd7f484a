#!/usr/bin/env bash
# The Python client package (clients/python) as a user installs it: a fresh venv (Debian's python3
# and its setuptools, no network), `pip install` of a copy of the package, then its tests — the
# camera and EXR helpers alone, and the rest (and the Houdini recipe's, clients/houdini) against
# a live server started with a token and a 1 MiB upload limit (tests/web/with_server.sh). Usage: run_python_client.sh VOLSTYLE_BINARY
set -euo pipefail
binary=$(realpath "$1")
root=$(cd "$(dirname "$0")/../.." && pwd)
python=/usr/bin/python3
if ! "$python" -c 'import venv, ensurepip' 2>/dev/null; then
  echo "needs Debian's python3-venv (scripts/install_deps.sh installs it)"
  exit 1
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp -r "$root/clients/python" "$work/src"  # pip builds in the source folder: keep the checkout clean
"$python" -m venv --system-site-packages "$work/venv"
"$work/venv/bin/pip" install --quiet --no-index --no-build-isolation "$work/src"
cd "$work"  # import the installed package, not the source
"$work/venv/bin/python" -m unittest discover -s "$root/clients/python/tests" -p 'test_camera.py' -v
export VOLSTYLE_TOKEN=client-test-token
VOLSTYLE_SERVE_ARGS="--token $VOLSTYLE_TOKEN --max-upload-mib 1" \
  bash "$root/tests/web/with_server.sh" "$binary" bash -c "
    '$work/venv/bin/python' -m unittest discover -s '$root/clients/python/tests' -p 'test_live_server.py' -v &&
    '$work/venv/bin/python' -m unittest discover -s '$root/clients/houdini/tests' -v  # the Houdini recipe's logic"
# The documented pipeline example (docs/CLIENTS.md), as a user runs it.
bash "$root/tests/web/with_server.sh" "$binary" bash -c \
  "'$work/venv/bin/python' '$root/docs/examples/pipeline.py' --url \"\$VOLSTYLE_URL\" --size 48 -o '$work/solved.vdb' && '$binary' info '$work/solved.vdb' | grep -q emission && echo 'pipeline example: passed'"
