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
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    add_rule_arguments(parser)
    parser.set_defaults(func=_cosine)


def add_rule_arguments(parser: argparse.ArgumentParser) -> None:
    """--optimiser and --zeta-gain of the cosine experiment (defaults: `CosineSetup`'s)."""
    from model.config import LEARNING_RULES, ZETA_GAIN

    parser.add_argument("--optimiser", choices=LEARNING_RULES, default="paper", help="learning rule")
    parser.add_argument(
        "--zeta-gain", type=float, default=ZETA_GAIN, help="eq. (10)'s constant (the paper's rule only)"
    )


def _cosine(args: argparse.Namespace) -> int:
    import torch

    from model.experiments.cosine import CosineSetup, run_cosine

    torch.set_num_threads(1)
    summaries = []
    with tqdm(total=len(args.psi) * args.runs, unit="run", desc="cosine") as bar:
        for psi in args.psi:  # the runs of one psi learn together (`train_cosine_runs`)
            bar.set_postfix(psi=psi)
            setup = CosineSetup(optimiser=args.optimiser, zeta_gain=args.zeta_gain)
            result = run_cosine(psi, args.runs, args.seed, setup)
            bar.update(args.runs)
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
