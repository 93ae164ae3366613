"""The one job system of the app: start, queue, list, cancel and follow jobs of every kind (`jobs.kinds`).

A train or evaluate job is checked (`kinds`, `bounds`; its model's name must be free), kept in the
jobs table (`jobs.store`, `<user_dir>/jobs.sqlite`: listed after a restart, unfinished ones marked
"interrupted") and queued. At most `settings.max_jobs` run at once, each in its own process
(`jobs.child`); the others wait in order, with their position in the queue. Every process is
started by the manager's one long-lived launcher thread: a child dies when the thread that
started it ends (PR_SET_PDEATHSIG), so a short-lived request thread must never start one. A
thread per running job reads its events, keeps its state in the table and fans the events (finite
JSON, `jobs.events`) out to subscribers (the Server-Sent Events route). A cosine run (lesson 5)
runs in a thread of the server and is kept in memory; its events take the same way.

A finished training job's checkpoint is in `<user_dir>/models/<name>/`; `on_model(name, path)`
lets the model registry serve it.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import queue
import secrets
import signal
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from server.jobs.child import job_main
from server.jobs.events import finite, public_error
from server.jobs.kinds import (
    PROCESS_KINDS,
    CosineRecord,
    new_job_id,
    run_cosine,
    validate_cosine,
)
from server.jobs.store import INTERRUPTED, JobStore
from server.services.errors import Conflict, Invalid, NotFound
from server.services.models import user_models
from server.settings import Settings

logger = logging.getLogger(__name__)

ACTIVE = ("queued", "running")
PROGRESS_STORE_SECONDS = 1.0  # how often a job's latest progress is written to the store
KEPT_COSINE_RUNS = 64  # finished cosine runs kept for replay


@dataclass
class _Running:
    process: Any
    events: Any
    params: dict
    cancelled: bool = False
    last_store: float = 0.0


@dataclass
class Subscriber:
    """A listener of one job's events: `push` is called from the reader thread."""

    push: Callable[[dict], None]
    job_id: str
    token: str = field(default_factory=lambda: secrets.token_hex(4))


