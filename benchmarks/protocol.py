"""Evaluation throughput: runs per hour on this machine's cores, local pool and Ray, and the
scaling to expect on N nodes.

    .venv/bin/python benchmarks/protocol.py                       # end_to_end, 4 runs per engine
    .venv/bin/python benchmarks/protocol.py --mode faithful --runs 6 --engines local
    .venv/bin/python benchmarks/protocol.py --set training.epochs_auditory=300 --json

Each engine trains the same `--runs` runs (folds x 1 init, the shipped corpus, default budgets
unless --set) into a fresh run store and reports: wall time, runs per hour, the mean time of one
run inside its worker (t_run), and the engine's overhead = wall - (sum of t_run) / workers
(process start, imports, data transfer, scheduling, the tail when runs do not divide evenly).

Scaling argument (printed): with C cores per node and N nodes, Ray keeps C x N runs in flight;
a run costs t_run + t_task where t_task is Ray's per-task cost (scheduling and the result's
return, milliseconds; the data goes to each node's object store once), so
    runs/hour(N) ~= 3600 * C * N / (t_run + t_task)
which is linear in N while t_task << t_run (here t_run is tens of seconds, t_task is measured
below as the Ray overhead per run), until the driver's bookkeeping (one SQLite transaction per
finished run, ~ms) or the number of runs (K x N of the protocol, 100 for the paper's setting)
limits it: 100 runs on N nodes take ceil(100 / (C N)) rounds of t_run.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from model.experiments.protocol import data_digest, plan, run_protocol  # noqa: E402
from model.experiments.runstore import RunStore  # noqa: E402
from server.commands.evaluate import build_config, load_data, parse_overrides  # noqa: E402


def measure(engine: str, mode: str, runs: int, workers: int, config: dict, data: object) -> dict:
    """Train `runs` runs (fold k, init 0) on `engine` into a fresh store; time them."""
    specs = plan("benchmark", mode, runs, 1, config, data_digest(data))
    with tempfile.TemporaryDirectory(prefix=f"bench-{engine}-") as tmp:
        started = time.perf_counter()
        result = run_protocol(data, specs, RunStore(tmp), engine, workers)
        wall = time.perf_counter() - started
    if engine == "ray":
        import ray

        ray.shutdown()
    seconds = [r.seconds for r in result.runs if r.seconds is not None]
    t_run = sum(seconds) / max(1, len(seconds))
    overhead = wall - sum(seconds) / workers
    return {
        "engine": engine,
        "mode": mode,
        "runs": len(result.runs),
        "failed": len(result.failed),
        "workers": workers,
        "wall_s": wall,
        "runs_per_hour": 3600.0 * len(result.runs) / wall,
        "t_run_s": t_run,
        "overhead_s": overhead,
        "overhead_per_run_s": overhead / max(1, len(result.runs)),
        "test_f1_mean": sum(r.metrics["test"]["f1"] for r in result.runs) / max(1, len(result.runs)),
    }


def from_store(run_dir: Path, mode: str, workers: int) -> dict:
    """Throughput of an evaluation already in a run store (one invocation of `mtrnn evaluate`):
    wall = last finish - registration, t_run = mean seconds inside the workers."""
    runs = RunStore(run_dir).runs(experiment="evaluate", mode=mode)
    if not runs:
        raise SystemExit(f"no finished {mode} evaluation runs in {run_dir}")
    import sqlite3

    with sqlite3.connect(RunStore(run_dir).path) as db:
        created = min(
            db.execute("SELECT created FROM runs WHERE key = ?", (r.key,)).fetchone()[0] for r in runs
        )
    wall = max(r.finished for r in runs) - created
    seconds = [r.seconds for r in runs]
    overhead = wall - sum(seconds) / workers
    return {
        "engine": f"local (store {run_dir})",
        "mode": mode,
        "runs": len(runs),
        "failed": 0,
        "workers": workers,
        "wall_s": wall,
        "runs_per_hour": 3600.0 * len(runs) / wall,
        "t_run_s": sum(seconds) / len(seconds),
        "overhead_s": overhead,
        "overhead_per_run_s": overhead / len(runs),
        "test_f1_mean": sum(r.metrics["test"]["f1"] for r in runs) / len(runs),
    }


def scaling(row: dict, cores: int, nodes: tuple[int, ...] = (1, 2, 4, 8, 16)) -> list[dict]:
    """Expected runs/hour on N nodes of `cores` cores from the measured t_run and per-run overhead."""
    t = row["t_run_s"] + max(0.0, row["overhead_per_run_s"]) * row["workers"]
    out = []
    for n in nodes:
        rate = 3600.0 * cores * n / t
        out.append(
            {
                "nodes": n,
                "runs_per_hour": rate,
                "paper_protocol_minutes": math.ceil(100 / (cores * n)) * t / 60,
            }
        )
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mode", default="end_to_end")
    parser.add_argument("--runs", type=int, default=4)
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 2)
    parser.add_argument("--engines", nargs="*", default=["local", "ray"], choices=["local", "ray"])
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument(
        "--from-store", type=Path, default=None, help="also report an evaluation in this store"
    )
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)

    config = build_config(parse_overrides(args.overrides), args.mode)
    data = load_data(None)
    rows = [from_store(args.from_store, args.mode, args.workers)] if args.from_store else []
    rows += [measure(e, args.mode, args.runs, args.workers, config, data) for e in args.engines]
    answer = {
        "cores": os.cpu_count(),
        "overrides": args.overrides,
        "engines": rows,
        "scaling": scaling(rows[-1], args.workers),
    }
    if args.json:
        print(json.dumps(answer, indent=1))
        return 0
    print(
        f"{args.mode}: {args.runs} runs per measured engine, {args.workers} workers, {os.cpu_count()} cores; "
        f"overrides {args.overrides or 'none (Table 1 budgets)'}"
    )
    header = ("engine", "runs", "wall s", "runs/hour", "t_run s", "overhead/run s", "test F1")
    print(f"{header[0]:<28} " + " ".join(f"{h:>10}" for h in header[1:]))
    for r in rows:
        cells = (
            r["runs"],
            r["wall_s"],
            r["runs_per_hour"],
            r["t_run_s"],
            r["overhead_per_run_s"],
            r["test_f1_mean"],
        )
        print(f"{r['engine']:<28} " + " ".join(f"{c:>10.3g}" for c in cells))
    print(f"expected with N nodes of {args.workers} cores (from the {rows[-1]['engine']} row):")
    for s in answer["scaling"]:
        print(
            f"  N={s['nodes']:>2}: {s['runs_per_hour']:>8.0f} runs/hour; the paper's 100 runs in "
            f"{s['paper_protocol_minutes']:.1f} min"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
