#!/usr/bin/env python3
"""Every rename that acknowledges a write is followed by an fsync of its folder (issue #36,
"Durability"), and every folder it creates is followed by an fsync of the folder above it (the
new folder's entry lives there): runs `volstyle serve` under strace, makes writes of every kind the data directory
holds (a session, a view and its target image, the lighting, a mesh, an uploaded volume version, a
frame, a job record), stops the server, and reads the trace: after each rename into the data
directory, the same thread must fsync the target's folder before its next rename.
  python3 rename_fsync_trace.py BUILD/bin/volstyle
"""
import http.client
import json
import os
import re
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
import zlib

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'probe'))
import hostile_files as hf  # noqa: E402


def png(width, height, rgba):
    rows = b''.join(b'\0' + bytes(rgba) * width for _ in range(height))
    chunk = lambda kind, data: struct.pack('>I', len(data)) + kind + data + struct.pack('>I', zlib.crc32(kind + data) & 0xffffffff)
    return (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', width, height, 8, 6, 0, 0, 0)) +
            chunk(b'IDAT', zlib.compress(rows)) + chunk(b'IEND', b''))


def children(pid):
    """The processes whose parent is `pid` (from /proc)."""
    out = []
    for entry in os.listdir('/proc'):
        if entry.isdigit():
            try:
                stat = open('/proc/%s/stat' % entry).read()
                if int(stat[stat.rindex(')') + 2:].split()[1]) == pid:
                    out.append(int(entry))
            except (OSError, ValueError):
                pass
    return out


def main():
    binary = os.path.abspath(sys.argv[1])
    if not shutil.which('strace'):
        print('FAIL: strace is not installed (scripts/install_deps.sh installs it)')
        return 1
    work = tempfile.mkdtemp()
    data, trace, log = os.path.join(work, 'data'), os.path.join(work, 'trace.txt'), os.path.join(work, 'server.log')
    server = subprocess.Popen(['strace', '-f', '--seccomp-bpf', '-y', '-qq', '-e', 'trace=rename,renameat,renameat2,fsync,mkdir,mkdirat', '-o', trace,
                               binary, 'serve', '--port', '0', '--data-dir', data, '--web-dir', work],
                              stdout=open(log, 'w'), stderr=subprocess.STDOUT)
    try:
        port = None
        for _ in range(300):
            m = re.search(r'serving http://127\.0\.0\.1:(\d+)/', open(log).read())
            if m:
                port = int(m.group(1))
                break
            time.sleep(0.1)
        if not port:
            print('FAIL: the server did not start under strace:\n' + open(log).read())
            return 1

        def call(method, path, body=None, kind='application/json'):
            c = http.client.HTTPConnection('127.0.0.1', port, timeout=120)
            if isinstance(body, (dict, list)):
                body = json.dumps(body).encode()
            c.request(method, '/api/v1' + path, body=body, headers={'Content-Type': kind} if body is not None else {})
            r = c.getresponse()
            out = r.read()
            if r.status >= 300:
                raise RuntimeError('%s %s: %d %s' % (method, path, r.status, out[:200]))
            return out

        t0 = time.monotonic()
        sid = json.loads(call('POST', '/sessions', {'scene': 'builtin:cloud', 'resolution': 16}))['id']
        base = '/sessions/' + sid
        vid = json.loads(call('POST', base + '/views', {'camera': {'eye': [0, 0, 3], 'target': [0, 0, 0], 'width': 8, 'height': 8}}))['id']
        call('PUT', base + '/views/%s/target' % vid, png(8, 8, [128, 100, 80, 255]), 'image/png')
        call('PUT', base + '/lighting', json.loads(call('GET', base + '/lighting')))
        call('PUT', base + '/stylizer/occluders/tri', hf.gltf_triangle(), 'application/octet-stream')
        vdb = call('GET', base + '/volume.vdb')
        call('PUT', base + '/volume', vdb, 'application/octet-stream')
        call('PUT', base + '/frames/0', vdb, 'application/octet-stream')
        job = json.loads(call('POST', base + '/solve', {'max_iterations': 1}))['job']
        for _ in range(600):
            if json.loads(call('GET', '/jobs/' + job))['state'] not in ('queued', 'running'):
                break
            time.sleep(0.1)
        print('[ measured ] writes made in %.1f s' % (time.monotonic() - t0))
    finally:
        t1 = time.monotonic()
        # The server is strace's child: stop it (strace leaves with it).
        for pid in children(server.pid):
            os.kill(pid, signal.SIGTERM)
        try:
            server.wait(60)
        except subprocess.TimeoutExpired:
            server.kill()
        print('[ measured ] the server stopped %.1f s after SIGTERM' % (time.monotonic() - t1))
    # 1234  rename("/d/sessions/x/session.json.tmp-1a2b3c4d", "/d/sessions/x/session.json") = 0
    # 1234  fsync(7</d/sessions/x>) = 0
    rename = re.compile(r'^(\d+)\s+rename(?:at2?)?\(.*"([^"]+)"(?:, \w+)?\)\s+= 0')
    fsync = re.compile(r'^(\d+)\s+fsync\(\d+<([^>]+)>\)\s+= 0')
    pending, checked, missing = {}, 0, []
    for line in open(trace):
        m = rename.match(line)
        if m:
            tid, target = m.group(1), m.group(2)
            if tid in pending:
                missing.append(pending.pop(tid))
            # A rename into a temporary name (a library writing its own temporary, as OpenVDB's
            # writer does inside ours) acknowledges nothing; the rename into place does.
            if target.startswith(data + '/') and '.tmp-' not in os.path.basename(target):
                pending[tid] = target
                checked += 1
            continue
        m = fsync.match(line)
        if m and m.group(1) in pending and m.group(2) == os.path.dirname(pending[m.group(1)]):
            del pending[m.group(1)]
    missing += pending.values()
    # 1234  mkdir("/d/sessions/x", 0777) = 0  (or mkdirat(AT_FDCWD, "/d/…", 0777) = 0)
    mkdir = re.compile(r'^(\d+)\s+mkdir(?:at)?\((?:AT_FDCWD[^,]*, )?"([^"]+)"')
    made, unsynced = 0, []
    for line in open(trace):
        m = mkdir.match(line)
        if m and line.rstrip().endswith('= 0') and m.group(2).startswith(data):
            unsynced.append((m.group(1), m.group(2).rstrip('/')))
            made += 1
            continue
        m = fsync.match(line)
        if m:
            unsynced = [(tid, d) for tid, d in unsynced if not (tid == m.group(1) and os.path.dirname(d) == m.group(2))]
    shutil.rmtree(work, ignore_errors=True)
    print('[ measured ] %d folders created in the data directory, %d without an fsync of the folder above them' % (made, len(unsynced)))
    for _, folder in unsynced[:10]:
        print('FAIL: no fsync of the folder above the new folder ' + folder)
    if unsynced:
        return 1
    print('[ measured ] %d renames into the data directory, %d without an fsync of their folder after them' % (checked, len(missing)))
    for target in missing[:10]:
        print('FAIL: no fsync of the folder after the rename into ' + target)
    if checked < 8:
        print('FAIL: only %d renames traced; the writes above make at least 8' % checked)
        return 1
    return 1 if missing else 0


if __name__ == '__main__':
    sys.exit(main())
