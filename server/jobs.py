"""Training and evaluation jobs of the app: one child process per job, live progress, cancel, restart.

`JobManager` starts a job in its own process (spawned, so a job can use torch and its own worker
pool without touching the server), reads the job's events from a queue in a thread, keeps the
job's state in the run store's `jobs` table (so jobs are listed after a server restart; a job
that was running when the server stopped is marked "interrupted"), and fans events out to
subscribers (the Server-Sent Events route). Events:

    {"type": "status", "status": "running"}
    {"type": "progress", "stage", "epoch", "epochs", "loss", "points": [[pc1, pc2], ...], "labels": [...]}
    {"type": "run", "done", "total", "metrics"}                       (evaluation jobs)
    {"type": "done", "result": {...}}  /  {"type": "error", "error": "..."}

`points` is the PCA (model.metrics.CscPCA) of the Csc patterns the training stage is shaping at
that epoch (c_0 of MTRNN_a, c_T of the encoders), so a page can show them self-organise.

A finished training job writes its checkpoint to `<models_dir>/<name>/` (the app's model
folder), so the model registry (`/api/models`) can serve it, also after a restart.
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
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from model.experiments.runstore import RunStore

logger = logging.getLogger(__name__)

ACTIVE = ("queued", "running")
FINISHED = ("done", "failed", "cancelled", "interrupted")
TRAIN_MODES = ("faithful", "end_to_end")  # modes the app can serve (checkpoints of a MultiMTRNN)
EVALUATE_MODES = ("faithful", "end_to_end", "peer")
DEFAULT_DATA = "server.jobs:corpus_data"
PROGRESS_STORE_SECONDS = 1.0  # how often a job's latest progress is written to the store


def corpus_data(corpus_path: str | None = None) -> Any:
    """The whole encoded corpus as a SequenceSet (default data of a job)."""
    from data.corpus import load_corpus

    return load_corpus(Path(corpus_path) if corpus_path else None).training_data()


def _resolve(path: str) -> Callable[..., Any]:
    from model.experiments.protocol import resolve

    return resolve(path)


# --- the child process ----------------------------------------------------------------------------


def _die_with_parent() -> None:
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except OSError:
        logger.debug("prctl unavailable; a job may outlive a killed server")


class _ProgressRelay:
    """Training progress -> queue events, with the PCA of the Csc patterns being shaped."""

    def __init__(self, events: Any, labels: list[str]) -> None:
        self.events, self.labels = events, labels

    def __call__(self, report: dict) -> None:
        import numpy as np

        from model.metrics import CscPCA

        event = {"type": "progress", **{k: v for k, v in report.items() if k != "csc"}}
        csc = report.get("csc")
        if csc is not None:
            x = np.asarray(csc, dtype=np.float64)
            if x.ndim == 2 and x.shape[0] >= 2 and x.shape[1] >= 2 and np.ptp(x, axis=0).max() > 0:
                event["points"] = CscPCA(2).fit_transform(x).round(4).tolist()
                event["labels"] = self.labels[: len(x)]
        self.events.put(event)


def _train_job(params: dict, events: Any, data: Any, models_dir: Path) -> dict:
    from model import checkpoint
    from model.experiments.evaluation import fold_split, score_split, slot_vocabularies
    from model.experiments.protocol import apply_overrides, default_config
    from model.metrics import parse_slots
    from model.training import train

    mode, fold, seed = params["mode"], int(params.get("fold", 0)), int(params.get("seed", 0))
    config = apply_overrides(default_config(mode), params.get("overrides") or {})
    train_idx, test_idx = fold_split(data.ids, fold, seed=0)
    train_set, test_set = data.subset(train_idx), data.subset(test_idx)
    labels = [parse_slots(u)["action"] or "?" for u in train_set.utterances]
    from model.config import MultiMTRNNConfig

    trained = train(train_set, mode, MultiMTRNNConfig.from_dict(config), seed, _ProgressRelay(events, labels))
    vocab = slot_vocabularies(data.utterances)
    metrics = score_split(trained.model, trained.lexicon, train_set, test_set, vocab)
    meta = dict(trained.meta)
    meta.update(
        {
            "fold": fold,
            "split": {"train": list(train_set.ids), "test": list(test_set.ids)},
            "metrics": metrics,
            "job": params.get("job_id"),
        }
    )
    name = params["name"]
    checkpoint.save(trained.model, models_dir / name, meta, trained.csc)
    return {"model": name, "path": str(models_dir / name), "metrics": metrics}


def _evaluate_job(params: dict, events: Any, data: Any, run_dir: Path) -> dict:
    from model.experiments.protocol import (
        apply_overrides,
        data_digest,
        default_config,
        plan,
        run_protocol,
        runner_for,
        summarise,
    )

    mode = params["mode"]
    config = apply_overrides(default_config(mode), params.get("overrides") or {})
    specs = plan(
        "evaluate",
        mode,
        int(params["folds"]),
        int(params["inits"]),
        config,
        data_digest(data),
        int(params.get("seed", 0)),
    )

    def relay(event: dict) -> None:
        events.put(
            {"type": "run", **{k: event[k] for k in ("done", "total", "failed", "seconds", "metrics")}}
        )

    result = run_protocol(
        data,
        specs,
        RunStore(run_dir),
        "local",
        int(params.get("workers", 1)),
        runner=runner_for(mode),
        progress=relay,
    )
    return {
        "runs": len(result.runs),
        "executed": result.executed,
        "skipped": result.skipped,
        "failed": len(result.failed),
        "summary": summarise(result.runs),
    }


def _job_main(
    job: dict, events: Any, run_dir: str, models_dir: str, data_loader: str, data_arg: str | None
) -> None:
    _die_with_parent()
    os.setpgrp()  # its own process group: cancelling kills the job's worker pool too
    import torch

    torch.set_num_threads(1)
    try:
        events.put({"type": "status", "status": "running"})
        load = _resolve(data_loader)
        data = load(data_arg) if data_arg is not None else load()
        if job["kind"] == "train":
            result = _train_job(job["params"], events, data, Path(models_dir))
        else:
            result = _evaluate_job(job["params"], events, data, Path(run_dir))
        events.put({"type": "done", "result": result})
    except Exception:
        events.put({"type": "error", "error": traceback.format_exc()})


# --- the server side --------------------------------------------------------------------------------


@dataclass
class _Running:
    process: Any
    events: Any
    thread: threading.Thread
    cancelled: bool = False


@dataclass
class Subscriber:
    """A listener of one job's events: `push` is called from the reader thread."""

    push: Callable[[dict], None]
    job_id: str
    token: str = field(default_factory=lambda: secrets.token_hex(4))


