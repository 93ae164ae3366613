"""The one job system of the app: start, list, cancel and follow jobs of every kind (`jobs.kinds`).

A train or evaluate job runs in its own process (spawned, so it can use torch and its own worker
pool without touching the server); a thread reads its events from a queue, keeps its state in the
jobs table (`jobs.store`: listed after a restart, unfinished ones marked "interrupted") and fans
the events out to subscribers (the Server-Sent Events route). A cosine run (lesson 5) runs in a
thread of the server and is kept in memory; its events take the same way.

A finished training job's checkpoint is in `<models_dir>/<name>/`; `on_model(name, path)` lets
the model registry serve it.
"""

from __future__ import annotations

import ctypes
import logging
import multiprocessing
import os
import queue
import secrets
import signal
import threading
import time
import traceback
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from model.experiments.protocol import resolve
from server.jobs.kinds import PROCESS_KINDS, CosineRecord, new_job_id, run_cosine, validate_cosine
from server.jobs.store import INTERRUPTED, JobStore
from server.services.errors import Conflict, Invalid, NotFound
from server.settings import Settings

logger = logging.getLogger(__name__)

ACTIVE = ("queued", "running")
PROGRESS_STORE_SECONDS = 1.0  # how often a job's latest progress is written to the store
KEPT_COSINE_RUNS = 64  # finished cosine runs kept for replay


# --- the child process ----------------------------------------------------------------------------


def _die_with_parent() -> None:
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except OSError:
        logger.debug("prctl unavailable; a job may outlive a killed server")


def _job_main(job: dict, events: Any, settings: Settings) -> None:
    _die_with_parent()
    os.setpgrp()  # its own process group: cancelling kills the job's worker pool too
    import torch

    torch.set_num_threads(1)
    try:
        events.put({"type": "status", "status": "running"})
        load = resolve(settings.job_data)
        data = load(str(settings.corpus_path)) if settings.corpus_path else load()
        _, work = PROCESS_KINDS[job["kind"]]
        result = work(job["params"], events.put, data, settings)
        events.put({"type": "done", "result": result})
    except Exception:
        events.put({"type": "error", "error": traceback.format_exc()})


# --- the server side --------------------------------------------------------------------------------


@dataclass
class _Running:
    process: Any
    events: Any
    cancelled: bool = False
    last_store: float = 0.0


@dataclass
class Subscriber:
    """A listener of one job's events: `push` is called from the reader thread."""

    push: Callable[[dict], None]
    job_id: str
    token: str = field(default_factory=lambda: secrets.token_hex(4))


class JobManager:
    """Jobs of one app; train and evaluate jobs kept in `<run_dir>/jobs.sqlite`."""

    def __init__(self, settings: Settings, on_model: Callable[[str, Path], None] | None = None) -> None:
        self.settings, self.on_model = settings, on_model
        self.store = JobStore(settings.run_dir)
        self._running: dict[str, _Running] = {}
        self._latest: dict[str, dict] = {}
        self._cosine: OrderedDict[str, CosineRecord] = OrderedDict()
        self._subscribers: list[Subscriber] = []
        self._lock = threading.RLock()
        interrupted = self.store.mark_interrupted(ACTIVE)
        if interrupted:
            logger.info("jobs interrupted by the last shutdown: %s", ", ".join(interrupted))

    # --- queries
    def list(self) -> list[dict]:
        return [self._view(j) for j in self.store.jobs()]

    def get(self, job_id: str) -> dict | None:
        jobs = self.store.jobs(job_id)
        return self._view(jobs[0]) if jobs else None

    def _view(self, job: dict) -> dict:
        latest = self._latest.get(job["id"])
        return job if latest is None else {**job, "progress": latest}

    def cosine_run(self, run_id: str) -> CosineRecord:
        run = self._cosine.get(run_id)
        if run is None:
            raise NotFound(f"no cosine run {run_id!r} (runs are kept while the server runs)")
        return run

    def is_running(self, job_id: str) -> bool:
        with self._lock:
            return job_id in self._running

    # --- commands
    def start(self, kind: str, params: dict) -> dict:
        """Validate and start a train or evaluate job; returns its row. Raises Invalid."""
        if kind not in PROCESS_KINDS:
            raise Invalid(f"unknown job kind {kind!r}: train or evaluate")
        job_id = new_job_id()
        validate, _ = PROCESS_KINDS[kind]
        params = validate(dict(params), job_id, self.settings)
        self.store.put(job_id, kind, params, "queued")
        ctx = multiprocessing.get_context("spawn")
        events = ctx.Queue()
        job = {"id": job_id, "kind": kind, "params": params}
        process = ctx.Process(target=_job_main, args=(job, events, self.settings), name=f"job-{job_id}")
        process.start()
        with self._lock:
            self._running[job_id] = _Running(process, events)
        threading.Thread(
            target=self._pump, args=(job_id, kind), name=f"job-events-{job_id}", daemon=True
        ).start()
        logger.info("job %s (%s %s) started, pid %d", job_id, kind, params.get("mode"), process.pid)
        return self.get(job_id) or job

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
        """Kill a running job (and its worker pool); False if it is not running."""
        with self._lock:
            running = self._running.get(job_id)
            if running is None:
                return False
            running.cancelled = True
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
        """Stop every running job (server shutdown); they are recorded as interrupted."""
        with self._lock:
            ids = list(self._running)
        for job_id in ids:
            self.cancel(job_id)
            self.store.update(job_id, status="interrupted", error=INTERRUPTED)

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
            run.apply(event)
            self._publish(run.id, event)

        started = time.perf_counter()
        emit({"type": "status", "status": "running"})
        try:
            final = {"type": "done", "result": run_cosine(params, emit, self.settings)}
        except Exception as err:  # the learner sees the message; the log keeps the traceback
            logger.exception("cosine run %s failed", run.id)
            final = {"type": "error", "error": f"{type(err).__name__}: {err}"}
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

    def _next_event(self, running: _Running) -> dict | None:
        """The job's next event; None once its process has ended without sending one."""
        while True:
            try:
                return running.events.get(timeout=0.5)
            except queue.Empty:
                if not running.process.is_alive():
                    return None

    def _pump(self, job_id: str, kind: str) -> None:
        running = self._running[job_id]
        final: dict | None = None
        while (event := self._next_event(running)) is not None:
            self._record(job_id, running, event)
            if event["type"] in ("done", "error"):  # published after the bookkeeping, with the status
                final = event
                break
            self._publish(job_id, event)
        running.process.join(timeout=10)
        final = self._finish(job_id, kind, running, final)
        with self._lock:
            self._running.pop(job_id, None)
        status = (self.get(job_id) or {}).get("status")
        self._publish(job_id, {**final, "status": status})
        logger.info("job %s ended: %s", job_id, status)

    def _finish(self, job_id: str, kind: str, running: _Running, final: dict | None) -> dict:
        """Record how a process job ended; returns the event that says so."""
        if job_id in self._latest:
            self.store.update(job_id, progress=self._latest[job_id])
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
            self.on_model(final["result"]["model"], Path(final["result"]["path"]))
        return final
