"""Shared by bench/soak.py and bench/kill_loop.py: start `volstyle serve` on a free port, talk to
it with the standard library only, and make small test images and volumes."""
import json
import http.client
import os
import re
import struct
import subprocess
import time
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BINARY = os.path.join(ROOT, "build", "bin", "volstyle")


class Server:
    """`volstyle serve --port 0 --data-dir DIR` as a child; .port once it listens."""

    def __init__(self, data_dir, binary=BINARY, extra=()):
        t0 = time.monotonic()
        self.proc = subprocess.Popen([binary, "serve", "--port", "0", "--data-dir", data_dir,
                                      "--web-dir", os.path.join(ROOT, "web"), *extra],
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        line = self.proc.stdout.readline()
        if "serving http://" not in line:
            raise RuntimeError("the server did not start: " + line)
        self.port = int(re.search(r"serving http://[^:]+:([0-9]+)", line).group(1))
        self.startup_ms = (time.monotonic() - t0) * 1000

    @property
    def pid(self):
        return self.proc.pid

    def rss_mib(self):
        with open(f"/proc/{self.proc.pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024
        return 0.0

    def kill(self):
        self.proc.kill()
        self.proc.wait()

    def stop(self):
        self.proc.terminate()
        return self.proc.wait(timeout=60)


def request(port, method, path, body=None, content_type="application/json", timeout=120):
    """(status, bytes); status 0 when the connection failed."""
    data = json.dumps(body).encode() if isinstance(body, (dict, list)) else body
    try:
        c = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
        headers = {"Content-Type": content_type} if data is not None else {}
        c.request(method, "/api/v1" + path, body=data, headers=headers)
        r = c.getresponse()
        payload = r.read()
        c.close()
        return r.status, payload
    except (OSError, http.client.HTTPException):
        return 0, b""


def png(width, height, rgb):
    """An 8-bit RGB PNG of one colour (0..255 per channel)."""
    raw = b"".join(b"\x00" + bytes(rgb) * width for _ in range(height))
    chunk = lambda kind, data: struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def percentile(values, p):
    if not values:
        return float("nan")
    s = sorted(values)
    return s[min(len(s) - 1, int(round(p / 100 * (len(s) - 1))))]
