"""`mtrnn sweep`: the paper's parameter sweeps as resumable runs of the evaluation engine.

    mtrnn sweep psi_s 1e-4 2e-4 5e-4 1e-3 2e-3 5e-3 1e-2 2e-2 5e-2 --folds 4 --inits 2   (Fig. 9)
    mtrnn sweep cosine 0 1e-5 5e-5 2e-4 --runs 10                                        (Fig. 3)

Without values each sweep uses the paper's. Results go to the same run store as `mtrnn evaluate`
(experiments "psi_s" and "cosine"); `mtrnn report` turns them into figures.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from server.commands.cosine import add_rule_arguments
from server.commands.evaluate import (
    add_engine_arguments,
    build_config,
    engine_options,
    load_data,
    parse_overrides,
    run_store,
    with_progress,
)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "sweep", help="psi_s sweep of the model (Fig. 9) or psi of the cosines (Fig. 3)"
    )
    kinds = parser.add_subparsers(dest="sweep", required=True)

    psi_s = kinds.add_parser("psi_s", help="self-organisation forcing of MTRNN_s (4.3, Fig. 9)")
    psi_s.add_argument("values", type=float, nargs="*", help="psi_s values (default: the paper's nine)")
    psi_s.add_argument("--mode", default="faithful", help="training mode (the paper's: faithful)")
    add_engine_arguments(psi_s)
    psi_s.set_defaults(func=run_psi_s)

    cosine = kinds.add_parser("cosine", help="the contrary-cosines experiment over psi (3.2.2, Fig. 3)")
    cosine.add_argument("values", type=float, nargs="*", help="psi values (default: 0 1e-5 5e-5 2e-4)")
    cosine.add_argument("--runs", type=int, default=10, help="runs per psi (paper: 100)")
    cosine.add_argument("--engine", choices=("local", "ray"), default="local")
    cosine.add_argument("--address", default=None)
    cosine.add_argument("--workers", type=int, default=2)
    cosine.add_argument("--run-dir", type=Path, default=None)
    cosine.add_argument("--seed", type=int, default=0)
    cosine.add_argument("--json", action="store_true")
    add_rule_arguments(cosine)
    cosine.set_defaults(func=run_cosine)


def _fmt(v: float, e: float) -> str:
    return "-" if math.isnan(v) else f"{v:.4g} +- {e:.2g}"


def run_psi_s(args: argparse.Namespace) -> int:
    from model.experiments.protocol import DEFAULT_RUNNER, data_digest, run_protocol
    from model.experiments.sweeps import PSI_S_PAPER, PSI_S_RUNNER, psi_s_specs, psi_s_table

    values = args.values or list(PSI_S_PAPER)
    config = build_config(parse_overrides(args.overrides), args.mode)
    data = load_data(args.corpus)
    store = run_store(args.run_dir)
    digest = data_digest(data)
    specs = psi_s_specs(values, args.mode, args.folds, args.inits, config, digest, args.seed)
    runner = PSI_S_RUNNER if args.mode == "faithful" else DEFAULT_RUNNER
    result = with_progress(
        store,
        specs,
        lambda update: run_protocol(data, specs, store, runner=runner, **engine_options(args, update)),
    )
    table = psi_s_table(result.runs)
    if args.json:
        print(json.dumps({"mode": args.mode, "table": table, "failed": len(result.failed)}, indent=1))
    else:
        print(f"psi_s sweep, mode {args.mode}: {len(result.runs)} runs in {result.seconds:.0f} s")
        print(
            f"{'psi_s':>8} {'mixed F1':>18} {'mixed edit':>18} {'d_rel':>18} {'d_inter':>18} {'d_intra':>18}"
        )
        for row in table:
            print(
                f"{row['psi_s']:>8.0e} "
                + " ".join(
                    f"{_fmt(row[k], row[k + '_sem']):>18}"
                    for k in ("mixed_f1", "mixed_edit_distance", "d_rel", "d_inter", "d_intra")
                )
            )
    return 1 if result.failed else 0


def run_cosine(args: argparse.Namespace) -> int:
    from model.experiments.protocol import run_protocol
    from model.experiments.sweeps import COSINE_RUNNER, PSI_COSINE_PAPER, cosine_specs, cosine_table

    values = args.values or list(PSI_COSINE_PAPER)
    store = run_store(args.run_dir)
    rule = {"optimiser": args.optimiser, "zeta_gain": args.zeta_gain}
    specs = cosine_specs(values, args.runs, args.seed, rule)
    result = with_progress(
        store,
        specs,
        lambda update: run_protocol(None, specs, store, runner=COSINE_RUNNER, **engine_options(args, update)),
    )
    table = cosine_table(result.runs, (args.optimiser, args.zeta_gain))
    if args.json:
        print(json.dumps({"table": table, "failed": len(result.failed)}, indent=1))
    else:
        print(f"cosine sweep: {len(result.runs)} runs in {result.seconds:.0f} s")
        print(f"{'psi':>8} {'epochs':>18} {'d_avg':>18} {'d_rel':>18}")
        for row in table:
            print(
                f"{row['psi']:>8.0e} "
                + " ".join(
                    f"{_fmt(row.get(k, math.nan), row.get(k + '_sem', math.nan)):>18}"
                    for k in ("epochs", "d_avg", "d_rel")
                )
            )
    return 1 if result.failed else 0
