"""The add-on's buttons. Each reports the server's error in Blender's status bar (and fails
cleanly); the solve runs in the background with its progress in the status bar (in a script,
`bpy.ops.volstyle.solve()` waits for it)."""
from __future__ import annotations

import threading

import bpy

from . import session
from .volstyle_client import VolstyleError
from .volstyle_client.job import describe_progress


def _run(op, context, fn, *args):
    try:
        result = fn(context.scene, *args)
    except (VolstyleError, ValueError, OSError) as e:
        op.report({"ERROR"}, str(e))
        context.scene.volstyle.status = str(e)
        return {"CANCELLED"}
    op.report({"INFO"}, context.scene.volstyle.status)
    return {"FINISHED"} if result is not False else {"CANCELLED"}


class VOLSTYLE_OT_connect(bpy.types.Operator):
    """Check the server and its GL device"""
    bl_idname, bl_label = "volstyle.connect", "Connect"

    def execute(self, context):
        return _run(self, context, session.connect)


class VOLSTYLE_OT_send_volume(bpy.types.Operator):
    """Start a session with the selected Volume object's VDB (or a built-in cloud)"""
    bl_idname, bl_label, bl_options = "volstyle.send_volume", "Send volume", {"REGISTER", "UNDO"}
    builtin: bpy.props.BoolProperty(name="Built-in cloud", default=False)

    def execute(self, context):
        return _run(self, context, lambda scene: session.send_volume(scene, context.active_object, self.builtin))


class VOLSTYLE_OT_render_views(bpy.types.Operator):
    """Render every camera's view (or the selected cameras') through the server into Images to paint"""
    bl_idname, bl_label = "volstyle.render_views", "Render views"
    selected_only: bpy.props.BoolProperty(name="Selected cameras only", default=False)

    def execute(self, context):
        return _run(self, context, lambda scene: session.render_views(scene, session.cameras(scene, self.selected_only)))


class VOLSTYLE_OT_send_targets(bpy.types.Operator):
    """Send the painted views as the solve's targets (linear float; weight from the paint)"""
    bl_idname, bl_label = "volstyle.send_targets", "Send paintings"

    def execute(self, context):
        return _run(self, context, session.send_targets)


class VOLSTYLE_OT_import_result(bpy.types.Operator):
    """Import the session's current volume as a Volume object with the volstyle material"""
    bl_idname, bl_label, bl_options = "volstyle.import_result", "Import result", {"REGISTER", "UNDO"}

    def execute(self, context):
        return _run(self, context, session.import_result)


class VOLSTYLE_OT_shafts(bpy.types.Operator):
    """Send the scene's meshes and sun to the light-shaft stylizer and show its frame"""
    bl_idname, bl_label = "volstyle.shafts", "Light shafts"

    def execute(self, context):
        return _run(self, context, session.shafts)


class VOLSTYLE_OT_solve(bpy.types.Operator):
    """Solve the volume so its renders match the paintings (progress in the status bar)"""
    bl_idname, bl_label = "volstyle.solve", "Solve"

    _timer = None

    def _start(self, context):
        scene = context.scene
        sid = session.require_session(scene)
        self.job = session.client(scene).solve(sid, session.solve_options(scene))
        self.state = {"text": "queued", "fraction": 0.0, "result": None, "error": None}

    def _follow(self):
        def seen(name, data):
            if name == "progress":
                fraction, text = describe_progress("solve", data, self.job.total)
                self.state.update(text=text, fraction=fraction if fraction is not None else self.state["fraction"])
        try:
            self.state["result"] = self.job.wait(progress=seen)
        except Exception as e:  # reported by the modal loop
            self.state["error"] = e

    def _finish(self, context):
        scene = context.scene
        if self.state["error"]:
            scene.volstyle.status = str(self.state["error"])
            self.report({"ERROR"}, scene.volstyle.status)
            return {"CANCELLED"}
        r = self.state["result"]
        report = r.get("report", {})
        if scene.volstyle.import_each_solve:
            session.import_result(scene, r.get("version"))
        scene.volstyle.status = f"solved: version {r.get('version')}, {report.get('iterations')} iterations ({report.get('stop_reason')})"
        reach = report.get("reach") or {}
        if reach.get("advice"):
            self.report({"WARNING"}, reach["advice"])
        self.report({"INFO"}, scene.volstyle.status)
        return {"FINISHED"}

    def execute(self, context):  # a script's call: wait here
        try:
            self._start(context)
        except (VolstyleError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self._follow()
        return self._finish(context)

    def invoke(self, context, event):  # a button: follow the job in a thread, redraw from a timer
        try:
            self._start(context)
        except (VolstyleError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        context.scene.volstyle["job"] = self.job.id
        self._thread = threading.Thread(target=self._follow, daemon=True)
        self._thread.start()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.25, window=context.window)
        wm.progress_begin(0, 1000)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        wm = context.window_manager
        wm.progress_update(int(1000 * (self.state["fraction"] or 0.0)))
        context.workspace.status_text_set(f"volstyle: {self.state['text']}")
        context.scene.volstyle["progress"] = self.state["text"]  # what the status bar shows, for scripts
        if self._thread.is_alive():
            return {"RUNNING_MODAL"}
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)
        return self._finish(context)


class VOLSTYLE_OT_cancel(bpy.types.Operator):
    """Cancel the running solve (the volume keeps its version)"""
    bl_idname, bl_label = "volstyle.cancel", "Cancel"

    def execute(self, context):
        job = context.scene.volstyle.get("job")
        if not job:
            return {"CANCELLED"}
        return _run(self, context, lambda scene: session.client(scene).cancel_job(job))


CLASSES = [VOLSTYLE_OT_connect, VOLSTYLE_OT_send_volume, VOLSTYLE_OT_render_views, VOLSTYLE_OT_send_targets, VOLSTYLE_OT_solve,
           VOLSTYLE_OT_cancel, VOLSTYLE_OT_import_result, VOLSTYLE_OT_shafts]
