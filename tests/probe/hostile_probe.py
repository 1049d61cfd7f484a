#!/usr/bin/env python3
"""The hostile-input probe of issue #35, against a running `volstyle serve` (tests/web/with_server.sh
starts one: VOLSTYLE_URL, VOLSTYLE_SERVER_PID). Every case must get exactly one answer with the
SPEC error body and the expected status; the server must stay up; its peak RSS is printed and
bounded. Exits 1 on any failure.
  python3 hostile_probe.py [--rss-limit-mib 4096]
"""
import http.client
import json
import os
import socket
import statistics
import sys
import threading
import time
import urllib.parse

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hostile_files as hf  # noqa: E402

ROOT = os.environ.get('VOLSTYLE_ROOT', os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
URL = urllib.parse.urlparse(os.environ['VOLSTYLE_URL'])
HOST, PORT = URL.hostname, URL.port
PID = int(os.environ.get('VOLSTYLE_SERVER_PID', '0'))
SESSION_MIB = int(os.environ.get('VOLSTYLE_PROBE_SESSION_MIB', '64'))
RSS_LIMIT_MIB = float(sys.argv[sys.argv.index('--rss-limit-mib') + 1]) if '--rss-limit-mib' in sys.argv else 4096
failures = []
cases = 0
earlier_peaks = []  # VmHWM before each reset


def fail(message):
    failures.append(message)
    print('FAIL: ' + message, flush=True)


def request(method, path, body=None, content_type='application/json', timeout=120):
    c = http.client.HTTPConnection(HOST, PORT, timeout=timeout)
    try:
        if isinstance(body, (dict, list)):
            body = json.dumps(body).encode()
        c.request(method, path, body=body, headers={'Content-Type': content_type} if body is not None else {})
        r = c.getresponse()
        data = r.read()
        return r.status, data, dict(r.getheaders())
    finally:
        c.close()


def expect(name, method, path, body, status, code=None, content_type='application/json', seconds=None):
    """One request: its status and, for errors, the SPEC body with `code`."""
    global cases
    cases += 1
    t0 = time.monotonic()
    try:
        got, data, _ = request(method, path, body, content_type)
    except Exception as e:  # a reset, a time-out: no answer
        fail('%s: no answer (%s)' % (name, e))
        return None
    took = time.monotonic() - t0
    detail = data[:300].decode('utf-8', 'replace')
    if got != status:
        fail('%s: HTTP %d, expected %d: %s' % (name, got, status, detail))
    elif status >= 400:
        try:
            err = json.loads(data)['error']
            if code and err['code'] != code:
                fail('%s: code %s, expected %s: %s' % (name, err['code'], code, err['message']))
            print('  ok  %-46s %d %-18s %6.2f s  %s' % (name, got, err['code'], took, err['message'][:110]), flush=True)
        except Exception:
            fail('%s: the body is not the SPEC error body: %s' % (name, detail))
    else:
        print('  ok  %-46s %d %6.2f s' % (name, got, took), flush=True)
    if seconds and took > seconds:
        fail('%s: took %.1f s (over %.0f s)' % (name, took, seconds))
    return data


def raw(data, timeout=15):
    """Sends bytes on a fresh connection and reads until the server closes it."""
    s = socket.create_connection((HOST, PORT), timeout=timeout)
    try:
        s.sendall(data)
    except OSError:
        pass  # the server may answer and close before reading everything
    out = b''
    try:
        while True:
            chunk = s.recv(65536)
            if not chunk:
                break
            out += chunk
    except OSError as e:
        out += b'\n<error: %s>' % str(e).encode()
    s.close()
    return out


def expect_one_answer(name, data, status):
    global cases
    cases += 1
    answer = raw(data)
    lines = [l for l in answer.split(b'\r\n') if l.startswith(b'HTTP/1.')]
    statuses = [int(l.split()[1]) for l in lines]
    if statuses != [status]:
        fail('%s: status lines %s, expected one %d' % (name, statuses, status))
        return
    body = answer.split(b'\r\n\r\n', 1)[1]
    try:
        err = json.loads(body)['error']
        print('  ok  %-46s %d %-18s one answer, closed  %s' % (name, status, err['code'], err['message'][:90]), flush=True)
    except Exception:
        fail('%s: not the SPEC body: %r' % (name, body[:200]))


def peak_rss_mib():
    if not PID:
        return None
    with open('/proc/%d/status' % PID) as f:
        for line in f:
            if line.startswith('VmHWM:'):
                return int(line.split()[1]) / 1024.0
    return None


def reset_peak_rss():
    """Resets the server's VmHWM (Linux: 5 > /proc/PID/clear_refs); False where that is refused.
    The peak so far is kept for the probe's whole-run figure."""
    before = peak_rss_mib()
    if before is not None:
        earlier_peaks.append(before)
    try:
        with open('/proc/%d/clear_refs' % PID, 'w') as f:
            f.write('5')
        return True
    except OSError:
        return False


def health():
    status, _, _ = request('GET', '/api/v1/health', timeout=30)
    return status


def new_session(resolution=16):
    status, data, _ = request('POST', '/api/v1/sessions', {'scene': 'builtin:cloud', 'resolution': resolution})
    assert status == 201, data
    return json.loads(data)['id']


def meshes(base):
    print('meshes (read in the child process; checked before assimp sees them):')
    occ = base + '/stylizer/occluders/'
    expect('glTF triangle', 'PUT', occ + 'tri', hf.gltf_triangle(), 200)
    expect('GLB triangle', 'PUT', occ + 'glbtri', hf.glb_triangle(), 200)
    for depth in (10000, 20000, 50000, 200000):
        expect('glTF nodes nested %d deep' % depth, 'PUT', occ + 'deep', hf.gltf_chain(depth), 413, 'too_large', seconds=10)
    expect('glTF 24 levels each referenced twice', 'PUT', occ + 'bomb', hf.gltf_doubling(24), 413, 'too_large', seconds=5)
    expect('glTF 60 levels each referenced twice', 'PUT', occ + 'bomb', hf.gltf_doubling(60), 413, 'too_large', seconds=5)
    expect('glTF nodes in a cycle', 'PUT', occ + 'cycle', hf.gltf_cycle(), 422, 'unsupported_media')
    expect('glTF JSON nested 100000 deep', 'PUT', occ + 'json', hf.gltf_deep_json(100000), 422, 'unsupported_media')
    expect('PLY, CR only, 3M vertices in ~200 bytes', 'PUT', occ + 'ply', hf.ply(3000000, '\r'), 422, 'unsupported_media')
    expect('PLY declaring 10^9 vertices', 'PUT', occ + 'ply', hf.ply(10 ** 9), 413, 'too_large')
    expect('PLY declaring 2^64+10^9 vertices', 'PUT', occ + 'ply', hf.ply(2 ** 64 + 10 ** 9), 413, 'too_large')
    expect('PLY, CR only, declaring 2^64+10^9', 'PUT', occ + 'ply', hf.ply(2 ** 64 + 10 ** 9, '\r'), 413, 'too_large')
    expect('PLY triangle, CR only', 'PUT', occ + 'plytri', hf.ply(3, '\r'), 200)
    for name in ('assimp-ply-abort.ply', 'assimp-ply-body-abort.ply'):  # found by fuzz_mesh_ply: each aborted assimp
        expect('PLY that aborted assimp: ' + name, 'PUT', occ + 'abort',
               open(os.path.join(ROOT, 'tests/data/hostile', name), 'rb').read(), 422, 'unsupported_media')
    expect('GLB length 0xFFFFFFFF', 'PUT', occ + 'glb', hf.glb_triangle(length=0xFFFFFFFF), 422, 'unsupported_media')
    expect('GLB buffer byteLength 2^40', 'PUT', occ + 'glb', hf.glb_triangle(byte_length=2 ** 40), 422, 'unsupported_media')
    expect('GLB requiring KHR_draco_mesh_compression', 'PUT', occ + 'glb',
           hf.glb_triangle(extra={'extensionsUsed': ['KHR_draco_mesh_compression'],
                                  'extensionsRequired': ['KHR_draco_mesh_compression']}), 422, 'unsupported_media')
    expect('glTF buffer in another file', 'PUT', occ + 'ext',
           hf.gltf_triangle().replace(b'data:application/octet-stream;base64,', b'../../etc/passwd#'), 422, 'unsupported_media')
    status, data, _ = request('GET', base + '/stylizer/occluders')
    listed = json.loads(data) if status == 200 else []
    names = sorted(m['name'] for m in (listed['meshes'] if isinstance(listed, dict) else listed))
    if names != ['glbtri', 'plytri', 'tri']:
        fail('only the three good meshes are stored, got %s' % names)


def framing():
    print('framing (one answer per request, then the connection closes):')
    expect_one_answer('method FOO', b'FOO /api/v1/health HTTP/1.1\r\nHost: x\r\nA: b\r\nB: c\r\n\r\n', 400)
    expect_one_answer('a garbage request line', b'\x01\x02 garbage\r\nHost: x\r\nA: b\r\n\r\n', 400)
    expect_one_answer('a 100 KB header', b'GET /api/v1/health HTTP/1.1\r\nHost: x\r\nX: ' + b'a' * 100000 + b'\r\n\r\n', 431)
    expect_one_answer('150 short headers', b'GET /api/v1/health HTTP/1.1\r\n' + b''.join(b'X-%d: y\r\n' % i for i in range(150)) + b'\r\n', 431)
    expect_one_answer('5,000 headers', b'GET /api/v1/health HTTP/1.1\r\n' + b''.join(b'X-%d: y\r\n' % i for i in range(5000)) + b'\r\n', 431)
    expect_one_answer('a header line without a colon', b'GET /api/v1/health HTTP/1.1\r\nHost: x\r\nnonsense\r\n\r\n', 400)
    expect_one_answer('/index.html%00.png', b'GET /index.html%00.png HTTP/1.1\r\nHost: x\r\n\r\n', 400)
    expect_one_answer('%2f inside an id', b'GET /api/v1/sessions/ab%2fcd HTTP/1.1\r\nHost: x\r\n\r\n', 400)
    expect_one_answer('a 20 KB request target', b'GET /api/v1/' + b'a' * 20000 + b' HTTP/1.1\r\nHost: x\r\n\r\n', 414)
    expect_one_answer('HTTP/2.0 on a text line', b'GET /api/v1/health HTTP/2.0\r\nHost: x\r\n\r\n', 400)
    # A good request on the same connection after a good one still works (keep-alive intact).
    answer = raw(b'GET /api/v1/health HTTP/1.1\r\nHost: x\r\n\r\nGET /api/v1/health HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n')
    if answer.count(b'HTTP/1.1 200') != 2:
        fail('two pipelined health checks get two 200s, got %r' % answer[:200])


def values(base):
    print('values at the door:')
    v = json.loads(request('POST', base + '/views', {'camera': {'eye': [0, 0, 3], 'target': [0, 0, 0], 'width': 8, 'height': 8}})[1])['id']
    expect('render.png?exposure=1e308', 'GET', base + '/views/%s/render.png?exposure=1e308' % v, None, 400, 'invalid_argument')
    expect('render "exposure": 1e308', 'POST', base + '/render',
           {'camera': {'eye': [0, 0, 3], 'target': [0, 0, 0], 'width': 8, 'height': 8}, 'exposure': 1e308}, 400, 'invalid_argument')
    expect('solve "views": []', 'POST', base + '/solve', {'views': []}, 400, 'invalid_argument')
    expect('solve "lights": {"lobes": 0}', 'POST', base + '/solve', {'unknowns': ['lights'], 'lights': {'lobes': 0}}, 400, 'invalid_argument')
    expect('solve "lights": {"lobes": 257}', 'POST', base + '/solve', {'unknowns': ['lights'], 'lights': {'lobes': 257}}, 400, 'invalid_argument')


def budgets(base):
    print('budgets (estimated before the GL thread is held):')
    cam = {'eye': [0, 0, 3], 'target': [0, 0, 0], 'width': 4096, 'height': 4096}
    expect('translucent 4096², light buffer 4096, slice 0.05', 'POST', base + '/render',
           {'camera': cam, 'mode': 'translucent', 'translucent': {'light_buffer': 4096, 'slice_spacing': 0.05}}, 422, 'over_budget', seconds=5)
    reset = reset_peak_rss()
    expect('stylizer/pick with a 4096² camera', 'POST', base + '/stylizer/pick',
           {'x': 2048, 'y': 2048, 'camera': {'eye': [0, 3, 12], 'target': [0, 3, 0], 'width': 4096, 'height': 4096}}, 200, seconds=120)
    if reset:
        print('[ measured ] the server\'s peak RSS during a 4096² pick: %.0f MiB' % peak_rss_mib())


def frames():
    """Frames are charged by their decoded size: a session fills its budget, gets 507 naming it,
    and a deleted frame makes room again; a frames/render job stops within a chunk of a cancel."""
    print('frames (charged by decoded size; the probe serves with --session-memory-mib %d):' % SESSION_MIB)
    base = '/api/v1/sessions/' + new_session(64)
    status, vdb, _ = request('GET', base + '/volume.vdb')
    if status != 200:
        fail('GET volume.vdb: %d' % status)
        return
    stored = 0
    for n in range(400):
        status, data, _ = request('PUT', base + '/frames/%d' % n, vdb, 'application/octet-stream')
        if status == 507:
            err = json.loads(data)['error']
            print('  ok  %-46s 507 %-18s after %d frames  %s' % ('frames until the session budget', err['code'], stored, err['message'][:100]))
            if err['code'] != 'memory_budget' or 'budget' not in err['message']:
                fail('frames: the 507 does not name the budget: %s' % err)
            break
        if status != 200:
            fail('frames: PUT frame %d: %d %s' % (n, status, data[:200]))
            return
        stored += 1
    else:
        fail('frames: 400 frames fitted a %d MiB session budget' % SESSION_MIB)
    expect('a deleted frame makes room', 'DELETE', base + '/frames/0', None, 200)
    expect('… for the next one', 'PUT', base + '/frames/%d' % stored, vdb, 200, content_type='application/octet-stream')
    global cases
    cases += 1
    status, data, _ = request('POST', base + '/frames/render',
                              {'camera': {'eye': [0, 0, 3], 'target': [0, 0, 0], 'width': 4096, 'height': 4096}})
    if status != 202:
        fail('frames/render: %d %s' % (status, data[:200]))
        return
    job = '/api/v1/jobs/' + json.loads(data)['job']
    time.sleep(2)
    t0 = time.monotonic()
    request('DELETE', job)
    state = None
    while time.monotonic() - t0 < 60:
        state = json.loads(request('GET', job)[1])['state']
        if state not in ('queued', 'running'):
            break
        time.sleep(0.1)
    took = time.monotonic() - t0
    print('[ measured ] frames/render of %d 4096² frames: %s %.2f s after the cancel' % (stored, state, took))
    if state != 'cancelled' or took > 10:
        fail('frames/render: %s %.1f s after a cancel (expected cancelled within 10 s)' % (state, took))
    request('DELETE', base)


def tile_frames():
    """The 8.8 KB VDB holding a 256³ block of tiles (201 MB dense) as frame after frame: refused
    once the session's budget is full, however many frames the limit of 1,000 would allow."""
    tile = open(os.path.join(ROOT, 'tests/data/hostile/tile-256.vdb'), 'rb').read()
    base = '/api/v1/sessions/' + new_session(16)
    stored, t0 = 0, time.monotonic()
    for n in range(1000):
        status, data, _ = request('PUT', base + '/frames/%d' % n, tile, 'application/octet-stream')
        if status != 200:
            break
        stored += 1
    global cases
    cases += 1
    rss = peak_rss_mib()
    print('[ measured ] %d-byte tiled VDB as frames: %d stored, then %d (%s) after %.1f s; peak RSS so far %s MiB'
          % (len(tile), stored, status, json.loads(data)['error']['code'] if status >= 400 else '', time.monotonic() - t0,
             '%.0f' % rss if rss else '?'))
    if status != 507 or json.loads(data)['error']['code'] != 'memory_budget':
        fail('tiled frames: HTTP %d after %d frames, expected 507 memory_budget' % (status, stored))
    if stored * 201 > SESSION_MIB * 1.05 + 201:
        fail('tiled frames: %d frames of 201 MB fitted a %d MiB budget' % (stored, SESSION_MIB))
    request('DELETE', base)


def burst(base_count=100):
    print('a burst of %d parallel session creates (each answered; /health timed meanwhile):' % base_count)
    answers, errors = [], []
    lock = threading.Lock()

    def create():
        try:
            status, data, headers = request('POST', '/api/v1/sessions', {'scene': 'builtin:cloud', 'resolution': 16}, timeout=120)
            with lock:
                answers.append((status, headers.get('Retry-After')))
        except Exception as e:
            with lock:
                errors.append(str(e))

    times, stop = [], threading.Event()

    def watch():
        while not stop.is_set():
            t0 = time.monotonic()
            try:
                health()
                times.append((time.monotonic() - t0) * 1000)
            except Exception as e:
                errors.append('health: %s' % e)
            time.sleep(0.01)

    watcher = threading.Thread(target=watch)
    watcher.start()
    threads = [threading.Thread(target=create) for _ in range(base_count)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    stop.set()
    watcher.join()
    counts = {}
    for status, _ in answers:
        counts[status] = counts.get(status, 0) + 1
    p99 = sorted(times)[max(0, int(len(times) * 0.99) - 1)] if times else float('nan')
    print('[ measured ] burst: %d answered %s, %d unanswered; /health p50 %.1f ms, p99 %.1f ms over %d checks'
          % (len(answers), counts, len(errors), statistics.median(times) if times else float('nan'), p99, len(times)), flush=True)
    if errors:
        fail('burst: %d connections got no answer: %s' % (len(errors), errors[:3]))
    if set(counts) - {201, 422, 429, 503}:
        fail('burst: unexpected statuses %s' % counts)
    if any(s in (429, 503) and not ra for s, ra in answers):
        fail('burst: a 429/503 without Retry-After')
    if not (p99 < 100):
        fail('burst: /health p99 %.1f ms, over 100 ms' % p99)
    # Free the sessions the burst made.
    status, data, _ = request('GET', '/api/v1/sessions')
    listed = json.loads(data) if status == 200 else []
    for s in (listed.get('sessions', []) if isinstance(listed, dict) else listed):
        request('DELETE', '/api/v1/sessions/' + s['id'])


def main():
    base = '/api/v1/sessions/' + new_session()
    meshes(base)
    framing()
    values(base)
    budgets(base)
    frames()
    tile_frames()
    burst()
    if health() != 200:
        fail('the server is down after the probe')
    rss = peak_rss_mib()
    if rss is not None:
        rss = max([rss] + earlier_peaks)
        print('[ measured ] the server\'s peak RSS through the probe: %.0f MiB (bound %.0f MiB)' % (rss, RSS_LIMIT_MIB))
        if rss > RSS_LIMIT_MIB:
            fail('peak RSS %.0f MiB over %.0f MiB' % (rss, RSS_LIMIT_MIB))
    print('%d cases, %d failures' % (cases, len(failures)))
    sys.exit(1 if failures else 0)


if __name__ == '__main__':
    main()
