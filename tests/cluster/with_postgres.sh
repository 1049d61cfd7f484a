#!/usr/bin/env bash
# with_postgres.sh COMMAND… — starts a private PostgreSQL (Debian's postgresql-15 binaries) in a
# fresh folder, listening on 127.0.0.1 at a free port only (no Unix socket outside that folder,
# trust authentication for the local test user), runs COMMAND with VOLSTYLE_TEST_STORE set to its
# URL (postgresql://postgres@127.0.0.1:PORT/postgres), then stops it and removes the folder.
# PostgreSQL refuses to run as root: as root it runs as the `postgres` user the package made.
set -euo pipefail
bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1)
if [ -z "$bin" ] || [ ! -x "$bin/initdb" ]; then
  echo "with_postgres.sh: no PostgreSQL server binaries (scripts/install_deps.sh installs postgresql)" >&2
  exit 1
fi
dir=$(mktemp -d /tmp/volstyle-pg.XXXXXX)
as=()
if [ "$(id -u)" -eq 0 ]; then
  chown postgres: "$dir"
  as=(runuser -u postgres --)
fi
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
cleanup() {
  rc=$?
  set +e
  "${as[@]}" "$bin/pg_ctl" -D "$dir/data" -m immediate stop > /dev/null 2>&1
  [ $rc -eq 0 ] || { echo "--- the PostgreSQL log (last 20 lines):"; tail -n 20 "$dir/log" 2>/dev/null; }
  rm -rf "$dir"
  exit $rc
}
trap cleanup EXIT
"${as[@]}" "$bin/initdb" -D "$dir/data" -U postgres --auth=trust --no-sync -E UTF8 > "$dir/initdb.log" 2>&1 ||
  { cat "$dir/initdb.log"; exit 1; }
# fsync stays on: the store's promise (acknowledged = committed) is what the tests check.
"${as[@]}" "$bin/pg_ctl" -D "$dir/data" -l "$dir/log" -w -t 60 \
  -o "-c listen_addresses=127.0.0.1 -p $port -k $dir -c max_connections=200" start > /dev/null
export VOLSTYLE_TEST_STORE="postgresql://postgres@127.0.0.1:$port/postgres"
export VOLSTYLE_TEST_PG_BIN="$bin"
"$@"
