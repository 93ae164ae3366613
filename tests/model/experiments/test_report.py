"""The report: tables beside the paper's numbers, figures and the web page's data, from the store."""

from __future__ import annotations

import json

from model.experiments.report import PAPER, build_report, prose
from model.experiments.runstore import RunSpec, RunStore


def _metrics(f1_train: float, f1_test: float) -> dict:
    split = lambda f1: {"f1": f1, "edit_distance": 1 - f1, "sentence_exact": f1 / 2, "word_accuracy": f1}  # noqa: E731
    return {
        "train": split(f1_train),
        "test": split(f1_test),
        "mixed": {k: (split(f1_train)[k] + split(f1_test)[k]) / 2 for k in split(0)},
    }


def _store(tmp_path) -> RunStore:
    store = RunStore(tmp_path / "runs")
    numbers = {"faithful": [(0.9, 0.2), (0.8, 0.3)], "end_to_end": [(1.0, 0.9), (1.0, 0.95)]}
    for mode, runs in numbers.items():
        for fold, (train, test) in enumerate(runs):
            spec = RunSpec("evaluate", mode, fold, 0, fold, {"training": {"epochs_auditory": 10}}, {}, "d")
            store.register([spec])
            store.finish(spec.key, _metrics(train, test), 1.0)
    for psi, shift in ((1e-4, 0.0), (5e-4, 0.1)):
        for fold in range(2):
            spec = RunSpec(
                "psi_s", "faithful", fold, 0, fold, {"training": {"psi_s": psi}}, {"psi_s": psi}, "d"
            )
            store.register([spec])
            m = _metrics(0.8 + shift, 0.2 + shift)
            m["train"].update(
                {
                    "csc.somatosensory.d_avg": 1.0 - shift,
                    "csc.somatosensory.d_rel": 0.9,
                    "csc.somatosensory.d_inter": 0.6 - shift,
                    "csc.somatosensory.d_intra": 0.5,
                }
            )
            store.finish(spec.key, m, 1.0)
    return store


def test_the_report_puts_our_numbers_beside_the_papers_and_explains_each_difference(tmp_path) -> None:
    store = _store(tmp_path)
    out = tmp_path / "docs" / "RESULTS.md"
    report = build_report(store, out, tmp_path / "docs" / "figures", commands=["mtrnn evaluate ..."])
    text = out.read_text()
    assert "| train F1 (mean) | 0.952 | 0.8500 | 1.0000 |" in text
    assert "| test F1 (best run) | 0.638 | 0.3000 | 0.9500 |" in text
    assert "faithful test: F1 0.250 (0.031 worse than the paper's 0.281)" in text
    assert "end_to_end test: F1 0.925 (0.644 better than the paper's 0.281)" in text
    # one sentence per (mode, split) naming its causes by number; each cause is written out once
    assert "faithful train: F1 0.850 (0.102 worse than the paper's 0.952)" in text
    causes = text.split("Why, each cause once:")[1].split("\n\n")[1].splitlines()
    assert [c.split(". ")[0] for c in causes] == [str(n) for n in range(1, len(causes) + 1)]
    assert len(set(causes)) == len(causes) and "The faithful runs used another epoch budget" in text
    assert text.count(prose.CAUSES["end_to_end"]) == 1  # end_to_end train and test share it
    assert "edit distance 0.000 (within 0.02 of the paper's 0.0185)" in text
    assert "| 0.0005 | 0.600 |" in text  # psi_s table: mixed F1 at 5e-4
    assert "best psi_s by mixed F1 is 0.0005" in text
    assert "mtrnn evaluate ..." in text
    names = {p.name for p in report.figures}
    assert names == {"modes.png", "fig9_psi_s.png"}
    assert all(p.stat().st_size > 10_000 for p in report.figures)
    data = json.loads((tmp_path / "docs" / "figures" / "results.json").read_text())
    assert data["paper"] == PAPER and data["modes"]["faithful"]["runs"] == 2
    assert [r["psi_s"] for r in data["psi_s"]] == [1e-4, 5e-4]


def test_an_empty_store_gives_a_report_that_says_so(tmp_path) -> None:
    out = tmp_path / "RESULTS.md"
    build_report(RunStore(tmp_path / "runs"), out, tmp_path / "figures")
    assert "No finished runs" in out.read_text()


def test_runs_of_different_budgets_are_never_mixed_in_one_row(tmp_path) -> None:
    store = _store(tmp_path)
    extra = RunSpec("evaluate", "faithful", 0, 0, 0, {"training": {"epochs_auditory": 99}}, {}, "d")
    store.register([extra])
    store.finish(extra.key, _metrics(0.0, 0.0), 1.0)  # one run of another budget: left out
    text = build_report(store, tmp_path / "R.md", tmp_path / "fig").markdown
    assert "faithful (2 folds × 1 inits = 2 runs)" in text and "| train F1 (mean) | 0.952 | 0.8500 |" in text


