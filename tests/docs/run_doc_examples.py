#!/usr/bin/env python3
"""Runs every example in README.md and docs/*.md, so the docs cannot rot (issue #10).

Fenced blocks are examples by their language:
  sh      run with bash -e -o pipefail, in a scratch folder that sees the repository's docs/, a copy
          of its clients/ and the build's bin/ as build/bin (so `build/bin/volstyle ...`,
          `docs/examples/...` and `pip install ./clients/python` work as written);
  json    must parse;
  python  run with python3 in the same folder, the clients' packages importable (as installed).
A block whose text uses the API ($H, http://127.0.0.1:8080) gets a fresh `volstyle serve` on a free
port, substituted for 8080, and curl that fails on HTTP errors (--fail-with-body). A block preceded
by `<!-- docs-test: skip (reason) -->` is listed as skipped with its reason; blocks without a
language (diagrams) are not examples.

usage: run_doc_examples.py REPO_DIR BIN_DIR
"""
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile
import time

FENCE = re.compile(r"^```(\w*)\s*$")
SKIP = re.compile(r"<!--\s*docs-test:\s*skip\s*\((.*)\)\s*-->")


def blocks(path):
    """(line, language, text, skip reason or None) of every fenced block."""
    lines = path.read_text().splitlines()
    out, i = [], 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        start, lang = i, m.group(1)
        j = i + 1
        while j < len(lines) and not lines[j].startswith("```"):
            j += 1
        skip = SKIP.search(lines[start - 1]) if start > 0 else None
        out.append((start + 1, lang, "\n".join(lines[start + 1:j]), skip.group(1) if skip else None))
        i = j + 1
    return out


def start_server(binary, work):
    log = open(work / "server.log", "w+")
    proc = subprocess.Popen([str(binary), "serve", "--port", "0", "--data-dir", str(work / "server-data")],
                            stdout=log, stderr=subprocess.STDOUT)
    deadline = time.time() + 60
    while time.time() < deadline:
        log.seek(0)
        m = re.search(r"serving http://127\.0\.0\.1:(\d+)/", log.read())
        if m:
            return proc, int(m.group(1))
        if proc.poll() is not None:
            break
        time.sleep(0.1)
    proc.kill()
    log.seek(0)
    raise RuntimeError("the server did not start:\n" + log.read())


def run_block(lang, text, work, binary):
    if lang == "json":
        json.loads(text)
        return
    uses_api = "$H" in text or "127.0.0.1:8080" in text
    server = None
    try:
        prelude = ""
        if uses_api:
            server, port = start_server(binary, work)
            text = text.replace("127.0.0.1:8080", "127.0.0.1:%d" % port)
            prelude = 'curl() { command curl --fail-with-body -sS "$@"; }\n'
        if lang == "python":
            env = dict(os.environ, PYTHONPATH=os.pathsep.join(str(work / "clients" / c) for c in ("python", "houdini")))
            result = subprocess.run(["python3", "-c", text], cwd=work, capture_output=True, text=True, timeout=900, env=env)
        else:
            script = "set -eo pipefail\n" + prelude + text + "\n"
            result = subprocess.run(["bash", "-c", script], cwd=work, capture_output=True, text=True, timeout=900)
        if result.returncode != 0:
            raise RuntimeError("exit status %d\n--- stdout\n%s\n--- stderr\n%s" %
                               (result.returncode, result.stdout[-3000:], result.stderr[-3000:]))
    finally:
        if server:
            server.terminate()
            server.wait(timeout=30)


def main():
    repo, bin_dir = pathlib.Path(sys.argv[1]).resolve(), pathlib.Path(sys.argv[2]).resolve()
    files = [repo / "README.md"] + sorted((repo / "docs").glob("*.md"))
    ran, skipped, failed = 0, [], []
    for path in files:
        for line, lang, text, skip in blocks(path):
            if lang not in ("sh", "bash", "json", "python"):
                continue
            where = "%s:%d" % (path.relative_to(repo), line)
            if skip:
                skipped.append((where, skip))
                continue
            work = pathlib.Path(tempfile.mkdtemp(prefix="volstyle-docs-"))
            try:
                (work / "build").mkdir()
                os.symlink(bin_dir, work / "build" / "bin")
                os.symlink(repo / "docs", work / "docs")
                shutil.copytree(repo / "clients", work / "clients", ignore=shutil.ignore_patterns("__pycache__"))
                t0 = time.time()
                run_block(lang, text, work, bin_dir / "volstyle")
                ran += 1
                print("ok    %-28s %-6s %5.1f s" % (where, lang, time.time() - t0), flush=True)
            except Exception as e:  # noqa: BLE001 - report every failing block, then fail
                failed.append(where)
                print("FAIL  %s (%s)\n%s" % (where, lang, e), flush=True)
            finally:
                shutil.rmtree(work, ignore_errors=True)
    for where, reason in skipped:
        print("skip  %-28s %s" % (where, reason))
    print("%d examples ran, %d failed, %d skipped" % (ran + len(failed), len(failed), len(skipped)))
    return 1 if failed or ran == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