class JobManager:
    """Jobs of one app: start, list, cancel, subscribe; state kept in `<run_dir>/runs.sqlite`."""

    def __init__(
        self,
        run_dir: Path,
        models_dir: Path,
        data_loader: str = DEFAULT_DATA,
        data_arg: str | None = None,
        on_model: Callable[[str, Path], None] | None = None,
    ) -> None:
        self.run_dir, self.models_dir = Path(run_dir), Path(models_dir)
        self.store = RunStore(self.run_dir)
        self.data_loader, self.data_arg, self.on_model = data_loader, data_arg, on_model
        self._running: dict[str, _Running] = {}
        self._latest: dict[str, dict] = {}
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
        if latest is not None:
            job = {**job, "progress": latest}
        return job

    # --- commands
    def start(self, kind: str, params: dict) -> dict:
        """Validate and start a job; returns its row. Raises ValueError on bad parameters."""
        params = dict(params)
        if kind == "train":
            if params.get("mode") not in TRAIN_MODES:
                raise ValueError(f"a training job needs mode in {TRAIN_MODES}, got {params.get('mode')!r}")
        elif kind == "evaluate":
            if params.get("mode") not in EVALUATE_MODES:
                raise ValueError(
                    f"an evaluation job needs mode in {EVALUATE_MODES}, got {params.get('mode')!r}"
                )
            for key in ("folds", "inits"):
                if int(params.get(key, 0)) < 1:
                    raise ValueError(f"an evaluation job needs {key} >= 1")
        else:
            raise ValueError(f"unknown job kind {kind!r}: train or evaluate")
        from model.experiments.protocol import apply_overrides, default_config

        try:
            apply_overrides(default_config(params["mode"]), params.get("overrides") or {})
        except KeyError as err:
            raise ValueError(str(err.args[0])) from None
        job_id = time.strftime("%Y%m%d-%H%M%S-") + secrets.token_hex(3)
        params["job_id"] = job_id
        if kind == "train":
            name = (
                params.get("name")
                or f"{params['mode']}-f{params.get('fold', 0)}-s{params.get('seed', 0)}-{job_id[-6:]}"
            )
            if not name.replace("-", "").replace("_", "").isalnum():
                raise ValueError(f"model name {name!r}: use letters, digits, '-' and '_' only")
            if (self.models_dir / name).exists():
                raise ValueError(f"a model named {name!r} exists already")
            params["name"] = name
        self.store.put_job(job_id, kind, params, "queued")
        job = {"id": job_id, "kind": kind, "params": params}
        ctx = multiprocessing.get_context("spawn")
        events = ctx.Queue()
        process = ctx.Process(
            target=_job_main,
            args=(job, events, str(self.run_dir), str(self.models_dir), self.data_loader, self.data_arg),
            name=f"job-{job_id}",
            daemon=False,
        )
        process.start()
        thread = threading.Thread(
            target=self._pump, args=(job_id, kind), name=f"job-events-{job_id}", daemon=True
        )
        with self._lock:
            self._running[job_id] = _Running(process, events, thread)
        thread.start()
        logger.info("job %s (%s %s) started, pid %d", job_id, kind, params.get("mode"), process.pid)
        return self.get(job_id) or job

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

    def is_running(self, job_id: str) -> bool:
        with self._lock:
            return job_id in self._running

    def shutdown(self) -> None:
        """Stop every running job (server shutdown); they are recorded as interrupted."""
        with self._lock:
            ids = list(self._running)
        for job_id in ids:
            self.cancel(job_id)
            self.store.update_job(
                job_id, status="interrupted", error="the server stopped while this job was running"
            )

    # --- the reader thread
    def _publish(self, job_id: str, event: dict) -> None:
        with self._lock:
            subs = [s for s in self._subscribers if s.job_id == job_id]
        for s in subs:
            try:
                s.push(event)
            except Exception:  # a closed client must not stop the job's bookkeeping
                logger.debug("dropping a subscriber of job %s", job_id, exc_info=True)

    def _pump(self, job_id: str, kind: str) -> None:
        running = self._running[job_id]
        last_store = 0.0
        final: dict | None = None
        while True:
            try:
                event = running.events.get(timeout=0.5)
            except queue.Empty:
                if not running.process.is_alive():
                    break
                continue
            if event["type"] == "status":
                self.store.update_job(job_id, status=event["status"])
            elif event["type"] in ("progress", "run"):
                self._latest[job_id] = event
                if time.monotonic() - last_store > PROGRESS_STORE_SECONDS:
                    self.store.update_job(job_id, progress=event)
                    last_store = time.monotonic()
            if event["type"] in ("done", "error"):  # published after the bookkeeping, with the status
                final = event
                break
            self._publish(job_id, event)
        running.process.join(timeout=10)
        if job_id in self._latest:
            self.store.update_job(job_id, progress=self._latest[job_id])
        if running.cancelled:
            self.store.update_job(job_id, status="cancelled", error="cancelled by the user")
            final = {"type": "cancelled"}
        elif final is None:
            code = running.process.exitcode
            final = {"type": "error", "error": f"the job's process ended without a result (exit code {code})"}
            self.store.update_job(job_id, status="failed", error=final["error"])
        elif final["type"] == "error":
            self.store.update_job(job_id, status="failed", error=final["error"])
        else:
            self.store.update_job(job_id, status="done", result=final["result"])
            if kind == "train" and self.on_model is not None:
                self.on_model(final["result"]["model"], Path(final["result"]["path"]))
        with self._lock:
            self._running.pop(job_id, None)
        self._publish(job_id, {**final, "status": (self.get(job_id) or {}).get("status")})
        logger.info("job %s ended: %s", job_id, (self.get(job_id) or {}).get("status"))
