"""The Houdini recipe's logic without Houdini: a stand-in camera node (the parameters and the
row-vector world transform hou gives) projects points as a Houdini camera does, and the whole
round trip (send, render views, paint, send paintings, solve, fetch) runs against the live server."""
import math
import os
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
import volstyle_client as vc  # noqa: E402
import volstyle_houdini as vh  # noqa: E402


class Parm:
    def __init__(self, value):
        self.value = value

    def eval(self):
        return self.value


class FakeCamera:
    """hou.ObjNode of a camera: parm(name).eval() and worldTransform() (rows, p·M)."""

    def __init__(self, rows, **parms):
        self.rows, self.parms = rows, parms

    def parm(self, name):
        return Parm(self.parms[name]) if name in self.parms else None

    def worldTransform(self):
        return self.rows


def row_vector_transform(yaw_deg, pitch_deg, t):
    """A Houdini world transform (rows; p_world = p_local · M): rotate X by pitch, then Y by yaw, then translate."""
    cy, sy = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    cp, sp = math.cos(math.radians(pitch_deg)), math.sin(math.radians(pitch_deg))
    rx = [[1, 0, 0], [0, cp, sp], [0, -sp, cp]]  # row-vector rotation about X
    ry = [[cy, 0, -sy], [0, 1, 0], [sy, 0, cy]]  # row-vector rotation about Y
    r = [[sum(rx[i][k] * ry[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    return [r[0] + [0], r[1] + [0], r[2] + [0], list(t) + [1]]


def houdini_pixel(rows, point, focal, aperture, resx, resy, aspect):
    """Where Houdini's camera sees a world point, from its definition: into camera space by the
    inverse transform, x/−z scaled by focal/aperture across the width, y by the frame's aspect."""
    inv = vc.invert([[rows[j][i] for j in range(4)] for i in range(4)])  # column form, inverted
    x, y, z = vc.camera.transform_point(inv, point)
    u = 0.5 + (x / -z) * focal / aperture
    v = 0.5 + (y / -z) * focal / aperture * (resx * aspect) / resy
    return u * resx, (1 - v) * resy


class HoudiniRecipe(unittest.TestCase):
    def test_the_camera_lands_points_where_houdini_does(self):
        rows = row_vector_transform(30, -10, (2.0, 1.0, 4.0))
        for resx, resy, aspect in ((640, 360, 1.0), (720, 486, 0.9)):
            node = FakeCamera(rows, focal=50.0, aperture=41.4214, resx=resx, resy=resy, aspect=aspect, near=0.01, far=1000.0)
            cam = vh.houdini_camera(node)
            for p in ([0.1, 0.2, 0.0], [0.5, 0.8, -1.0], [-0.4, 1.3, 0.5]):
                hx, hy = houdini_pixel(rows, p, 50.0, 41.4214, resx, resy, aspect)
                px, py = vc.project(cam, p)
                # Same normalised frame: the height is rescaled for square pixels.
                self.assertAlmostEqual(px / cam["width"], hx / resx, delta=1e-9)
                self.assertAlmostEqual(py / cam["height"], hy / resy, delta=1e-9)
        with self.assertRaisesRegex(ValueError, "shift"):
            vh.houdini_camera(FakeCamera(rows, focal=50.0, aperture=41.4214, resx=64, resy=64, winx=0.2))

    @unittest.skipUnless(os.environ.get("VOLSTYLE_URL"), "needs a live server (tests/clients/run_python_client.sh)")
    def test_the_round_trip(self):
        vs = vc.Client(os.environ["VOLSTYLE_URL"])
        with tempfile.TemporaryDirectory() as folder:
            # "Houdini's" VDB: a cloud written by the server.
            src = vs.create_session("builtin:cloud", 24)
            vdb = os.path.join(folder, "cloud.vdb")
            vs.download_volume(src["id"], path=vdb)
            vs.delete_session(src["id"])
            cam = vh.houdini_camera(FakeCamera(row_vector_transform(0, 0, (0, 0.1, 3.4)), focal=50.0, aperture=41.4214, resx=48, resy=48))
            sun = vc.sun_from_dcc(vc.camera.IDENTITY, 6.0)  # straight down −z: light from +z
            sid = vh.send(vs, vdb, [sun], background=(0.1, 0.12, 0.2))
            views = vh.render_views(vs, sid, {"cam1": cam}, folder)
            w, h, layers = vc.read_exr(open(os.path.join(folder, "cam1.exr"), "rb").read())
            rgb = vc.picture_of(layers)
            cover = vc.read_exr(vs.render_view(sid, views["cam1"], "exr"))[2]["A"]  # the "painting": warmer where the medium is
            glow = [v * (1.5, 1.1, 0.9)[i % 3] if cover[i // 3] > 0.2 else v for i, v in enumerate(rgb)]
            with open(os.path.join(folder, "cam1.painted.exr"), "wb") as f:
                f.write(vc.exr_rgba(w, h, glow, 1.0))
            self.assertEqual(vh.send_paintings(vs, sid, views, folder), ["cam1"])
            out = os.path.join(folder, "solved.vdb")
            result = vh.solve_and_fetch(vs, sid, out, iterations=10, progress=False)
            report = result["report"]
            self.assertLess(report["final_rms"][0], 0.5 * report["initial_rms"][0])
            with open(out, "rb") as f:
                self.assertEqual(f.read(4), b"\x20\x42\x44\x56")
            self.assertEqual(vs.get_lighting(sid)["sun"]["irradiance"], [6.0, 6.0, 6.0])
            vs.delete_session(sid)


if __name__ == "__main__":
    unittest.main()
