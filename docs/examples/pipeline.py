#!/usr/bin/env python3
"""A pipeline step with the volstyle Python client (clients/python, docs/CLIENTS.md).

Uploads a VDB (or starts from a built-in cloud), adds two views, renders each as linear EXR,
"paints" it in code (a warm glow in the middle, weight 1 where painted, 0.2 elsewhere), solves for
emission and albedo with a progress bar, and writes the solved VDB.

    pip install ./clients/python
    python3 docs/examples/pipeline.py --url http://127.0.0.1:8080 [--vdb smoke.vdb] -o solved.vdb
"""
import argparse
import math

import volstyle_client as vc


def glow(width, height, picture):
    """A warm glow over the middle third of a picture: (rgb, weights) for exr_rgba."""
    rgb, weights = list(picture), [0.2] * (width * height)
    for y in range(height):
        for x in range(width):
            r = math.hypot(x / width - 0.5, y / height - 0.5)
            if r < 0.17:
                i = y * width + x
                k = 1 - r / 0.17  # strongest in the middle
                rgb[3 * i:3 * i + 3] = [picture[3 * i] * (1 + 0.8 * k) + 0.3 * k, picture[3 * i + 1] * (1 + 0.2 * k), picture[3 * i + 2] * (1 - 0.3 * k)]
                weights[i] = 1.0
    return rgb, weights


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--url", default="http://127.0.0.1:8080")
    p.add_argument("--token", default=None, help="the server's token (default $VOLSTYLE_TOKEN)")
    p.add_argument("--vdb", help="a VDB to restyle (default: the built-in cloud)")
    p.add_argument("--size", type=int, default=96, help="the views' size in pixels")
    p.add_argument("--unknowns", default="emission,albedo", help="what the solve may change (comma-separated)")
    p.add_argument("--iterations", type=int, default=20)
    p.add_argument("-o", "--output", default="solved.vdb")
    a = p.parse_args()

    vs = vc.Client(a.url, a.token)
    session = vs.create_session("builtin:cloud", 48)
    sid = session["id"]
    if a.vdb:
        session = vs.upload_volume(sid, a.vdb)
        vol = session["volume"]
        print(f"uploaded {a.vdb}: {vol['dims'][0]}x{vol['dims'][1]}x{vol['dims'][2]}, stored {vol.get('storage', 'dense')}, "
              f"{vol.get('active_voxels', 0)} active voxels, {vol.get('bytes', 0) / 2**20:.0f} MiB")
    lo, hi = session["volume"]["bbox"]
    centre = [(l + h) / 2 for l, h in zip(lo, hi)]
    radius = math.dist(lo, hi) / 2
    for azimuth in (0.0, 0.9):  # two cameras around the volume, framing its bounding sphere
        d = radius / math.sin(math.radians(19))
        eye = [centre[0] + d * math.sin(azimuth), centre[1] + 0.1 * d, centre[2] + d * math.cos(azimuth)]
        view = vs.add_view(sid, {"eye": eye, "target": centre, "fov_y_deg": 38, "width": a.size, "height": a.size})
        w, h, layers = vc.read_exr(vs.render_view(sid, view["id"], "exr", exr_type="float"))
        rgb, weights = glow(w, h, vc.picture_of(layers))
        vs.set_target(sid, view["id"], vc.exr_rgba(w, h, rgb, weights))

    job = vs.solve(sid, unknowns=a.unknowns.split(","), max_iterations=a.iterations)
    result = job.wait()  # a progress bar on a terminal; raises JobFailed if it fails
    report = result["report"]
    print(f"solved: version {result['version']}, {report['iterations']} iterations ({report['stop_reason']}), "
          f"RMS {sum(report['initial_rms']) / 2:.4g} -> {sum(report['final_rms']) / 2:.4g}")
    vs.download_volume(sid, path=a.output)
    print("wrote", a.output)


if __name__ == "__main__":
    main()
