"""`mtrnn cosine`: the paper's preliminary experiment on self-organisation forcing (3.2.2, Fig. 3)."""

from __future__ import annotations

import argparse
import json

from tqdm import tqdm


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "cosine", help="psi vs spread of abstracted contexts on contrary cosines (Fig. 3)"
    )
    parser.add_argument("--psi", type=float, nargs="+", default=[0.0, 1e-5, 5e-5, 2e-4], help="psi values")
    parser.add_argument("--runs", type=int, default=10, help="seeded runs per psi (same seeds for every psi)")
    parser.add_argument("--seed", type=int, default=0, help="first seed")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON (without snapshots)")
    parser.set_defaults(func=_cosine)


def _cosine(args: argparse.Namespace) -> int:
    import torch

    from model.experiments.cosine import run_cosine

    torch.set_num_threads(1)
    summaries = []
    with tqdm(total=len(args.psi) * args.runs, unit="run", desc="cosine") as bar:

        def progress(report: dict) -> None:
            bar.set_postfix(psi=report["psi"], epoch=report["epoch"], err=f"{report['loss']:.2e}")

        for psi in args.psi:
            result = run_cosine(psi, args.runs, args.seed, progress)
            bar.update(args.runs)
            result.pop("snapshots")
            summaries.append(result)
    if args.json:
        print(json.dumps(summaries, indent=2))
        return 0
    print(f"{'psi':>8}  {'d_avg':>15}  {'d_rel':>15}  {'epochs':>13}  converged")
    for s in summaries:
        print(
            f"{s['psi']:8.0e}  {s['d_avg']['mean']:.4f} +- {s['d_avg']['se']:.4f}  "
            f"{s['d_rel']['mean']:.4f} +- {s['d_rel']['se']:.4f}  "
            f"{s['epochs']['mean']:6.0f} +- {s['epochs']['se']:4.0f}"
            f"  {s['converged']}/{s['runs']}"
        )
    return 0
