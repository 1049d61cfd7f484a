"""Camera conversion without Blender: volstyle's projection of the converted camera against an
independent pinhole built the way Blender frames a sensor (its world_to_camera_view: points into
camera space by the inverse matrix, divided by depth, scaled by the sensor frame). The Blender
add-on's test repeats this against Blender itself."""
import math
import random
import unittest

import volstyle_client as vc


def rotation(axis, degrees):
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    x, y, z = axis
    return [[c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s, 0],
            [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s, 0],
            [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c), 0], [0, 0, 0, 1]]


def translation(t):
    return [[1, 0, 0, t[0]], [0, 1, 0, t[1]], [0, 0, 1, t[2]], [0, 0, 0, 1]]


def sensor_frame(lens, sw, sh, fit, ax, ay):
    """Half extents of the frame at distance 1, as Blender's camera frame (BKE_camera_params)."""
    if fit == "AUTO":
        fit, size = ("HORIZONTAL" if ax >= ay else "VERTICAL"), sw
    else:
        size = sw if fit == "HORIZONTAL" else sh
    if fit == "HORIZONTAL":
        hx = size / 2 / lens
        return hx, hx * ay / ax
    hy = size / 2 / lens
    return hy * ax / ay, hy


def blender_pixel(matrix_world, point, lens, sw, sh, fit, res, pixel_aspect):
    local = vc.camera.transform_point(vc.invert(matrix_world), point)
    depth = -local[2]
    hx, hy = sensor_frame(lens, sw, sh, fit, res[0] * pixel_aspect[0], res[1] * pixel_aspect[1])
    u = (local[0] / depth / hx + 1) / 2  # Blender's normalised view coordinates (0..1, v up)
    v = (local[1] / depth / hy + 1) / 2
    return u, v


class CameraConversion(unittest.TestCase):
    def test_ten_points_land_on_the_same_pixels(self):
        rng = random.Random(7)
        cases = [("AUTO", (1920, 1080), (1, 1), 50), ("AUTO", (720, 1280), (1, 1), 35), ("HORIZONTAL", (640, 480), (1, 1), 85),
                 ("VERTICAL", (400, 300), (1, 1), 24), ("AUTO", (720, 576), (16, 15), 50)]
        for fit, res, aspect, lens in cases:
            m = vc.camera.multiply(translation((3, -7, 2)), vc.camera.multiply(rotation((0, 0, 1), 40), rotation((1, 0, 0), 75)))
            cam = vc.camera_from_dcc(m, lens_mm=lens, sensor_width_mm=36, sensor_height_mm=24, sensor_fit=fit, resolution=res,
                                     pixel_aspect=aspect)
            for _ in range(10):
                # a point in front of the camera, inside its frame
                d = [rng.uniform(-0.3, 0.3), rng.uniform(-0.2, 0.2), -1.0]
                p = vc.camera.transform_point(m, [x * rng.uniform(2, 20) for x in d])
                u, v = blender_pixel(m, p, lens, 36, 24, fit, res, aspect)
                px, py = vc.project(cam, p)
                self.assertAlmostEqual(px, u * cam["width"], delta=1e-6 * cam["width"], msg=(fit, res))
                self.assertAlmostEqual(py, (1 - v) * cam["height"], delta=1e-6 * cam["height"], msg=(fit, res))

    def test_a_volume_object_turned_upright_sees_volstyle_space(self):
        # A volstyle volume shown upright in Blender (+90° about X): a camera given in Blender's
        # world is the same camera in volstyle's y-up world.
        obj = vc.camera.multiply(translation((1, 2, 3)), vc.BLENDER_FROM_VOLSTYLE)
        cam_world = vc.camera.multiply(translation((0, -5, 3)), rotation((1, 0, 0), 90))  # looks along +y (Blender), z up
        cam = vc.camera_from_dcc(cam_world, lens_mm=50, resolution=(100, 100), to_volstyle=vc.invert(obj))
        for a, b in zip(cam["up"], [0, 1, 0]):
            self.assertAlmostEqual(a, b)
        forward = [t - e for t, e in zip(cam["target"], cam["eye"])]
        for a, b in zip(forward, [0, 0, -1]):  # Blender +y is volstyle −z
            self.assertAlmostEqual(a, b)

    def test_what_volstyle_cannot_do_is_refused(self):
        with self.assertRaisesRegex(ValueError, "shift"):
            vc.camera_from_dcc(vc.camera.IDENTITY, lens_mm=50, shift=(0.1, 0))
        with self.assertRaisesRegex(ValueError, "orthographic"):
            vc.camera_from_dcc(vc.camera.IDENTITY, lens_mm=50, perspective=False)
        with self.assertRaisesRegex(ValueError, "8192"):
            vc.camera_from_dcc(vc.camera.IDENTITY, lens_mm=50, resolution=(10000, 100))

    def test_a_sun_points_toward_the_light(self):
        sun = vc.sun_from_dcc(rotation((1, 0, 0), 0), 3.0, (1, 0.5, 0.25))  # shining straight down −z
        self.assertEqual([round(x, 9) for x in sun["direction"]], [0, 0, 1])
        self.assertEqual(sun["irradiance"], [3.0, 1.5, 0.75])


class FollowingAJob(unittest.TestCase):
    def test_a_broken_stream_is_followed_again_where_it_was(self):
        # The server replays a job's stream from the first event; after a break the callback
        # sees each event once, and the final one ends the wait.
        events = [("progress", {"phase": "preparing_views"}), ("progress", {"iteration": 1, "rms_per_view": [0.5]}),
                  ("progress", {"iteration": 2, "rms_per_view": [0.25]}), ("done", {"state": "done", "result": {"version": 2}})]

        class Client:
            calls = 0

            def job_events(self, jid):
                Client.calls += 1
                for k, e in enumerate(events):
                    if Client.calls == 1 and k == 2:
                        raise vc.ConnectionFailed("the stream broke off")
                    yield e

            def get_job(self, jid):
                return {"state": "running"}

        seen = []
        result = vc.Job(Client(), "j1", "solve", 2).wait(progress=lambda name, data: seen.append((name, data)))
        self.assertEqual(result, {"version": 2})
        self.assertEqual(seen, events)
        self.assertEqual(Client.calls, 2)


class ExrRoundTrip(unittest.TestCase):
    def test_write_then_read(self):
        rgb = [i / 7 for i in range(3 * 6 * 4)]
        w, h, c = vc.read_exr(vc.exr_rgba(6, 4, rgb, [k % 2 for k in range(24)]))
        self.assertEqual((w, h), (6, 4))
        self.assertEqual(c["A"][:4], [0, 1, 0, 1])
        for a, b in zip(vc.picture_of(c), rgb):
            self.assertAlmostEqual(a, b, places=6)


if __name__ == "__main__":
    unittest.main()
