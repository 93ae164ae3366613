"""The report's sections, each from one experiment of the run store: the training modes beside
the paper (4.3), the psi_s sweep (Fig. 9), the contrary cosines (Fig. 3) and the Csc spaces of
the lowest and highest generalising runs (Fig. 10)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from model.experiments.protocol import summarise
from model.experiments.report import figures, prose
from model.experiments.report.panels import SPACE_NAMES, csc_panels
from model.experiments.report.tables import (
    MODES,
    PAPER,
    best_runs,
    budget,
    fmt,
    folds_inits,
    mode_table,
    one_config,
    paper_budget,
    paper_table,
)
from model.experiments.runstore import RunRecord, RunStore
from model.experiments.sweeps import cosine_table, psi_s_table

PSI_S_COLUMNS = (
    "mixed_f1",
    "mixed_edit_distance",
    "test_f1",
    "test_sentence_exact",
    "d_avg",
    "d_rel",
    "d_inter",
    "d_intra",
)
PAPER_BEST_PSI_S = 5e-4  # 4.3: the best value, tested against psi_s = 0 (p < 0.001)


@dataclass
class Report:
    markdown: str
    figures: list[Path] = field(default_factory=list)
    data: dict[str, Any] = field(default_factory=dict)


@dataclass
class Page:
    """The report being written: its Markdown lines, figures and the figures' numbers."""

    figures_dir: Path
    rel: Path  # how the Markdown refers to figures_dir
    md: list[str] = field(default_factory=list)
    report: Report = field(default_factory=lambda: Report(""))

    def figure(self, name: str) -> Path:
        path = self.figures_dir / name
        self.report.figures.append(path)
        return path

    def image(self, alt: str, path: Path) -> str:
        return f"![{alt}]({self.rel / path.name})"


def modes(page: Page, store: RunStore) -> dict[str, list[RunRecord]]:
    """Every mode's evaluation runs on the paper's split (of its most evaluated config) and, if any,
    their section."""
    evaluate = {m: one_config(store.runs(experiment="evaluate", mode=m, split="scenes")) for m in MODES}
    evaluate = {m: r for m, r in evaluate.items() if r}
    summaries = {m: summarise(r) for m, r in evaluate.items()}
    page.report.data["modes"] = {
        m: {
            "summary": summaries[m],
            "runs": len(evaluate[m]),
            "budget": budget(evaluate[m]),
            "per_run": [{"fold": r.fold, "init": r.init, "metrics": r.metrics} for r in evaluate[m]],
        }
        for m in evaluate
    }
    page.report.data["paper"] = PAPER
    if evaluate:
        _modes_table(page, evaluate, summaries)
        _beside_the_paper(page, evaluate, summaries)
    return evaluate


def _modes_table(page: Page, evaluate: dict[str, list[RunRecord]], summaries: dict[str, dict]) -> None:
    page.md += [
        "## Training modes on the same folds",
        "",
        "Mean ± standard error over runs; a fold is a 50:50 split by scene (all recordings of a "
        "scene on one "
        "side, paper 4.2), test scenes are action/colour/object combinations never seen in training. "
        '"mixed" = mean of train and test (4.3).',
        "",
    ]
    page.md += mode_table(summaries, {m: folds_inits(r) for m, r in evaluate.items()}) + [""]
    page.md += ["Epoch budgets used:", ""]
    for m, runs in evaluate.items():
        page.md.append(f"- {m}: `{json.dumps(budget(runs), sort_keys=True)}`")
    page.md.append(
        f"- Table 1 / paper defaults of the MultiMTRNN: `{json.dumps(paper_budget(), sort_keys=True)}`"
    )
    page.md.append("")
    path = page.figure("modes.png")
    figures.figure_modes(summaries, path)
    page.md += [
        page.image("modes", path),
        "",
        "## Beside the paper",
        "",
        "The paper reports the faithful model only (mean over 100 runs, and the best network). "
        "Best run = the run with the highest test F1 (its train numbers from the same run).",
        "",
    ]


