#!/usr/bin/env python3
"""A pipeline script against the volstyle HTTP API, standard library only.

Creates a session from a built-in scene, adds a view, uploads a painted target (here a warm tint
written as a Radiance .hdr, which needs no imaging library), solves for emission while printing the
progress events, and downloads the solved volume as OpenVDB.

    python3 docs/examples/client.py [http://127.0.0.1:8080] [out.vdb] [--token T]

The token (a server started with --token) may also come from $VOLSTYLE_TOKEN.
"""
import argparse
import json
import os
import struct
import urllib.error
import urllib.request


class Api:
    def __init__(self, base, token=None):
        self.base = base.rstrip("/") + "/api/v1"
        self.headers = {"Authorization": "Bearer " + token} if token else {}

    def request(self, method, path, body=None, content_type="application/json", raw=False):
        data = json.dumps(body).encode() if isinstance(body, (dict, list)) else body
        req = urllib.request.Request(self.base + path, data=data, method=method, headers=dict(self.headers))
        if data is not None:
            req.add_header("Content-Type", content_type)
        try:
            with urllib.request.urlopen(req) as res:
                payload = res.read()
        except urllib.error.HTTPError as e:
            err = json.loads(e.read())["error"]
            details = "; ".join(f"{d['path']}: {d['message']}" for d in err["details"])
            raise SystemExit(f"{method} {path}: {e.code} {err['code']}: {err['message']} {details}")
        return payload if raw else (json.loads(payload) if payload else None)

    def events(self, path):
        """Yields (event, data) from a text/event-stream until the server closes it."""
        req = urllib.request.Request(self.base + path, headers=dict(self.headers))
        with urllib.request.urlopen(req) as res:
            event = None
            for line in res:
                line = line.decode().rstrip("\n")
                if line.startswith("event: "):
                    event = line[7:]
                elif line.startswith("data: "):
                    yield event, json.loads(line[6:])


def radiance_hdr(width, height, rgb):
    """An uncompressed Radiance RGBE image of one colour."""
    r, g, b = rgb
    m = max(r, g, b)
    exponent = 0
    while m >= 1.0:
        m, exponent = m / 2, exponent + 1
    scale = 256.0 / (2.0 ** exponent)
    pixel = struct.pack("4B", int(r * scale), int(g * scale), int(b * scale), exponent + 128)
    header = f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n".encode()
    return header + pixel * (width * height)


def main():
    parser = argparse.ArgumentParser(description="Solve a painted view through the volstyle API.")
    parser.add_argument("url", nargs="?", default="http://127.0.0.1:8080", help="the server (default %(default)s)")
    parser.add_argument("out", nargs="?", default="solved.vdb", help="where to write the result (default %(default)s)")
    parser.add_argument("--token", default=os.environ.get("VOLSTYLE_TOKEN"),
                        help="the server's bearer token (default $VOLSTYLE_TOKEN)")
    args = parser.parse_args()
    api = Api(args.url, args.token)
    out = args.out

    print("server:", api.request("GET", "/health")["gl_renderer"])
    session = api.request("POST", "/sessions", {"scene": "builtin:sphere", "resolution": 32})
    sid = session["id"]
    view = api.request("POST", f"/sessions/{sid}/views",
                       {"camera": {"eye": [0, 0.3, 3], "target": [0, 0, 0], "width": 48, "height": 48}})
    api.request("PUT", f"/sessions/{sid}/views/{view['id']}/target", radiance_hdr(48, 48, (0.9, 0.55, 0.3)),
                content_type="application/octet-stream")
    job = api.request("POST", f"/sessions/{sid}/solve", {"unknowns": ["emission"], "max_iterations": 6})["job"]
    for event, data in api.events(f"/jobs/{job}/events"):
        if event == "progress":
            print(f"iteration {data['iteration']}: objective {data['objective']:.4g}")
        elif event in ("done", "failed", "cancelled"):
            print("job", event, json.dumps(data.get("result") or data.get("error"))[:200])
            if event != "done":
                raise SystemExit(1)
    with open(out, "wb") as f:
        f.write(api.request("GET", f"/sessions/{sid}/volume.vdb", raw=True))
    print("wrote", out)


if __name__ == "__main__":
    main()
