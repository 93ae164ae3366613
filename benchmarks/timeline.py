"""Speed of the live description (issue 15): `MultiMTRNN.timeline` over corpus scenes.

For each shipped model (data/artefacts/models/default and faithful) and every `--every`-th corpus
recording, times what the model would say at every step of the recording (the Csc trajectories,
the assemblies at every step, MTRNN_a's batched generation and the decoding to text) and prints
the milliseconds per step: over all steps, and the median and worst recording
(goal: <= 5 ms per step on average).

    .venv/bin/python benchmarks/timeline.py [--every 4] [--threads 1] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from data.corpus import load_corpus  # noqa: E402
from model import checkpoint  # noqa: E402
from model.encoding.utterance import Lexicon  # noqa: E402

MODELS = ROOT / "data" / "artefacts" / "models"
GOAL_MS_PER_STEP = 5.0


def measure(name: str, entries: list) -> dict:
    """ms per step of one model's timelines over `entries` (one warm-up recording first)."""
    model, meta = checkpoint.load(MODELS / name)
    lexicon = Lexicon(meta["lexicon"])
    model.timeline(entries[0].proprioception, entries[0].vision, lexicon)
    per_recording, total_s, steps = [], 0.0, 0
    for e in entries:
        t0 = time.perf_counter()
        model.timeline(e.proprioception, e.vision, lexicon)
        dt = time.perf_counter() - t0
        total_s += dt
        steps += len(e.proprioception)
        per_recording.append(dt * 1e3 / len(e.proprioception))
    return {
        "model": name,
        "mode": meta.get("mode"),
        "recordings": len(entries),
        "steps": steps,
        "ms_per_step": total_s * 1e3 / steps,
        "median_recording_ms_per_step": statistics.median(per_recording),
        "worst_recording_ms_per_step": max(per_recording),
        "ms_per_recording": total_s * 1e3 / len(entries),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--every", type=int, default=4, help="time every n-th corpus recording")
    parser.add_argument("--threads", type=int, default=1, help="torch threads (1, as `mtrnn serve` runs)")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    args = parser.parse_args()
    torch.set_num_threads(max(1, args.threads))
    entries = load_corpus().entries[:: max(1, args.every)]
    load = os.getloadavg()
    results = [measure(name, entries) for name in ("default", "faithful")]
    if args.json:
        figures = {"load_average_before": load, "threads": torch.get_num_threads(), "models": results}
        print(json.dumps(figures))
        return
    print(
        f"timeline over {len(entries)} corpus recordings, {torch.get_num_threads()} torch threads, "
        f"load average {load[0]:.1f}"
    )
    for r in results:
        verdict = "ok" if r["ms_per_step"] <= GOAL_MS_PER_STEP else "SLOWER THAN THE GOAL"
        print(
            f"  {r['model']:9s} ({r['mode']}): {r['ms_per_step']:.3f} ms per step over {r['steps']} steps "
            f"(median recording {r['median_recording_ms_per_step']:.3f}, worst "
            f"{r['worst_recording_ms_per_step']:.3f}; {r['ms_per_recording']:.1f} ms per recording); "
            f"goal <= {GOAL_MS_PER_STEP} ms: {verdict}"
        )


if __name__ == "__main__":
    main()
