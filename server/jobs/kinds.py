"""The kinds of job the app runs: what each validates, where it runs and what it does.

    train     one model (`model.experiments.evaluation.run_once`), saved to the app's own models
              folder (`<user_dir>/models`, beside none of the shipped ones)
    evaluate  K folds x N initialisations of one mode (`model.experiments.protocol.run_protocol`)
              into the app's own run store (`<user_dir>/runs`, not the one `mtrnn report` reads)
    cosine    the cosine experiment of 3.2.2 for one psi, live in lesson 5 (`train_cosine_once`)

A job's config is its mode's defaults, scaled by its epoch preset (`presets`), then its overrides,
every key and value checked before it is queued (`bounds`). Both process kinds take a protocol
`split` (`model.experiments.splits`: "scenes", the paper's 50:50, by default) and, for the size
split, `train_scenes`, checked before the job is queued too (`bounds.check_split`).

Train and evaluate run in a child process and are kept in the jobs table; a cosine run is small,
runs in a thread of the server and is kept in memory (a run is deterministic in (psi, seed), so
asking for it again returns the kept one). Events a job sends (its kind's shapes):

    {"type": "status", "status": "running"}
    {"type": "progress", "stage", "epoch", "epochs", "loss", "eta", "seconds",
     "points": [[pc1, pc2], ...], "labels": [...]}                       ("attempt", "attempts" too
                                                                           while a stage restarts)
    {"type": "run", "done", "total", "failed", "seconds", "eta", "metrics"}  (evaluate)
    {"type": "progress", "epoch", "loss", "frame": {...}, "seconds"}         (cosine)
    {"type": "done", "result": {...}}  /  {"type": "error", "error": "..."}

"eta" is the seconds left (of the stage, or of the evaluation) at the pace so far, None at first.
"""

from __future__ import annotations

import importlib
import json
import math
import os
import secrets
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from model.experiments.protocol import default_config
from model.metrics import CscPCA
from server.jobs.bounds import check_overrides, check_split
from server.jobs.presets import PRESETS, scale_epochs
from server.lessons.abstracting import snapshot
from server.services.errors import Invalid
from server.services.models import user_models
from server.settings import Settings

TRAIN_MODES = ("faithful", "end_to_end")  # modes the app can serve (checkpoints of a MultiMTRNN)
EVALUATE_MODES = ("faithful", "end_to_end", "peer")
Emit = Callable[[dict], None]


def corpus_data(corpus_path: str | None = None) -> Any:
    """The whole encoded corpus as a SequenceSet (default data of a job)."""
    from data.corpus import load_corpus

    return load_corpus(Path(corpus_path) if corpus_path else None).training_data()


def user_runs(settings: Settings) -> Path:
    """The run store of the app's evaluation jobs."""
    return settings.user_dir / "runs"


def _split(params: dict) -> dict:
    """The job's protocol split as `run_once` and `plan` take it: {"split", "train_scenes"}."""
    return {"split": params.get("split") or "scenes", "train_scenes": params.get("train_scenes")}


def _config(params: dict) -> dict:
    """The job's mode's defaults, scaled by its preset, with its overrides (all checked)."""
    mode = params["mode"]
    base = default_config(mode)
    if params.get("preset"):
        base = scale_epochs(base, mode, PRESETS[params["preset"]].scale)
    return check_overrides(mode, params.get("overrides") or {}, base)


class _Pace:
    """Seconds left at the pace so far: `eta(done, total)` for one stage (or one evaluation)."""

    def __init__(self) -> None:
        self.first: tuple[float, float] | None = None

    def eta(self, done: float, total: float) -> float | None:
        now = time.monotonic()
        if self.first is None:
            self.first = (now, done)
            return None
        t0, d0 = self.first
        if done <= d0:
            return None
        return round((now - t0) / (done - d0) * max(0.0, total - done), 1)


# --- train ------------------------------------------------------------------------------------------


