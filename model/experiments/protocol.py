"""The evaluation engine: the paper's protocol (4.2, K folds x N initialisations) run at scale.

One function, `run_protocol`, serves the CLI, the app's jobs, the sweeps and the tests. It plans
`RunSpec`s, registers them in the run store, skips the ones already done, and executes the rest
on an engine:

- ``local``: a pool of worker processes (default 2, one run per core: one run per core beat one
  run on two threads in the feasibility spike); each worker uses one torch thread.
- ``ray``: each run is a Ray task (``num_cpus=1``); ``ray.init()`` starts a local instance with
  ``num_cpus`` CPUs when no address is given, otherwise it joins the cluster at ``address``.

Both engines call the same worker function, `execute_task`, in a fresh-seeded process with one
torch thread, so the same seeds give the same numbers on either engine. A task is one run, or, for
a runner that trains several runs in one vectorised pass (a `batch_size` attribute, e.g. the cosine
experiment's), up to `batch_size` runs. Workers return metrics
and checkpoint bytes; only the driver writes the run store, one transaction per finished run, so
a killed evaluation restarted with the same command loses nothing and repeats no finished run.
"""

from __future__ import annotations

import ctypes
import hashlib
import importlib
import logging
import multiprocessing
import signal
import tempfile
import time
import traceback
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from model.experiments.runstore import RunRecord, RunSpec, RunStore
from model.metrics import mean_sem

logger = logging.getLogger(__name__)

Engine = Literal["local", "ray"]
ProgressFn = Callable[[dict[str, Any]], None]

# The function a worker calls, for every training mode:
# run_once(data, mode, fold, seed, config=None, out_dir=None) -> RunResult, with split= and
# train_scenes= for a run of another split than the paper's (`model.experiments.splits`).
DEFAULT_RUNNER = "model.experiments.evaluation:run_once"
SEED_STRIDE = 1000  # seed of (fold, init) = base_seed + SEED_STRIDE * fold + init


def run_seed(base_seed: int, fold: int, init: int) -> int:
    """The initialisation seed of one run: distinct per (fold, init), reproducible from the command."""
    return base_seed + SEED_STRIDE * fold + init


def data_digest(data: Any) -> str:
    """Fingerprint of a SequenceSet (ids, utterances, array contents): runs on other data never match."""
    h = hashlib.sha256()
    for rid, text, prop, vis in zip(data.ids, data.utterances, data.proprioception, data.vision, strict=True):
        h.update(rid.encode())
        h.update(text.encode())
        for array in (prop, vis):
            a = np.ascontiguousarray(array, dtype=np.float64)
            h.update(str(a.shape).encode())
            h.update(a.tobytes())
    return h.hexdigest()[:16]


def apply_overrides(config: Mapping[str, Any], overrides: Mapping[str, Any]) -> dict[str, Any]:
    """Set dotted keys ("training.psi_s") of a nested config dict; unknown keys are an error."""
    out = _deep_copy(config)
    for dotted, value in overrides.items():
        node: Any = out
        *path, leaf = dotted.split(".")
        for part in path:
            if not isinstance(node, dict) or part not in node:
                raise KeyError(f"unknown config key {dotted!r} (no {part!r})")
            node = node[part]
        # a mode's named options ("options.recombine") may be absent from the defaults: the mode
        # validates them when it builds its options dataclass
        if not isinstance(node, dict) or (leaf not in node and path != ["options"]):
            raise KeyError(f"unknown config key {dotted!r}")
        node[leaf] = value
    return out


def _deep_copy(d: Mapping[str, Any]) -> dict[str, Any]:
    return {k: _deep_copy(v) if isinstance(v, Mapping) else v for k, v in d.items()}


def default_config(mode: str = "faithful") -> dict[str, Any]:
    """The full default config of a mode as a dict (the peer has its own sizes)."""
    from model.training import CONFIGS

    return CONFIGS[mode]().to_dict()


def plan(
    experiment: str,
    mode: str,
    folds: int | Sequence[int],
    inits: int,
    config: Mapping[str, Any],
    digest: str,
    base_seed: int = 0,
    params: Mapping[str, Any] | None = None,
    split: str = "scenes",
    train_scenes: int | None = None,
) -> list[RunSpec]:
    """The K x N runs of one setting (paper 4.2: 10 folds x 10 random initialisations) on one
    protocol split (`model.experiments.splits`; `train_scenes` for the size split)."""
    fold_ids = range(folds) if isinstance(folds, int) else folds
    return [
        RunSpec(
            experiment=experiment,
            mode=mode,
            fold=fold,
            init=init,
            seed=run_seed(base_seed, fold, init),
            config=dict(config),
            params=dict(params or {}),
            data_digest=digest,
            split=split,
            train_scenes=train_scenes,
        )
        for fold in fold_ids
        for init in range(inits)
    ]


# --- the worker side ----------------------------------------------------------------------------


@dataclass
class RunOutcome:
    """What a worker sends back: everything the run store keeps about one run."""

    key: str
    ok: bool
    metrics: dict[str, dict[str, float]] = field(default_factory=dict)
    seconds: float = 0.0
    checkpoint: dict[str, bytes] = field(default_factory=dict)  # file name -> bytes
    artifacts: dict[str, Any] = field(default_factory=dict)
    error: str = ""


