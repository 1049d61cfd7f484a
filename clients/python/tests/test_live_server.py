"""The client against a live server ($VOLSTYLE_URL, started with --token $VOLSTYLE_TOKEN and
--max-upload-mib 1 by tests/clients/run_python_client.sh): every route of the server's OpenAPI
description has its call; a full paint → solve → download flow; errors as exceptions carrying the
SPEC body (bad token, 404, 413, a bad option); a cancelled job; idempotent retries; paging."""
import io
import os
import subprocess
import sys
import tempfile
import unittest

import volstyle_client as vc

URL = os.environ["VOLSTYLE_URL"]
CAMERA = {"eye": [0, 0.2, 3.4], "target": [0, -0.05, 0], "fov_y_deg": 38, "width": 48, "height": 48}


class LiveServer(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.vs = vc.Client(URL)  # the token from $VOLSTYLE_TOKEN

    def session(self, scene="builtin:cloud", resolution=24):
        s = self.vs.create_session(scene, resolution)
        self.addCleanup(lambda: self.vs.delete_session(s["id"]))
        return s["id"]

    def test_every_route_of_the_openapi_description_has_a_call(self):
        described = {}
        for path, ops in self.vs.openapi()["paths"].items():
            for method, op in ops.items():
                if method in ("get", "put", "post", "delete", "patch"):
                    described[op["operationId"]] = (method.upper(), path)
        ours = {op: (method, path) for op, method, path in vc.Client.routes().values()}
        self.assertEqual(sorted(set(described) - set(ours)), [], "routes the server describes that the client does not call")
        self.assertEqual(sorted(set(ours) - set(described)), [], "calls of routes the server does not describe")
        for op, where in described.items():
            self.assertEqual(ours[op], where, op)
        self.assertEqual(len(ours), len(vc.Client.routes()), "one method per route")

    def test_paint_solve_download(self):
        sid = self.session()
        view = self.vs.add_view(sid, CAMERA)
        # The view's linear picture, painted: a warm glow in a disc, the rest kept (weight 1).
        w, h, layers = vc.read_exr(self.vs.render_view(sid, view["id"], "exr", exr_type="float"))
        self.assertEqual((w, h), (48, 48))
        base = vc.picture_of(layers)
        painted = list(base)
        for y in range(h):
            for x in range(w):
                if (x - 24) ** 2 + (y - 25) ** 2 < 64:
                    i = 3 * (y * w + x)
                    painted[i:i + 3] = [base[i] * 1.6 + 0.2, base[i + 1] * 1.1 + 0.05, base[i + 2] * 0.8]
        v = self.vs.set_target(sid, view["id"], vc.exr_rgba(w, h, painted, 1.0))
        self.assertTrue(v["has_target"])
        self.assertEqual(v["clipped_pixels"], 0)
        events = []
        job = self.vs.solve(sid, unknowns=["emission", "albedo"], max_iterations=12)
        result = job.wait(progress=lambda name, data: events.append(name))
        self.assertEqual(events[-1], "done")
        self.assertIn("progress", events)
        report = result["report"]
        self.assertLess(report["final_rms"][0], 0.5 * report["initial_rms"][0], report)
        self.assertEqual(result["version"], 2)
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "solved.vdb")
            data = self.vs.download_volume(sid, path=out)
            self.assertEqual(data[:4], b"\x20\x42\x44\x56", "an OpenVDB file")  # its magic number
            self.assertEqual(os.path.getsize(out), len(data))
        self.assertIn("emission", self.vs.get_session(sid)["volume"]["grids"])
        # The render after the solve is nearer the paint than before.
        _, _, after = vc.read_exr(self.vs.render_view(sid, view["id"], "exr", exr_type="float"))
        rms = lambda a: (sum((p - q) ** 2 for p, q in zip(a, painted)) / len(a)) ** 0.5  # noqa: E731
        self.assertLess(rms(vc.picture_of(after)), 0.5 * rms(base))

    def test_the_live_stream_brings_jpeg_frames(self):
        # Issue #40: …/stylizer/stream as (headers, JPEG) parts, the first one the scene now.
        sid = self.session(resolution=16)
        scene = self.vs.get_stylizer(sid)
        scene["camera"]["width"], scene["camera"]["height"] = 48, 27
        self.vs.set_stylizer(sid, scene)
        stream = self.vs.stylizer_stream(sid)
        headers, jpeg = next(stream)
        stream.close()
        self.assertEqual(headers["content-type"], "image/jpeg")
        self.assertEqual((headers["x-width"], headers["x-height"]), ("48", "27"))
        self.assertGreaterEqual(int(headers["x-revision"]), 1)
        self.assertEqual(jpeg[:2], b"\xff\xd8")
        self.assertEqual(len(jpeg), int(headers["content-length"]))

    def test_ready_and_metrics(self):
        # Issue #41: readiness for a load balancer, and the Prometheus counters by route template.
        self.assertEqual(self.vs.ready()["status"], "ready")
        self.vs.health()
        m = self.vs.metrics()
        self.assertGreaterEqual(m['volstyle_http_requests_total{method="GET",route="/api/v1/health",status="200"}'], 1)
        self.assertIn('volstyle_jobs{state="queued"}', m)

    def test_the_viewport_streams_what_it_was_set_to(self):
        # Issue #40: PUT …/viewport, then …/viewport/stream brings that camera's frame as a JPEG.
        sid = self.session(resolution=16)
        self.assertEqual(self.vs.get_viewport(sid)["revision"], 0)
        camera = dict(CAMERA, width=40, height=30)
        self.assertEqual(self.vs.set_viewport(sid, camera)["revision"], 1)
        stream = self.vs.viewport_stream(sid)
        headers, jpeg = next(stream)
        stream.close()
        self.assertEqual(headers["content-type"], "image/jpeg")
        self.assertEqual((headers["x-width"], headers["x-height"], headers["x-revision"]), ("40", "30", "1"))
        self.assertEqual(jpeg[:2], b"\xff\xd8")

    def test_the_exr_reader_reads_what_the_server_writes(self):
        # Half-float ZIP (the default render.exr) against float: the same picture to half precision.
        sid = self.session(resolution=16)
        view = self.vs.add_view(sid, CAMERA)
        _, _, half = vc.read_exr(self.vs.render_view(sid, view["id"], "exr"))
        _, _, full = vc.read_exr(self.vs.render_view(sid, view["id"], "exr", exr_type="float"))
        a, b = vc.picture_of(half), vc.picture_of(full)
        self.assertGreater(max(b), 0.1)
        self.assertLess(max(abs(x - y) for x, y in zip(a, b)), 2e-3 * max(b))
        # The numpy path (Blender, Houdini; Debian's python3-numpy here) and the standard
        # library's read the same values.
        from volstyle_client import images
        self.assertIsNotNone(images._np, "numpy is installed by scripts/install_deps.sh")
        data = self.vs.render_view(sid, view["id"], "exr")
        fast = vc.read_exr(data)
        saved, images._np = images._np, None
        try:
            self.assertEqual(vc.read_exr(data), fast)
        finally:
            images._np = saved

    def test_errors_carry_the_spec_body(self):
        with self.assertRaises(vc.Unauthorized) as e:
            vc.Client(URL, token="wrong").list_sessions()
        self.assertEqual((e.exception.status, e.exception.code), (401, "unauthorized"))
        self.assertTrue(e.exception.request_id)
        with self.assertRaises(vc.NotFound) as e:
            self.vs.get_session("nope")
        self.assertIn("nope", e.exception.message)
        sid = self.session(resolution=8)
        with self.assertRaises(vc.TooLarge) as e:
            self.vs.upload_volume(sid, b"\0" * (2 << 20))  # over the test server's 1 MiB
        self.assertEqual((e.exception.status, e.exception.code), (413, "too_large"))
        with self.assertRaises(vc.InvalidRequest) as e:
            self.vs.solve(sid, unknowns=["happiness"])
        self.assertEqual(e.exception.status, 400)
        self.assertTrue(any(d.path.startswith("/unknowns") for d in e.exception.details), e.exception.details)
        self.assertIn("/unknowns", str(e.exception))
        with self.assertRaises(vc.ConnectionFailed):
            vc.Client("http://127.0.0.1:9", retries=1).health()

    def test_a_cancelled_job_raises_with_its_state(self):
        sid = self.session(resolution=32)
        for k in range(2):
            self.vs.add_view(sid, {**CAMERA, "eye": [3.4 * k, 0.2, 3.4 * (1 - k)], "width": 64, "height": 64})
            self.vs.set_target(sid, f"v{k + 1}", vc.exr_rgba(64, 64, [0.9, 0.4, 0.1] * 64 * 64, 1.0))
        job = self.vs.solve(sid, unknowns=["emission"], max_iterations=5000, tolerance=0)
        for name, data in job.events():
            if name == "progress" and data.get("iteration"):
                job.cancel()
                break
        with self.assertRaises(vc.JobFailed) as e:
            job.wait(progress=False)
        self.assertEqual(e.exception.state, "cancelled")
        self.assertEqual(self.vs.get_session(sid)["volume"]["version"], 1, "a cancelled solve leaves the volume")

    def test_the_same_idempotency_key_is_the_same_job(self):
        sid = self.session(resolution=16)
        view = self.vs.add_view(sid, CAMERA)
        self.vs.set_target(sid, view["id"], self.vs.render_view(sid, view["id"], "png"))
        a = self.vs.solve(sid, unknowns=["emission"], max_iterations=2, idempotency_key="k-1")
        b = self.vs.solve(sid, unknowns=["emission"], max_iterations=2, idempotency_key="k-1")
        self.assertEqual(a.id, b.id)
        a.wait(progress=False)
        with self.assertRaises(vc.InvalidRequest) as e:
            self.vs.solve(sid, unknowns=["emission"], max_iterations=3, idempotency_key="k-1")
        self.assertEqual(e.exception.code, "idempotency_conflict")

    def test_a_terminal_bar_and_pages(self):
        sid = self.session(resolution=16)
        view = self.vs.add_view(sid, CAMERA)
        self.vs.set_target(sid, view["id"], self.vs.render_view(sid, view["id"], "png"))
        bar = io.StringIO()
        self.vs.solve(sid, unknowns=["emission"], max_iterations=3).wait(progress=bar)
        self.assertIn("iterating", bar.getvalue())
        self.assertIn("solve done", bar.getvalue())
        ids = {self.session(resolution=8) for _ in range(3)}
        listed = {s["id"] for s in self.vs.iter_sessions(page_size=1)}
        self.assertTrue(ids <= listed)
        self.assertEqual(len(self.vs.list_sessions(limit=1)), 1)
        self.assertTrue(any(j["session"] == sid for j in self.vs.iter_jobs(session=sid, page_size=1)))

    def test_an_interrupted_wait_cancels_the_job(self):
        # A DCC's Cancel button raises from the progress callback: the job stops on the server too.
        sid = self.session(resolution=32)
        self.vs.add_view(sid, {**CAMERA, "width": 64, "height": 64})
        self.vs.set_target(sid, "v1", vc.exr_rgba(64, 64, [0.9, 0.4, 0.1] * 64 * 64, 1.0))
        job = self.vs.solve(sid, unknowns=["emission"], max_iterations=5000, tolerance=0)

        def cancel_button(name, data):
            if name == "progress" and data.get("iteration"):
                raise RuntimeError("the artist pressed Cancel")

        with self.assertRaisesRegex(RuntimeError, "pressed Cancel"):
            job.wait(progress=cancel_button)
        with self.assertRaises(vc.JobCancelled):
            job.wait(progress=False)

    def test_pages_local_files_and_addresses(self):
        for _ in range(2):
            self.session(resolution=8)
        first = self.vs.list_sessions(limit=1)
        self.assertEqual(len(first), 1)
        self.assertTrue(first.next_cursor, "a page says where the next one starts")
        second = self.vs.list_sessions(limit=1, cursor=first.next_cursor)
        self.assertNotEqual(first[0]["id"], second[0]["id"])
        sid = self.session(resolution=8)
        view = self.vs.add_view(sid, CAMERA)
        with self.assertRaisesRegex(vc.LocalFileError, "cannot read '/no/such/painting.exr'"):
            self.vs.set_target(sid, view["id"], "/no/such/painting.exr")
        with self.assertRaisesRegex(vc.LocalFileError, "no folder"):
            self.vs.download_volume(sid, path="/no/such/folder/out.vdb")
        bare = URL.split("://", 1)[1]
        self.assertEqual(vc.Client(bare).health()["status"], self.vs.health()["status"], "host:port means http")
        self.assertTrue(vc.Client(URL + "/api/v1/").health(), "the API's own address works too")
        with self.assertRaises(vc.InvalidRequest) as e:
            self.vs.create_session("builtin:cloud", 3)
        text = str(e.exception)
        self.assertEqual(text.count("/resolution"), 1, f"each detail once: {text}")

    def test_the_command_line(self):
        out = subprocess.run([sys.executable, "-m", "volstyle_client", "--url", URL, "health"], capture_output=True, text=True)
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertIn("gl_renderer", out.stdout)
        out = subprocess.run([sys.executable, "-m", "volstyle_client", "--url", URL, "--token", "wrong", "sessions"], capture_output=True,
                             text=True)
        self.assertEqual(out.returncode, 2)
        self.assertIn("401 unauthorized", out.stderr)


if __name__ == "__main__":
    unittest.main()
