"""Epoch budgets that mean the same for every training mode: the Jobs page's presets and the CLI's
`--epochs-scale` multiply every epoch count *that mode reads* (`EPOCH_FIELDS`).

Each mode keeps its epochs in its own place: `faithful` in `training.epochs_*` (its four stages),
`end_to_end` in its named options (stage 1 per attempt, its self-check period, stages 2 and 3;
it ignores `training.epochs_*`), `peer` in its own `epochs`. Scaling only `training.epochs_*`
left `end_to_end` at full length.

`PRESETS[name].minutes[mode]` is the wall time of one job of that preset (one fold: train,
score, save) measured with `benchmarks/presets.py` on the 2-core development machine, itself busy
(load average 5 -> 14 during the run, so a quiet machine is faster: the shipped end_to_end model's
own training took 34 s, the peer's 300 epochs 80-105 s); the labels show it.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from model.training.end_to_end.options import EndToEndOptions

EPOCH_FIELDS: dict[str, tuple[str, ...]] = {
    "faithful": (
        "training.epochs_auditory",
        "training.epochs_somatosensory",
        "training.epochs_visual",
        "training.epochs_assemblies",
    ),
    "end_to_end": (
        "options.auditory_epochs",
        "options.auditory_check_every",
        "options.perception_epochs",
        "options.joint_epochs",
    ),
    "peer": ("epochs",),
}
OPTION_DEFAULTS: dict[str, dict[str, Any]] = {"end_to_end": asdict(EndToEndOptions())}


@dataclass(frozen=True)
class Preset:
    """An epoch budget: every epoch count of the mode times `scale`."""

    title: str
    scale: float
    minutes: dict[str, float]  # measured wall time of one job per mode (benchmarks/presets.py)

    def label(self, mode: str) -> str:
        return f"{self.title}: about {_minutes(self.minutes[mode])}"


def _minutes(value: float) -> str:
    return f"{value * 60:.0f} s" if value < 1 else f"{value:.1f} min"


PRESETS: dict[str, Preset] = {
    "quick": Preset(
        "quick (a tenth of every stage's epochs)",
        0.1,
        {"faithful": 0.31, "end_to_end": 0.36, "peer": 0.26},
    ),
    "paper": Preset(
        "full (the mode's defaults, Table 1 for faithful)",
        1.0,
        {"faithful": 1.26, "end_to_end": 0.74, "peer": 7.7},
    ),
}


def scale_epochs(config: dict[str, Any], mode: str, scale: float) -> dict[str, Any]:
    """A copy of the mode's config dict with each of its `EPOCH_FIELDS` times `scale` (rounded, at
    least 1; a count of 0, a stage left out, stays 0). An option not in `config` is read from the
    mode's defaults. `scale` 1 returns the config unchanged."""
    if mode not in EPOCH_FIELDS:
        raise ValueError(f"unknown training mode {mode!r}; available: {sorted(EPOCH_FIELDS)}")
    if not scale > 0:
        raise ValueError(f"the epoch scale must be > 0, got {scale}")
    out = {k: dict(v) if isinstance(v, dict) else v for k, v in config.items()}
    if scale == 1:
        return out
    for dotted in EPOCH_FIELDS[mode]:
        *path, leaf = dotted.split(".")
        node = out
        for part in path:
            node = node.setdefault(part, {})
        value = node.get(leaf, OPTION_DEFAULTS.get(mode, {}).get(leaf))
        node[leaf] = 0 if value == 0 else max(1, round(value * scale))
    return out