def resolve(path: str) -> Callable[..., Any]:
    """ "package.module:function" -> the function (importable in any worker process)."""
    module, _, name = path.partition(":")
    return getattr(importlib.import_module(module), name)


def _flat_metrics(metrics: Mapping[str, Any]) -> dict[str, dict[str, float]]:
    """{split: {name: number}}; nested dicts (e.g. Csc measures per space) become "csc_s.d_avg"."""
    out: dict[str, dict[str, float]] = {}
    for split, values in metrics.items():
        flat: dict[str, float] = {}
        _flatten(values, "", flat)
        out[split] = flat
    return out


def _flatten(value: Any, prefix: str, out: dict[str, float]) -> None:
    if isinstance(value, Mapping):
        for k, v in value.items():
            _flatten(v, f"{prefix}{k}.", out)
    elif isinstance(value, bool | int | float | np.floating | np.integer):
        out[prefix[:-1]] = float(value)


def execute_run(data: Any, spec: RunSpec, runner: str = DEFAULT_RUNNER) -> RunOutcome:
    """Train and score one run in this process, with one torch thread. Never raises."""
    import torch

    torch.set_num_threads(1)
    started = time.perf_counter()
    try:
        config = _deep_copy(spec.config) if spec.config else None  # runners take the config as a dict
        run_once = resolve(runner)
        split = {} if spec.split == "scenes" else {"split": spec.split, "train_scenes": spec.train_scenes}
        with tempfile.TemporaryDirectory(prefix="mtrnn-run-") as tmp:
            out = Path(tmp)
            result = run_once(data, spec.mode, spec.fold, spec.seed, config=config, out_dir=out, **split)
            files = {p.name: p.read_bytes() for p in sorted(Path(tmp).iterdir()) if p.is_file()}
        artifacts = dict(getattr(result, "artifacts", None) or {})
        return RunOutcome(
            key=spec.key,
            ok=True,
            metrics=_flat_metrics(result.metrics),
            seconds=float(getattr(result, "seconds", time.perf_counter() - started)),
            checkpoint=files,
            artifacts=artifacts,
        )
    except Exception:  # a failed run is recorded, retried on restart, and never stops the others
        return RunOutcome(
            key=spec.key, ok=False, seconds=time.perf_counter() - started, error=traceback.format_exc()
        )


def execute_batch(data: Any, specs: list[RunSpec], runner: str) -> list[RunOutcome]:
    """Train `specs` together with a batched runner: runner(data, specs) -> one result per spec, in
    order (its metrics, seconds, artifacts and optionally its checkpoint files). Never raises."""
    import torch

    torch.set_num_threads(1)
    started = time.perf_counter()
    try:
        results = resolve(runner)(data, specs)
        return [
            RunOutcome(
                key=s.key,
                ok=True,
                metrics=_flat_metrics(r.metrics),
                seconds=float(r.seconds),
                checkpoint=dict(getattr(r, "checkpoint", None) or {}),
                artifacts=dict(r.artifacts or {}),
            )
            for s, r in zip(specs, results, strict=True)
        ]
    except Exception:  # the whole batch is recorded as failed and retried on restart
        error = traceback.format_exc()
        seconds = (time.perf_counter() - started) / len(specs)
        return [RunOutcome(key=s.key, ok=False, seconds=seconds, error=error) for s in specs]


def execute_task(data: Any, specs: list[RunSpec], runner: str) -> list[RunOutcome]:
    """One engine task: a batch for a batched runner, otherwise its one run."""
    if getattr(resolve(runner), "batch_size", None):
        return execute_batch(data, specs, runner)
    return [execute_run(data, spec, runner) for spec in specs]


def tasks(specs: list[RunSpec], runner: str) -> list[list[RunSpec]]:
    """`specs` cut into engine tasks: chunks of the runner's `batch_size` (1 if it has none)."""
    size = getattr(resolve(runner), "batch_size", None) or 1
    return [specs[i : i + size] for i in range(0, len(specs), size)]


_WORKER_DATA: Any = None


def _die_with_parent() -> None:
    """Linux: ask the kernel to SIGKILL this worker when the driver dies (even by SIGKILL)."""
    try:
        libc = ctypes.CDLL("libc.so.6", use_errno=True)
        libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except OSError:
        logger.debug("prctl unavailable; workers may outlive a killed driver")


def _init_worker(data: Any) -> None:
    global _WORKER_DATA
    _die_with_parent()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the driver handles Ctrl-C
    _WORKER_DATA = data


def _pool_task(specs: list[RunSpec], runner: str) -> list[RunOutcome]:
    return execute_task(_WORKER_DATA, specs, runner)


# --- engines ------------------------------------------------------------------------------------


