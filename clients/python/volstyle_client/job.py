"""A server job (solve, animate, frames render, stylizer sequence): its events, a wait with a
progress bar in a terminal (quiet in scripts), cancel, result."""
from __future__ import annotations

import shutil
import sys
import time
from typing import TYPE_CHECKING, Any, Callable, Iterator, TextIO

from .errors import ConnectionFailed, JobFailed

if TYPE_CHECKING:
    from .client import Client

FINAL_STATES = ("done", "failed", "cancelled")

# What each phase of a solve is called on the bar (progress events' "phase", docs/API.md).
_PHASES = {"preparing_views": "preparing views", "analysing_reach": "analysing reach", "writing": "writing", "iterating": "iterating"}


class ProgressBar:
    """One line on a terminal, redrawn in place: `[#####-----] 12/30 iterating · RMS 0.0123`."""

    def __init__(self, stream: TextIO, width: int = 28):
        self.stream, self.width, self.shown, self.fraction = stream, width, False, None
        self.columns = shutil.get_terminal_size((80, 24)).columns - 1  # never wrap the line

    def update(self, fraction: float | None, text: str) -> None:
        if fraction is not None:
            self.fraction = fraction  # a phase after the first iteration keeps the bar where it was
        if self.fraction is None:
            bar = "[" + "." * self.width + "]"
        else:
            full = int(round(max(0.0, min(1.0, self.fraction)) * self.width))
            bar = "[" + "#" * full + "-" * (self.width - full) + "]"
        self.stream.write("\r" + (bar + " " + text)[:self.columns].ljust(self.columns))
        self.stream.flush()
        self.shown = True

    def close(self, text: str) -> None:
        if self.shown:
            self.stream.write("\r" + text[:self.columns].ljust(self.columns) + "\n")
            self.stream.flush()


def describe_progress(kind: str, p: dict, total: int | None) -> tuple[float | None, str]:
    """(fraction done or None, a line) for one progress event of a job of `kind`."""
    phase = p.get("phase")
    if "iteration" in p and (phase in (None, "iterating")):
        it = p["iteration"]
        rms = p.get("rms_per_view") or []
        line = f"{it}/{total} iterating" if total else f"iteration {it}"
        if rms:
            line += f" · RMS {sum(rms) / len(rms):.4g}"
        return (it / total if total else None), line
    if "frame" in p and "frames" in p:
        return (p["frame"] + 1) / max(1, p["frames"]), f"frame {p['frame'] + 1}/{p['frames']}"
    if phase:
        return None, _PHASES.get(phase, phase)
    return None, kind


class Job:
    """A job by id. `wait()` follows its event stream (SSE) to the end and returns the result or
    raises JobFailed; a dropped stream is resumed by reading the job's state again."""

    def __init__(self, client: "Client", job_id: str, kind: str = "job", total: int | None = None):
        self.client, self.id, self.kind, self.total = client, job_id, kind, total
        self.last: dict | None = None

    def __repr__(self) -> str:
        return f"Job({self.id!r}, kind={self.kind!r})"

    def info(self) -> dict:
        """GET /jobs/{jid}: {id, session, state, progress, result, error}."""
        self.last = self.client.get_job(self.id)
        return self.last

    @property
    def state(self) -> str:
        return self.info()["state"]

    def events(self) -> Iterator[tuple[str, Any]]:
        """The job's events as (name, data): progress, preview, then done | failed | cancelled."""
        return self.client.job_events(self.id)

    def cancel(self) -> dict:
        """DELETE /jobs/{jid}: asks the job to stop (a finished job stays as it ended)."""
        return self.client.cancel_job(self.id)

    def wait(self, progress: bool | TextIO | Callable[[str, dict], None] | None = None, timeout: float | None = None,
             cancel_on_interrupt: bool = True) -> dict:
        """Waits for the job's end; returns its `result` (raises JobFailed, or JobCancelled, when
        it did not finish). `progress`: None draws a bar on stderr when stderr is a terminal
        (quiet in scripts), True always, False never, a stream draws there, a callable gets
        (event, data) once per event. A stream that breaks off is followed again where it was.
        Ctrl-C, or an exception from the callable (a DCC's Cancel button), cancels the job on
        the server before it is raised (`cancel_on_interrupt=False` leaves the job running)."""
        callback: Callable[[str, dict], None] | None = None
        bar: ProgressBar | None = None
        if callable(progress) and not hasattr(progress, "write"):
            callback = progress  # type: ignore[assignment]
        elif progress is True or (progress is None and sys.stderr.isatty()):
            bar = ProgressBar(sys.stderr)
        elif progress not in (None, False):
            bar = ProgressBar(progress)  # type: ignore[arg-type]
        try:
            final = self._follow(callback, bar, timeout)
        except TimeoutError:
            raise  # waited long enough: the job goes on
        except (KeyboardInterrupt, Exception):
            if cancel_on_interrupt:
                try:
                    self.cancel()
                except Exception:  # the interrupt is what the caller must see
                    pass
            raise
        self.last = final
        if bar:
            bar.close(f"{self.kind} {final.get('state')}" + _summary(final))
        if final.get("state") != "done":
            raise JobFailed.of(final)
        return final.get("result") or {}

    def _follow(self, callback, bar, timeout) -> dict:
        """The job's final JSON, following its stream (and again after a break, past the events
        already seen: the server replays a stream from the first event)."""
        deadline = time.monotonic() + timeout if timeout else None
        seen = 0
        while True:
            try:
                for k, (name, data) in enumerate(self.events()):
                    if k < seen:
                        continue
                    seen += 1
                    if callback:
                        callback(name, data)
                    if name == "progress" and bar:
                        bar.update(*describe_progress(self.kind, data, self.total))
                    if name in FINAL_STATES:
                        return data
                    if deadline and time.monotonic() > deadline:
                        raise TimeoutError(f"job {self.id} still running after {timeout} s")
            except ConnectionFailed:
                pass  # the stream broke off: read the state, then follow the stream again
            info = self.info()
            if info["state"] in FINAL_STATES:
                return info
            if deadline and time.monotonic() > deadline:
                raise TimeoutError(f"job {self.id} still running after {timeout} s")
            time.sleep(0.2)


def _summary(job: dict) -> str:
    report = (job.get("result") or {}).get("report") or {}
    if "iterations" not in report:
        return ""
    mean = lambda v: sum(v) / len(v) if isinstance(v, list) and v else (v or 0.0)  # noqa: E731 (per view)
    return f": {report['iterations']} iterations ({report.get('stop_reason')}), RMS {mean(report.get('initial_rms')):.4g} → {mean(report.get('final_rms')):.4g}"
