"""Wall time of one job of every epoch preset (`server.jobs.presets.PRESETS`) in every mode.

One job is what the app's train job does: split fold 0 of the shipped corpus, train with the
preset's epochs (`scale_epochs`), score both sides and save the checkpoint, on one torch thread.
The minutes printed are the ones the presets' labels show (`Preset.minutes`).

Run:  .venv/bin/python benchmarks/presets.py [--modes faithful end_to_end peer]
      [--presets quick paper] [--json]
The machine is shared: the load average is printed before and after.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import torch

from model.experiments.evaluation import run_once
from model.experiments.protocol import default_config
from server.jobs.kinds import corpus_data
from server.jobs.presets import EPOCH_FIELDS, PRESETS, scale_epochs


def measure(data: object, mode: str, preset: str) -> dict:
    config = scale_epochs(default_config(mode), mode, PRESETS[preset].scale)
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="mtrnn-preset-") as tmp:
        run = run_once(data, mode, 0, 0, config, out_dir=Path(tmp))
    seconds = time.perf_counter() - started
    return {
        "mode": mode,
        "preset": preset,
        "seconds": round(seconds, 1),
        "minutes": round(seconds / 60, 2),
        "test_f1": round(run.metrics["test"]["f1"], 3),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--modes", nargs="+", default=list(EPOCH_FIELDS))
    parser.add_argument("--presets", nargs="+", default=list(PRESETS))
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    torch.set_num_threads(1)
    print(f"load average before: {os.getloadavg()}", flush=True)
    data = corpus_data()
    rows = []
    for preset in args.presets:
        for mode in args.modes:
            rows.append(measure(data, mode, preset))
            if not args.json:
                r = rows[-1]
                print(
                    f"{preset:6s} {mode:10s} {r['seconds']:7.1f} s  ({r['minutes']:.2f} min)"
                    f"  test F1 {r['test_f1']}",
                    flush=True,
                )
    print(f"load average after: {os.getloadavg()}", flush=True)
    if args.json:
        print(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