def _local_outcomes(data: Any, specs: list[RunSpec], runner: str, workers: int) -> Iterator[RunOutcome]:
    """One process per core; the data is sent to each worker once."""
    ctx = multiprocessing.get_context("spawn")  # no forked torch state
    with ProcessPoolExecutor(
        max_workers=workers, mp_context=ctx, initializer=_init_worker, initargs=(data,)
    ) as pool:
        pending: set[Future] = {pool.submit(_pool_task, t, runner) for t in tasks(specs, runner)}
        try:
            while pending:
                finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                for f in finished:
                    yield from f.result()
        finally:
            for f in pending:
                f.cancel()


def ray_init(address: str | None = None, num_cpus: int = 2) -> None:
    """Join the cluster at `address`, or start a local Ray instance with `num_cpus` CPUs."""
    import ray

    if ray.is_initialized():
        return
    if address:
        ray.init(address=address, log_to_driver=False)
    else:
        ray.init(num_cpus=num_cpus, include_dashboard=False, log_to_driver=False)


def _ray_outcomes(
    data: Any, specs: list[RunSpec], runner: str, address: str | None, num_cpus: int
) -> Iterator[RunOutcome]:
    """Each run is a Ray task with one CPU; the data is put in the object store once."""
    import ray

    ray_init(address, num_cpus)
    task = ray.remote(num_cpus=1, max_retries=1)(execute_task)
    data_ref = ray.put(data)
    pending = [task.remote(data_ref, t, runner) for t in tasks(specs, runner)]
    try:
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            for ref in done:
                yield from ray.get(ref)
    finally:
        for ref in pending:
            ray.cancel(ref, force=True)


def outcomes(
    data: Any,
    specs: list[RunSpec],
    engine: Engine = "local",
    workers: int = 2,
    address: str | None = None,
    runner: str = DEFAULT_RUNNER,
) -> Iterator[RunOutcome]:
    """Execute `specs` on an engine and yield each outcome as it completes (any order)."""
    if not specs:
        return iter(())
    if engine == "local":
        return _local_outcomes(data, specs, runner, max(1, min(workers, len(tasks(specs, runner)))))
    if engine == "ray":
        return _ray_outcomes(data, specs, runner, address, workers)
    raise ValueError(f"unknown engine {engine!r}; use 'local' or 'ray'")


# --- the driver ---------------------------------------------------------------------------------


@dataclass
class ProtocolResult:
    runs: list[RunRecord]  # every planned run that is done, in plan order
    executed: int  # runs trained by this call (the others were already in the store)
    skipped: int
    failed: list[str]  # keys of runs that raised (retried on the next call)
    seconds: float


def run_protocol(
    data: Any,
    specs: list[RunSpec],
    store: RunStore,
    engine: Engine = "local",
    workers: int = 2,
    address: str | None = None,
    runner: str = DEFAULT_RUNNER,
    progress: ProgressFn | None = None,
) -> ProtocolResult:
    """Run every spec not yet done in `store`; resumable, one store transaction per finished run."""
    started = time.perf_counter()
    store.register(specs)
    keys = [s.key for s in specs]
    done = store.done_keys(keys)
    todo = [s for s in specs if s.key not in done]
    logger.info("%d runs planned, %d already done, %d to run on %s", len(specs), len(done), len(todo), engine)
    failed: list[str] = []
    for spec in todo:
        store.mark_running(spec.key)
    completed = len(done)
    for outcome in outcomes(data, todo, engine, workers, address, runner):
        if outcome.ok:
            path = store.write_checkpoint(outcome.key, outcome.checkpoint) if outcome.checkpoint else None
            store.finish(
                outcome.key,
                outcome.metrics,
                outcome.seconds,
                str(path) if path else None,
                outcome.artifacts,
            )
            completed += 1
        else:
            logger.error("run %s failed:\n%s", outcome.key, outcome.error)
            store.fail(outcome.key, outcome.error)
            failed.append(outcome.key)
        if progress is not None:
            progress(
                {
                    "event": "run",
                    "key": outcome.key,
                    "ok": outcome.ok,
                    "done": completed,
                    "failed": len(failed),
                    "total": len(specs),
                    "seconds": outcome.seconds,
                    "metrics": outcome.metrics,
                }
            )
    order = {k: i for i, k in enumerate(keys)}
    runs = sorted(store.runs(keys=keys), key=lambda r: order[r.key])
    return ProtocolResult(runs, len(todo) - len(failed), len(done), failed, time.perf_counter() - started)


def summarise(runs: Sequence[RunRecord]) -> dict[str, dict[str, dict[str, float]]]:
    """Mean, standard error, best and worst of every metric per split over runs."""
    values: dict[str, dict[str, list[float]]] = {}
    for r in runs:
        for split, metrics in r.metrics.items():
            for name, value in metrics.items():
                values.setdefault(split, {}).setdefault(name, []).append(value)
    out: dict[str, dict[str, dict[str, float]]] = {}
    for split, metrics in values.items():
        for name, vs in metrics.items():
            finite = [v for v in vs if v is not None and np.isfinite(v)]
            if not finite:
                continue
            mean, sem, n = mean_sem(finite)
            out.setdefault(split, {})[name] = {
                "mean": mean,
                "sem": sem,
                "min": float(min(finite)),
                "max": float(max(finite)),
                "n": float(n),
            }
    return out