def _split_run(
    store: RunStore, mode: str, fold: int, split: str, exact: float, size: int | None = None
) -> None:
    spec = RunSpec(
        "evaluate", mode, fold, 0, fold, {"training": {"epochs_auditory": 10}}, {}, "d", split, size
    )
    store.register([spec])
    m = _metrics(1.0, exact)
    m["test"].update({"slot_action": 1.0, "slot_colour": exact / 2, "slot_object": 0.75})
    store.finish(spec.key, m, 1.0)


def test_each_harder_split_gets_its_table_and_the_size_curve_its_figure(tmp_path) -> None:
    store = _store(tmp_path)
    before = build_report(store, tmp_path / "before" / "R.md", tmp_path / "before" / "fig").markdown
    for fold, exact in enumerate((0.2, 0.4)):
        _split_run(store, "end_to_end", fold, "objects", exact)
        _split_run(store, "peer", fold, "objects", exact + 0.4)
        for size, gain in ((8, 0.0), (16, 0.2), (48, 0.4)):
            _split_run(store, "end_to_end", fold, "size", exact + gain, size)
    report = build_report(store, tmp_path / "R.md", tmp_path / "fig")
    text = report.markdown
    without = text[: text.index("## Objects never seen")] + text[text.index("## Self-organisation") :]
    assert without.split("\n", 3)[3] == before.split("\n", 3)[3]  # the rest: as before, byte for byte
    assert "| mode | exact | phoneme F1 | action | colour | shape |" in text
    assert (
        "| end_to_end (2 folds × 1 inits = 2 runs) | 0.150 ± 0.050 | 0.300 ± 0.100 | 1.000 | "
        "0.150 ± 0.050 | 0.750 |" in text
    )
    assert "| peer (2 folds × 1 inits = 2 runs) | 0.350 ± 0.050 |" in text
    assert "action-object" not in text  # no runs of it: no section
    assert "| mode | 8 scenes | 16 scenes | 48 scenes |" in text
    assert "| end_to_end | 0.150 ± 0.050 (2) | 0.250 ± 0.050 (2) | 0.350 ± 0.050 (2) |" in text
    assert "size_curve.png" in {p.name for p in report.figures}
    assert (tmp_path / "fig" / "size_curve.png").stat().st_size > 10_000
    data = json.loads((tmp_path / "fig" / "results.json").read_text())
    assert [p["train_scenes"] for p in data["size_curve"]["end_to_end"]] == [8, 16, 48]
    assert set(data["splits"]["objects"]) == {"end_to_end", "peer"}
    assert data["modes"]["end_to_end"]["runs"] == 2  # the paper's split's runs only


def _psi_s_store(tmp_path, gains: dict[int, float]) -> RunStore:
    """psi_s 0 and 5e-4 on folds 0-2: 5e-4's novel-scene numbers higher by gains[fold]."""
    store = RunStore(tmp_path / "runs")
    for psi in (0.0, 5e-4):
        for fold, gain in gains.items():
            spec = RunSpec(
                "psi_s", "faithful", fold, 0, fold, {"training": {"psi_s": psi}}, {"psi_s": psi}, "d"
            )
            store.register([spec])
            store.finish(spec.key, _metrics(0.8, 0.3 + (gain if psi else 0.0)), 10.0)
    return store


def test_the_psi_s_section_tests_the_papers_best_value_against_none_paired_by_fold_and_init(tmp_path) -> None:
    out = tmp_path / "R.md"
    build_report(_psi_s_store(tmp_path, {0: 0.1, 1: 0.2, 2: 0.3}), out, tmp_path / "figures")
    text = out.read_text()
    ttest = text.split("### psi_s = 0 against psi_s = 0.0005 (t-test)")[1]
    # sentence exact is f1 / 2 in _metrics: +0.05, +0.10, +0.15, paired t = 3.46 on 2 df
    assert "(3 pairs)" in ttest and "sentence exact +0.100 +- 0.029 (p = 0.074)" in ttest
    assert "phoneme F1 +0.200 +- 0.058 (p = 0.074)" in ttest
    assert "| 0.0005 |" in text and "| 0.5 min |" in text  # 3 runs of 10 s of worker time


def test_a_forcing_that_changes_nothing_says_the_t_test_is_undefined(tmp_path) -> None:
    out = tmp_path / "R.md"
    build_report(_psi_s_store(tmp_path, {0: 0.0, 1: 0.0}), out, tmp_path / "figures")
    assert "sentence exact +0.000 and phoneme F1 +0.000 in every pair, so the paired t-test is undefined" in (
        out.read_text()
    )