def _beside_the_paper(page: Page, evaluate: dict[str, list[RunRecord]], summaries: dict[str, dict]) -> None:
    """The paper's table with each mode's best run, and one sentence per differing number."""
    best = {m: best_runs(r) for m, r in evaluate.items()}
    for m in best:
        for split in ("train", "test"):
            for metric in ("f1", "edit_distance"):
                key = "max" if metric == "f1" else "min"
                summaries[m].setdefault(split, {}).setdefault(metric, {})[key] = best[m][split].get(metric)
    page.md += paper_table(summaries) + ["", "How the means differ (the causes are numbered below):", ""]
    causes: list[str] = []
    for m in evaluate:
        cut = m == "faithful" and budget(evaluate[m]) != paper_budget()  # Table 1 is faithful's
        optimiser = evaluate[m][0].config.get("training", {}).get("optimiser")
        for split in ("train", "test"):
            values = {
                metric: (ours, PAPER[split][metric])
                for metric in ("f1", "edit_distance")
                if (ours := summaries[m].get(split, {}).get(metric, {}).get("mean")) is not None
            }
            if not values:
                continue
            sentence, keys = prose.comparison(m, split, values, optimiser, cut)
            causes += [k for k in keys if k not in causes]
            refs = ", ".join(str(causes.index(k) + 1) for k in keys)
            named = f": {'causes' if len(keys) > 1 else 'cause'} {refs}." if keys else "."
            page.md.append(f"- {sentence}{named}")
    if causes:
        page.md += ["", "Why, each cause once:", ""]
        page.md += [f"{n}. {prose.CAUSES[k]}" for n, k in enumerate(causes, start=1)]
    page.md.append("")


