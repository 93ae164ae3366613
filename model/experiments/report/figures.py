"""The report's matplotlib figures: modes side by side, Fig. 9 (psi_s), Fig. 3 (cosines) and the
Fig. 10-style PCA panels, each written as a PNG."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from model.experiments.report.tables import MODES, PAPER, SPLITS

# The app's palette (web/js/palette.js, Okabe-Ito): the modes in the same colours on the page and here.
MODE_COLOURS = {"faithful": "#0072B2", "end_to_end": "#E69F00", "peer": "#009E73"}


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def figure_modes(summaries: dict[str, dict], path: Path) -> None:
    plt = _pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    names = [m for m in MODES if m in summaries]
    for ax, (metric, label) in zip(
        axes,
        (("sentence_exact", "sentence exact"), ("f1", "phoneme F1"), ("edit_distance", "edit distance")),
        strict=True,
    ):
        width = 0.8 / max(1, len(names))
        for i, mode in enumerate(names):
            means = [summaries[mode].get(s, {}).get(metric, {}).get("mean", np.nan) for s in SPLITS]
            sems = [summaries[mode].get(s, {}).get(metric, {}).get("sem", 0.0) for s in SPLITS]
            x = np.arange(len(SPLITS)) + (i - (len(names) - 1) / 2) * width
            ax.bar(x, means, width, yerr=sems, capsize=3, label=mode, color=MODE_COLOURS.get(mode))
        if metric in PAPER["train"]:
            ax.scatter(
                np.arange(3),
                [PAPER[s][metric] for s in SPLITS],
                marker="D",
                color="black",
                zorder=5,
                label="paper (mean)",
            )
        ax.set_xticks(np.arange(3), SPLITS)
        ax.set_xlabel("split")
        ax.set_ylabel(f"{label} (mean +- s.e.)")
        ax.set_title(label)
        ax.grid(axis="y", alpha=0.3)
    axes[1].legend(fontsize=8, loc="lower right")  # the panel with every mode and the paper's marks
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_psi_s(table: list[dict], path: Path) -> None:
    """Fig. 9 (a-d): mixed F1, mixed edit distance, d_avg / d_rel, d_inter / d_intra over psi_s."""
    plt = _pyplot()
    x = [r["psi_s"] for r in table]
    fig, axes = plt.subplots(1, 4, figsize=(16, 3.6))
    panels = (
        ("(a) mixed F1", [("mixed_f1", "F1")]),
        ("(b) mixed edit distance", [("mixed_edit_distance", "edit distance")]),
        ("(c) d_avg, d_rel (Csc of MTRNN_s)", [("d_avg", "d_avg"), ("d_rel", "d_rel")]),
        ("(d) d_inter, d_intra (Csc of MTRNN_s)", [("d_inter", "d_inter"), ("d_intra", "d_intra")]),
    )
    for ax, (title, series) in zip(axes, panels, strict=True):
        for key, label in series:
            y = np.array([r[key] for r in table], dtype=float)
            e = np.array([r[f"{key}_sem"] for r in table], dtype=float)
            ax.errorbar(x, y, yerr=e, marker="o", capsize=3, label=label)
        ax.set_xscale("log")
        ax.set_xlabel("psi_s")
        ax.set_ylabel(", ".join(label for _, label in series))
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3)
        if len(series) > 1:
            ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_cosine(table: list[dict], examples: dict[float, list[list[float]]], path: Path) -> None:
    """Fig. 3: (a) epochs, (b) d_avg and d_rel over psi, (c-f) one run's abstracted contexts per psi."""
    plt = _pyplot()
    n = len(examples)
    fig, axes = plt.subplots(1, 2 + n, figsize=(4 * (2 + n), 3.6))
    labels = [f"{r['psi']:g}" for r in table]
    xs = np.arange(len(table))
    axes[0].errorbar(
        xs,
        [r.get("epochs", np.nan) for r in table],
        yerr=[r.get("epochs_sem", 0) for r in table],
        marker="o",
        capsize=3,
    )
    axes[0].set_title("(a) training epochs")
    axes[0].set_ylabel("epochs to converge")
    for key in ("d_avg", "d_rel"):
        axes[1].errorbar(
            xs,
            [r.get(key, np.nan) for r in table],
            yerr=[r.get(f"{key}_sem", 0) for r in table],
            marker="o",
            capsize=3,
            label=key,
        )
    axes[1].set_title("(b) d_avg and d_rel")
    axes[1].set_ylabel("distance (eqs. 13-15)")
    axes[1].legend(fontsize=8)
    for ax in axes[:2]:
        ax.set_xticks(xs, labels)
        ax.set_xlabel("psi")
        ax.grid(alpha=0.3)
    for k, (ax, (psi, points)) in enumerate(zip(axes[2:], sorted(examples.items()), strict=True)):
        p = np.asarray(points)
        for i, (x, y) in enumerate(p[:, :2]):
            ax.scatter([x], [y], s=60, label=f"seq {i + 1}")
        ax.set_title(f"({chr(ord('c') + k)}) psi = {psi:g}")
        ax.set_xlabel("Csc 1")
        ax.set_ylabel("Csc 2")
        ax.grid(alpha=0.3)
    if n:
        axes[2].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _scatter_panels(ax_row, panels: list[dict], colour_by: str) -> None:
    import matplotlib.pyplot as plt

    for ax, panel in zip(ax_row, panels, strict=True):
        labels = panel[colour_by]
        uniq = sorted(set(labels))
        cmap = plt.get_cmap("tab10")
        xy = np.asarray(panel["xy"])
        for j, u in enumerate(uniq):
            m = np.array([lab == u for lab in labels])
            ax.scatter(
                xy[m, 0],
                xy[m, 1],
                s=14,
                color=cmap(j % 10),
                label=u,
                edgecolors=[
                    "k" if s == "test" else "none" for s, keep in zip(panel["split"], m, strict=True) if keep
                ],
            )
        ax.set_title(panel["title"], fontsize=9)
        ax.set_xlabel("PC1")
        ax.set_ylabel("PC2")
        ax.grid(alpha=0.3)
    ax_row[0].legend(fontsize=7, title=colour_by, loc="best")


def figure_pca(rows: list[tuple[str, list[dict]]], path: Path, colour_by: str = "action") -> None:
    plt = _pyplot()
    columns = max(len(panels) for _, panels in rows)
    fig, axes = plt.subplots(len(rows), columns, figsize=(4.4 * columns, 3.8 * len(rows)), squeeze=False)
    for ax_row, (_, panels) in zip(axes, rows, strict=True):
        _scatter_panels(ax_row, panels, colour_by)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_size_curve(curve: dict[str, list[dict]], path: Path) -> None:
    """Test sentence exact against the number of training scenes, one line per mode."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for mode, points in curve.items():
        x = [p["train_scenes"] for p in points]
        y = np.array([np.nan if p["mean"] is None else p["mean"] for p in points], dtype=float)
        e = np.array([p["sem"] or 0.0 for p in points], dtype=float)
        ax.errorbar(x, y, yerr=e, marker="o", capsize=3, label=mode, color=MODE_COLOURS.get(mode))
    ax.set_xticks(sorted({p["train_scenes"] for points in curve.values() for p in points}))
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel("scenes trained on (of 64)")
    ax.set_ylabel("sentence exact on the novel scenes (mean +- s.e.)")
    ax.set_title("Training-size curve: exact on 16 novel scenes")
    ax.grid(alpha=0.3)
    ax.legend(title="mode", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
