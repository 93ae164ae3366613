"""`mtrnn evaluate --split` and `mtrnn train --split`: the protocol splits from the command line,
refused with a reason before any work (a Latin square has 4 folds, the size split needs its
sizes), and the training-size curve as one protocol per size in the run store."""

from __future__ import annotations

import json

import pytest

from model.experiments.runstore import RunStore
from server.cli import main

TINY = [
    "--set=training.epochs_auditory=2",
    "--set=training.epochs_somatosensory=2",
    "--set=training.epochs_visual=2",
    "--set=training.epochs_assemblies=2",
]


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (
            ["evaluate", "--mode", "faithful", "--split", "objects", "--folds", "5"],
            "at most 4 folds, got 5 folds",
        ),
        (
            ["evaluate", "--mode", "peer", "--split", "action-object", "--folds", "10"],
            "action-object split has 4 folds",
        ),
        (["evaluate", "--mode", "faithful", "--split", "size"], "the size split needs train_scenes"),
        (
            ["evaluate", "--mode", "faithful", "--split", "size", "--train-scenes", "8", "64"],
            r"in 1..48 \(the curve: 8, 16, 32, 48\), got 64",
        ),
        (["evaluate", "--mode", "faithful", "--train-scenes", "8"], "train_scenes is the size split's"),
        (["train", "--mode", "faithful", "--split", "objects", "--fold", "4", "--out", "x"], "got fold 4"),
    ],
)
def test_a_split_the_protocol_cannot_run_is_refused_before_any_work(argv, says, tmp_path) -> None:
    argv = [*argv, "--run-dir", str(tmp_path)] if argv[0] == "evaluate" else argv
    with pytest.raises(SystemExit, match=says):
        main(argv)
    assert not (tmp_path / "runs.sqlite").exists()


def test_an_unknown_split_is_an_argparse_error(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["evaluate", "--mode", "faithful", "--split", "colours"])
    assert "invalid choice: 'colours'" in capsys.readouterr().err


@pytest.mark.slow
def test_the_size_curve_runs_one_protocol_per_size_against_the_same_novel_scenes(tmp_path, capsys) -> None:
    argv = ["evaluate", "--mode", "faithful", "--split", "size", "--train-scenes", "2", "4"]
    argv += ["--folds", "1", "--inits", "1", "--workers", "1", "--run-dir", str(tmp_path), "--json", *TINY]
    assert main(argv) == 0
    answers = json.loads(capsys.readouterr().out)
    assert [(a["split"], a["train_scenes"], len(a["runs"])) for a in answers] == [
        ("size", 2, 1),
        ("size", 4, 1),
    ]
    runs = RunStore(tmp_path).runs(split="size")
    assert sorted(r.train_scenes for r in runs) == [2, 4]
    assert [r.metrics["train"]["n"] for r in sorted(runs, key=lambda r: r.train_scenes)] == [8, 16]
    assert {r.metrics["test"]["n"] for r in runs} == {64}  # the 16 novel scenes x 4 recordings


def test_train_takes_config_overrides_and_names_a_bad_one(tmp_path, capsys) -> None:
    out = tmp_path / "rprop"
    argv = ["train", "--mode", "faithful", "--out", str(out), "--epochs-scale", "0.01", "--json"]
    assert main([*argv, "--set", "training.optimiser=rprop"]) == 0
    meta = json.loads((out / "meta.json").read_text())
    assert meta["config"]["training"]["optimiser"] == "rprop"  # the shipped faithful model's reading
    assert main([*argv, "--set", "training.no_such_key=1"]) == 2
    assert "unknown config key 'training.no_such_key'" in capsys.readouterr().out
