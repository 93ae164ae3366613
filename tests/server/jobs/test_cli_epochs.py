"""The CLI's `--epochs-scale` means what the Jobs page's presets mean, for every mode, and
`mtrnn train` shows one progress bar per stage and per attempt of a restarted stage."""

from __future__ import annotations

import argparse

import pytest

from server.commands.evaluate import build_config
from server.commands.train import StageBars, _config


def _args(mode: str, scale: float, options: list[str] | None = None) -> argparse.Namespace:
    return argparse.Namespace(mode=mode, epochs_scale=scale, option=options or [], set=[])


def test_epochs_scale_shortens_end_to_end_and_peer_too() -> None:
    quick = _config(_args("end_to_end", 0.1, ["recombine=0"]))
    assert quick["options"]["auditory_epochs"] == 150 and quick["options"]["recombine"] == 0
    assert _config(_args("peer", 0.1))["epochs"] == 30
    assert _config(_args("faithful", 0.1))["training"]["epochs_assemblies"] == 200
    assert build_config({"options.perception_epochs": 7}, "end_to_end", 0.1)["options"] == {
        "auditory_epochs": 150,
        "auditory_check_every": 25,
        "perception_epochs": 7,  # --set after the scale
        "joint_epochs": 0,
    }
    with pytest.raises(ValueError, match="no named options"):
        _config(_args("peer", 1.0, ["x=1"]))


def test_train_shows_a_bar_per_stage_and_attempt(capsys: pytest.CaptureFixture[str]) -> None:
    bars = StageBars()
    for attempt in (1, 2):
        for epoch in (5, 10):
            bars(
                {
                    "stage": "auditory",
                    "epoch": epoch,
                    "epochs": 10,
                    "loss": 0.5,
                    "attempt": attempt,
                    "attempts": 3,
                }
            )
    bars({"stage": "perception", "epoch": 3, "epochs": 3, "loss": 0.1})
    bars.close()
    err = capsys.readouterr().err
    assert "auditory (attempt 1 of 3)" in err and "auditory (attempt 2 of 3)" in err
    assert "perception" in err and "10/10" in err and "<" in err  # tqdm's elapsed<remaining