class JobManager:
    """Jobs of one app; train and evaluate jobs kept in `<user_dir>/jobs.sqlite`."""

    def __init__(self, settings: Settings, on_model: Callable[[str, Path], None] | None = None) -> None:
        self.settings, self.on_model = settings, on_model
        self.store = JobStore(settings.user_dir)
        self._running: dict[str, _Running] = {}
        self._queue: list[dict] = []  # jobs waiting for a slot, first to start first
        self._latest: dict[str, dict] = {}
        self._cosine: OrderedDict[str, CosineRecord] = OrderedDict()
        self._subscribers: list[Subscriber] = []
        self._lock = threading.RLock()
        self._wake = threading.Condition(self._lock)
        self.closing = threading.Event()
        interrupted = self.store.mark_interrupted(ACTIVE)
        if interrupted:
            logger.info("jobs interrupted by the last shutdown: %s", ", ".join(interrupted))
        self._launcher = threading.Thread(target=self._launch_loop, name="job-launcher", daemon=True)
        self._launcher.start()

    # --- queries
    def list(self) -> list[dict]:
        return [self._view(j) for j in self.store.jobs()]

    def get(self, job_id: str) -> dict | None:
        jobs = self.store.jobs(job_id)
        return self._view(jobs[0]) if jobs else None

    def _view(self, job: dict) -> dict:
        with self._lock:
            latest = self._latest.get(job["id"])
            position = next((i + 1 for i, q in enumerate(self._queue) if q["id"] == job["id"]), None)
        view = job if latest is None else {**job, "progress": latest}
        return {**view, "position": position} if position is not None else view

    def cosine_run(self, run_id: str) -> CosineRecord:
        run = self._cosine.get(run_id)
        if run is None:
            raise NotFound(f"no cosine run {run_id!r} (runs are kept while the server runs)")
        return run

    def is_running(self, job_id: str) -> bool:
        with self._lock:
            return job_id in self._running

    def is_active(self, job_id: str) -> bool:
        """Queued or running."""
        with self._lock:
            return job_id in self._running or any(q["id"] == job_id for q in self._queue)

    def process_id(self, job_id: str) -> int | None:
        """The process of a running job (the server's log names it too)."""
        with self._lock:
            running = self._running.get(job_id)
            return running.process.pid if running is not None else None

    # --- commands
    def start(self, kind: str, params: dict) -> dict:
        """Check a train or evaluate job and queue it; returns its row (with its queue position).
        Raises Invalid (bad parameters) or Conflict (its model's name is taken)."""
        if kind not in PROCESS_KINDS:
            raise Invalid(f"unknown job kind {kind!r}: train or evaluate")
        if self.closing.is_set():
            raise Conflict("the server is stopping; start the job again once it is back")
        job_id = new_job_id()
        validate, _ = PROCESS_KINDS[kind]
        params = validate(dict(params), job_id, self.settings)
        with self._lock:
            if kind == "train":
                self._check_name(params["name"])
            self.store.put(job_id, kind, params, "queued")
            self._queue.append({"id": job_id, "kind": kind, "params": params})
            self._wake.notify_all()
        logger.info("job %s (%s %s) queued", job_id, kind, params.get("mode"))
        return self.get(job_id) or {"id": job_id}

    def _check_name(self, name: str) -> None:
        """Conflict when a shipped model, a model of the app or an unfinished job has `name`."""
        for folder, whose in (
            (self.settings.models_dir, "a shipped model"),
            (user_models(self.settings), "a model"),
        ):
            if (folder / name).exists():
                raise Conflict(f"name {name!r} is taken by {whose}; pick another name")
        jobs = [q["params"] for q in self._queue] + [r.params for r in self._running.values()]
        if any(p.get("name") == name for p in jobs):
            raise Conflict(f"name {name!r} is taken by an unfinished job; pick another name")

    def start_cosine(self, psi: float, seed: int) -> CosineRecord:
        """A live cosine run, one at a time; the kept run when (psi, seed) ran already."""
        params = validate_cosine({"psi": psi, "seed": seed}, "", self.settings)
        with self._lock:
            for run in self._cosine.values():
                if run.key == (params["psi"], params["seed"]) and run.status != "failed":
                    return run
            busy = [r for r in self._cosine.values() if r.status in ACTIVE]
            if busy:
                raise Conflict(
                    f"a cosine run (psi = {busy[0].psi:g}) is still in progress; try again when it ends"
                )
            run = CosineRecord(secrets.token_hex(6), params["psi"], params["seed"], params["epochs"])
            self._cosine[run.id] = run
            while len(self._cosine) > KEPT_COSINE_RUNS:  # forget the oldest finished runs
                self._cosine.popitem(last=False)
        threading.Thread(
            target=self._run_thread, args=(run, params), name=f"cosine-{run.id}", daemon=True
        ).start()
        return run

    def cancel(self, job_id: str) -> bool:
        """Take a queued job off the queue, or kill a running one (and its worker pool); False if
        it is neither."""
        with self._lock:
            waiting = next((q for q in self._queue if q["id"] == job_id), None)
            if waiting is not None:
                self._queue.remove(waiting)
                self.store.update(job_id, status="cancelled", error="cancelled by the user")
            running = self._running.get(job_id)
            if running is not None:
                running.cancelled = True
        if waiting is not None:
            self._publish(job_id, {"type": "cancelled", "status": "cancelled"})
            return True
        if running is None:
            return False
        try:
            os.killpg(running.process.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            running.process.kill()
        return True

    def subscribe(self, job_id: str, push: Callable[[dict], None]) -> Subscriber:
        sub = Subscriber(push, job_id)
        with self._lock:
            self._subscribers.append(sub)
        return sub

    def unsubscribe(self, sub: Subscriber) -> None:
        with self._lock:
            if sub in self._subscribers:
                self._subscribers.remove(sub)

    def shutdown(self) -> None:
        """Stop every job (server shutdown): queued and running ones are recorded as interrupted."""
        with self._lock:
            self.closing.set()
            waiting, self._queue = self._queue, []
            ids = list(self._running)
            self._wake.notify_all()
        for job in waiting:
            self.store.update(job["id"], status="interrupted", error=INTERRUPTED)
        for job_id in ids:
            self.cancel(job_id)
            self.store.update(job_id, status="interrupted", error=INTERRUPTED)
        self._launcher.join(timeout=5)

    # --- the launcher thread: starts every job's process, never more than max_jobs at once
    def _launch_loop(self) -> None:
        while True:
            with self._lock:
                while not self.closing.is_set() and not (
                    self._queue and len(self._running) < self.settings.max_jobs
                ):
                    self._wake.wait()
                if self.closing.is_set():
                    return
                job = self._queue.pop(0)
                try:
                    self._launch(job)
                except OSError as err:  # e.g. no memory left to start a process: the job fails, not the app
                    logger.exception("job %s could not start", job["id"])
                    self.store.update(job["id"], status="failed", error=public_error(err))

    def _launch(self, job: dict) -> None:
        """Start `job`'s process from this (the launcher) thread and a thread reading its events."""
        ctx = multiprocessing.get_context("spawn")
        events = ctx.Queue()
        process = ctx.Process(
            target=job_main, args=(job, events, self.settings, os.getpid()), name=f"job-{job['id']}"
        )
        process.start()
        self._running[job["id"]] = _Running(process, events, job["params"])
        threading.Thread(
            target=self._pump, args=(job["id"], job["kind"]), name=f"job-events-{job['id']}", daemon=True
        ).start()
        logger.info(
            "job %s (%s %s) started, pid %d", job["id"], job["kind"], job["params"].get("mode"), process.pid
        )

    # --- the reader threads
    def _publish(self, job_id: str, event: dict) -> None:
        with self._lock:
            subs = [s for s in self._subscribers if s.job_id == job_id]
        for s in subs:
            try:
                s.push(event)
            except Exception:  # a closed client must not stop the job's bookkeeping
                logger.debug("dropping a subscriber of job %s", job_id, exc_info=True)

    def _run_thread(self, run: CosineRecord, params: dict) -> None:
        """A cosine run in this thread: its events update its record and reach its subscribers."""

        def emit(event: dict) -> None:
            event = finite(event)
            run.apply(event)
            self._publish(run.id, event)

        started = time.perf_counter()
        emit({"type": "status", "status": "running"})
        try:
            final = {"type": "done", "result": run_cosine(params, emit, self.settings)}
        except Exception as err:  # the learner sees the message; the log keeps the traceback
            logger.exception("cosine run %s failed", run.id)
            final = {"type": "error", "error": public_error(err)}
        run.seconds = time.perf_counter() - started
        emit({**final, "status": "done" if final["type"] == "done" else "failed"})

    def _record(self, job_id: str, running: _Running, event: dict) -> None:
        """Keep a process job's status and latest progress (in the store at most once a second)."""
        if event["type"] == "status":
            self.store.update(job_id, status=event["status"])
        elif event["type"] in ("progress", "run"):
            self._latest[job_id] = event
            if time.monotonic() - running.last_store > PROGRESS_STORE_SECONDS:
                self.store.update(job_id, progress=event)
                running.last_store = time.monotonic()

    def _next_event(self, job_id: str, running: _Running) -> dict | None:
        """The job's next event (finite; an error's traceback goes to the log); None once its
        process has ended without sending one."""
        while True:
            try:
                event = running.events.get(timeout=0.5)
            except queue.Empty:
                if not running.process.is_alive():
                    return None
                continue
            if "traceback" in event:
                logger.error("job %s failed:\n%s", job_id, event.pop("traceback"))
            return finite(event)

    def _pump(self, job_id: str, kind: str) -> None:
        running = self._running[job_id]
        final: dict | None = None
        while (event := self._next_event(job_id, running)) is not None:
            self._record(job_id, running, event)
            if event["type"] in ("done", "error"):  # published after the bookkeeping, with the status
                final = event
                break
            self._publish(job_id, event)
        running.process.join(timeout=10)
        final = self._finish(job_id, kind, running, final)
        status = (self.get(job_id) or {}).get("status")
        self._publish(job_id, {**final, "status": status})  # before it leaves: no stream misses it
        with self._lock:
            self._running.pop(job_id, None)
            self._wake.notify_all()  # a slot is free
        logger.info("job %s ended: %s", job_id, status)

    def _finish(self, job_id: str, kind: str, running: _Running, final: dict | None) -> dict:
        """Record how a process job ended; returns the event that says so."""
        if job_id in self._latest:
            self.store.update(job_id, progress=self._latest[job_id])
        if running.cancelled and self.closing.is_set():
            self.store.update(job_id, status="interrupted", error=INTERRUPTED)
            return {"type": "cancelled"}
        if running.cancelled:
            self.store.update(job_id, status="cancelled", error="cancelled by the user")
            return {"type": "cancelled"}
        if final is None:
            code = running.process.exitcode
            final = {"type": "error", "error": f"the job's process ended without a result (exit code {code})"}
        if final["type"] == "error":
            self.store.update(job_id, status="failed", error=final["error"])
            return final
        self.store.update(job_id, status="done", result=final["result"])
        if kind == "train" and self.on_model is not None:
            name = final["result"]["model"]
            self.on_model(name, user_models(self.settings) / name)
        return final