def psi_s(page: Page, store: RunStore, data: Any | None) -> None:
    """Fig. 9 (a-d) from the psi_s sweep, and (e-g) when the corpus is given."""
    psi_runs = store.runs(experiment="psi_s", split="scenes")
    if not psi_runs:
        return
    table = psi_s_table(psi_runs)
    page.report.data["psi_s"] = table
    path = page.figure("fig9_psi_s.png")
    figures.figure_psi_s(table, path)
    best = max(table, key=lambda r: r["mixed_f1"])
    page.md += [
        "## Self-organisation forcing psi_s (Fig. 9 a-d)",
        "",
        f"Mode `{psi_runs[0].mode}`, "
        f"{folds_inits([r for r in psi_runs if r.params == psi_runs[0].params])} "
        f"per value; budget `{json.dumps(budget(psi_runs), sort_keys=True)}`. Csc measures of "
        "MTRNN_s on "
        "the training scenes, clusters = manipulations (eqs. 13-15, 22-23).",
        "",
        "| psi_s | mixed F1 | mixed edit distance | test F1 | test exact | d_avg | d_rel | "
        "d_inter | d_intra | worker time |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in table:
        page.md.append(
            f"| {r['psi_s']:g} | "
            + " | ".join(
                fmt(r[k], r[f"{k}_sem"], _digits(table, k) if k.startswith("d_") else 3)
                for k in PSI_S_COLUMNS
            )
            + f" | {r['seconds'] / 60:.1f} min |"
        )
    page.md += [
        "",
        page.image("Fig. 9", path),
        "",
        prose.best_psi_s(table, best) + " " + prose.psi_sentence(table),
        "",
    ]
    paper_best = next((r for r in table if r["psi_s"] == PAPER_BEST_PSI_S), None)
    if paper_best is not None and "test_sentence_exact_vs_0" in paper_best:
        page.md += [
            f"### psi_s = 0 against psi_s = {PAPER_BEST_PSI_S:g} (t-test)",
            "",
            prose.psi_s_ttest(paper_best),
            "",
        ]
    if data is not None:
        _psi_s_pca(page, psi_runs, table, best["psi_s"], data)


def _digits(table: list[dict], column: str) -> int:
    """Decimals that show a psi_s table column's values with three significant digits (the Csc
    distances of small codes are ~0.01)."""
    largest = max(
        (abs(r[column]) for r in table if r[column] is not None and math.isfinite(r[column])), default=1.0
    )
    return 3 if largest >= 0.1 else min(6, 2 - math.floor(math.log10(largest or 1e-6)))


def _psi_s_pca(page: Page, psi_runs: list[RunRecord], table: list[dict], best: float, data: Any) -> None:
    """Fig. 9 (e-g): the somatosensory Csc of the smallest, best and largest psi_s."""
    shown = (min(x["psi_s"] for x in table), best, max(x["psi_s"] for x in table))
    rows = []
    for value in sorted({float(r.params["psi_s"]) for r in psi_runs}):
        runs = [r for r in psi_runs if float(r.params["psi_s"]) == value and r.checkpoint]
        if runs and value in shown:
            rows.append((f"psi_s={value:g}", csc_panels(runs[0], data, ("somatosensory",))))
    if not rows:
        return
    path = page.figure("fig9_pca.png")
    panels = [p for _, ps in rows for p in ps]
    for (label, _), p in zip(rows, panels, strict=True):
        p["title"] = f"{label}: {p['title']}"
    figures.figure_pca([("psi_s", panels)], path)
    page.report.data["psi_s_pca"] = panels
    page.md += [
        "Fig. 9 (e-g)-style: the somatosensory Csc (PCA) for the smallest, best and "
        "largest psi_s "
        "(fold 0, init 0; colour = manipulation; black edge = test scene).",
        "",
        page.image("Fig. 9 e-g", path),
        "",
    ]


def cosine(page: Page, store: RunStore) -> None:
    """Fig. 3 from the cosine sweep: epochs, d_avg and d_rel per psi, one run's contexts per psi."""
    cos_runs = store.runs(experiment="cosine")
    if not cos_runs:
        return
    table = cosine_table(cos_runs)
    page.report.data["cosine"] = table
    examples = {}
    for r in cos_runs:
        if r.init == 0:
            points = store.artifact(r.key, "csc")
            if points:
                examples[float(r.params["psi"])] = points
    page.report.data["cosine_examples"] = {f"{k:g}": v for k, v in examples.items()}
    path = page.figure("fig3_cosine.png")
    figures.figure_cosine(table, examples, path)
    runs_per_psi = "/".join(sorted({str(r["runs"]) for r in table}))
    page.md += [
        "## Contrary cosines (Fig. 3)",
        "",
        f"{runs_per_psi} runs per psi (paper: 100), identical seeds for every psi, the paper's learning "
        "rule (eqs. 7-12) with eq. (10)'s constant calibrated on this figure (docs/experiments/faithful.md). "
        "The last two columns compare each psi with psi = 0 on the same seeds: mean difference +- standard "
        "error and the paired t-test's p.",
        "",
        "| psi | epochs | converged | d_avg | d_rel | d_rel - d_rel(psi 0), p | d_avg - d_avg(psi 0), p "
        "| wall time |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in table:
        page.md.append(
            f"| {r['psi']:g} | {fmt(r.get('epochs'), r.get('epochs_sem'), 0)} | "
            f"{fmt(r.get('converged'), None, 2)} | {fmt(r.get('d_avg'), r.get('d_avg_sem'))} | "
            f"{fmt(r.get('d_rel'), r.get('d_rel_sem'))} | {_versus_zero(r, 'd_rel')} | "
            f"{_versus_zero(r, 'd_avg')} | {r['seconds'] / 60:.0f} min |"
        )
    best = max(table, key=lambda r: r.get("d_rel", -1))
    page.md += [
        "",
        page.image("Fig. 3", path),
        "",
        f"d_rel is highest at psi = {best['psi']:g} (paper: best near 5e-5, degrading for larger psi). "
        + prose.cosine_sentence(table),
        "",
    ]


def _versus_zero(row: dict, name: str) -> str:
    """ "+0.013 +- 0.004, p = 0.002" for a cosine table row, "-" for psi = 0."""
    if f"{name}_vs_0" not in row:
        return "-"
    p = row[f"{name}_vs_0_p"]
    return f"{row[f'{name}_vs_0']:+.3f} +- {row[f'{name}_vs_0_sem']:.3f}, p = {p:.2g}"


def csc_spaces(page: Page, evaluate: dict[str, list[RunRecord]], data: Any) -> None:
    """Fig. 10: the Csc spaces of each mode's lowest and highest test-F1 run, by action, colour, object."""
    rows: list[tuple[str, list[dict]]] = []
    for m in [m for m in ("end_to_end", "faithful") if m in evaluate]:
        runs = [r for r in evaluate[m] if r.checkpoint]
        if not runs:
            continue
        ranked = sorted(runs, key=lambda r: r.metrics.get("test", {}).get("f1", 0.0))
        for label, run in (("low", ranked[0]), ("high", ranked[-1])):
            panels = csc_panels(run, data)
            f1 = run.metrics.get("test", {}).get("f1", math.nan)
            for p in panels:
                p["title"] = f"{label} ({m}, test F1 {f1:.2f}): {SPACE_NAMES[p['space']]}"
            rows.append((f"{m}-{label}", panels))
    if not rows:
        return
    page.report.data["pca"] = {name: panels for name, panels in rows}
    page.md += [
        "## Csc spaces after activation by perception (Fig. 10)",
        "",
        "PCA of c_s,T, c_v,T and the c_a,0 produced by the cell assemblies for every "
        "recording (train and "
        "test), normalised per axis, for the run with the lowest and the highest test F1 of "
        "each mode. "
        "Black edge = test scene.",
        "",
    ]
    for colour_by in ("action", "colour", "object"):
        path = page.figure(f"fig10_pca_{colour_by}.png")
        figures.figure_pca(rows, path, colour_by)
        page.md += [f"Coloured by {colour_by}:", "", page.image(f"Fig. 10 by {colour_by}", path), ""]