class _ProgressRelay:
    """Training progress -> events, with the PCA of the Csc patterns being shaped and the time
    left in the stage (a restarted stage, a new attempt, starts its own pace)."""

    def __init__(self, emit: Emit, labels: list[str]) -> None:
        self.emit, self.labels = emit, labels
        self.started = time.monotonic()
        self.paces: dict[tuple, _Pace] = {}

    def __call__(self, report: dict) -> None:
        event = {"type": "progress", **{k: v for k, v in report.items() if k != "csc"}}
        pace = self.paces.setdefault((report["stage"], report.get("attempt")), _Pace())
        event["eta"] = pace.eta(report["epoch"], report["epochs"])
        event["seconds"] = round(time.monotonic() - self.started, 1)
        csc = report.get("csc")
        if csc is not None:
            x = np.asarray(csc, dtype=np.float64)
            if x.ndim == 2 and x.shape[0] >= 2 and x.shape[1] >= 2 and np.ptp(x, axis=0).max() > 0:
                event["points"] = CscPCA(2).fit_transform(x).round(4).tolist()
                event["labels"] = self.labels[: len(x)]
        self.emit(event)


def validate_train(params: dict, job_id: str, settings: Settings) -> dict:
    """The checked params of a training job, with its model's name (the manager checks it is free)."""
    if params.get("mode") not in TRAIN_MODES:
        raise Invalid(f"a training job needs mode in {TRAIN_MODES}, got {params.get('mode')!r}")
    _config(params)
    fold, seed, split = params.get("fold", 0), params.get("seed", 0), _split(params)
    check_split(split["split"], split["train_scenes"], fold=fold)
    mode = params["mode"].replace("_", "-")
    name = params.get("name") or f"{mode}-{_split_label(split)}f{fold}-s{seed}-{job_id[-6:]}"
    return {**params, "job_id": job_id, "name": name}


def _split_label(split: dict) -> str:
    """A default model name's part: none for the paper's split, else e.g. "objects-" or "size16-"."""
    if split["split"] == "scenes":
        return ""
    return f"{split['split']}{split['train_scenes'] or ''}-"


def run_train(params: dict, emit: Emit, data: Any, settings: Settings) -> dict:
    """Split, train, score and save one model (`run_once`); the job's id joins its meta.json."""
    from model import checkpoint
    from model.experiments.evaluation import run_once
    from model.experiments.splits import split_indices
    from model.metrics import parse_slots

    fold, seed, out = (
        int(params.get("fold", 0)),
        int(params.get("seed", 0)),
        user_models(settings) / params["name"],
    )
    split = _split(params)
    train_idx, _ = split_indices(data.ids, data.utterances, fold, **split)
    labels = [parse_slots(data.utterances[i])["action"] or "?" for i in train_idx]
    relay = _ProgressRelay(emit, labels)
    run = run_once(data, params["mode"], fold, seed, _config(params), out, relay, **split)
    meta_path = out / checkpoint.META
    meta = {**json.loads(meta_path.read_text()), "job": params.get("job_id")}
    partial = meta_path.with_suffix(".partial")
    partial.write_text(json.dumps(meta, indent=2, sort_keys=True))
    os.replace(partial, meta_path)  # atomic: the registry never reads half a meta.json
    return {"model": params["name"], "metrics": run.metrics}


# --- evaluate ---------------------------------------------------------------------------------------


def validate_evaluate(params: dict, job_id: str, settings: Settings) -> dict:
    if params.get("mode") not in EVALUATE_MODES:
        raise Invalid(f"an evaluation job needs mode in {EVALUATE_MODES}, got {params.get('mode')!r}")
    _config(params)
    split = _split(params)
    check_split(split["split"], split["train_scenes"], folds=int(params.get("folds", 1)))
    return {**params, "job_id": job_id}


def run_evaluate(params: dict, emit: Emit, data: Any, settings: Settings) -> dict:
    """K x N runs of one mode into the run store, with one event per finished run."""
    from model.experiments.protocol import data_digest, plan, run_protocol, summarise
    from model.experiments.runstore import RunStore

    folds, inits, seed = int(params["folds"]), int(params["inits"]), int(params.get("seed", 0))
    digest = data_digest(data)
    specs = plan("evaluate", params["mode"], folds, inits, _config(params), digest, seed, **_split(params))

    store = RunStore(user_runs(settings))
    pace = _Pace()
    pace.eta(len(store.done_keys([s.key for s in specs])), len(specs))  # runs of an earlier try count

    def relay(event: dict) -> None:
        keys = ("done", "total", "failed", "seconds", "metrics")
        emit({"type": "run", **{k: event[k] for k in keys}, "eta": pace.eta(event["done"], event["total"])})

    result = run_protocol(data, specs, store, "local", int(params.get("workers", 1)), progress=relay)
    return {
        "runs": len(result.runs),
        "executed": result.executed,
        "skipped": result.skipped,
        "failed": len(result.failed),
        "summary": summarise(result.runs),
    }


# --- cosine (lesson 5) ------------------------------------------------------------------------------


def validate_cosine(params: dict, job_id: str, settings: Settings) -> dict:
    psi, seed = params["psi"], params["seed"]
    if not (math.isfinite(psi) and 0.0 <= psi <= 0.01):
        raise Invalid(f"psi must be between 0 and 0.01 (the paper tries 0 .. 2e-4), got {psi}")
    if not 0 <= seed <= 10_000:
        raise Invalid(f"seed must be in 0..10000, got {seed}")
    return {"psi": float(psi), "seed": int(seed), "epochs": settings.cosine_epochs}


def run_cosine(params: dict, emit: Emit, settings: Settings) -> dict:
    """One seeded run of the cosine experiment, one thread, a Csc snapshot every few epochs."""
    import torch

    from model.experiments.cosine import CosineSetup, train_cosine_once

    started = time.perf_counter()

    def progress(info: dict) -> None:
        loss = round(float(info.get("error", info.get("loss", 0.0))), 7)
        emit(
            {
                "type": "progress",
                "epoch": int(info["epoch"]),
                "loss": loss,
                "frame": snapshot(info),
                "seconds": time.perf_counter() - started,
            }
        )

    threads = torch.get_num_threads()
    try:
        torch.set_num_threads(1)
        setup = CosineSetup(max_epochs=params["epochs"], snapshot_every=settings.cosine_snapshot_every)
        run = train_cosine_once(params["psi"], params["seed"], setup, progress)
    finally:
        torch.set_num_threads(threads)
    keys = ("epochs", "converged", "d_avg", "d_rel", "target_d_avg", "target_d_rel")
    return {k: getattr(run, k) for k in keys}


@dataclass
class CosineRecord:
    """A live cosine run as lesson 5 polls it (kept in memory, `public(since)` pages its frames)."""

    id: str
    psi: float
    seed: int
    epochs: int  # upper bound of the run (it stops earlier once the error is below threshold)
    status: str = "queued"  # queued, running, done, failed
    epoch: int = 0
    loss: float | None = None
    frames: list[dict] = field(default_factory=list)  # Csc snapshots: points, targets, d_avg, d_rel
    result: dict | None = None
    error: str | None = None
    seconds: float = 0.0

    @property
    def key(self) -> tuple[float, int]:
        return (self.psi, self.seed)

    def apply(self, event: dict) -> None:
        kind = event["type"]
        if kind == "status":
            self.status = event["status"]
        elif kind == "progress":
            self.epoch, self.loss, self.seconds = event["epoch"], event["loss"], event["seconds"]
            self.frames.append(event["frame"])
        elif kind == "done":
            self.result, self.epoch, self.status = event["result"], int(event["result"]["epochs"]), "done"
        elif kind == "error":
            self.error, self.status = event["error"], "failed"

    def public(self, since: int = 0) -> dict:
        return {
            "id": self.id,
            "psi": self.psi,
            "seed": self.seed,
            "status": self.status,
            "epoch": self.epoch,
            "epochs": self.epochs,
            "progress": 1.0 if self.status == "done" else round(self.epoch / self.epochs, 4),
            "loss": self.loss,
            "frames": self.frames[since:],
            "frame_count": len(self.frames),
            "result": self.result,
            "error": self.error,
            "seconds": round(self.seconds, 2),
        }


def warm_up_cosine() -> None:
    """Import in the background what a cosine run's first optimiser step imports (torch._dynamo,
    seconds on a busy machine), so that the learner's first run starts at once."""
    threading.Thread(target=importlib.import_module, args=("torch._dynamo",), daemon=True).start()


Validate = Callable[[dict, str, Settings], dict]
Work = Callable[[dict, Emit, Any, Settings], dict]
PROCESS_KINDS: dict[str, tuple[Validate, Work]] = {  # kinds run in a child process, kept in the jobs table
    "train": (validate_train, run_train),
    "evaluate": (validate_evaluate, run_evaluate),
}


def new_job_id() -> str:
    return time.strftime("%Y%m%d-%H%M%S-") + secrets.token_hex(3)
