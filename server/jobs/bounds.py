"""What a job may override: the keys of its mode's config and the range of every value, checked
before a job is queued (a job of 1e9 epochs or of 100,000-unit layers is refused, 422).

An override is a dotted key of the mode's config (`model.experiments.protocol.default_config`:
"training.epochs_auditory", "auditory.cf", "epochs" for peer) or one of the mode's named options
("options.recombine": fields of `EndToEndOptions` / `FaithfulOptions`). `RANGES` gives each leaf's
type and range (the same for every section it appears in); the sizes fixed by the encodings (IO
layers, the peer's input sizes) and T_a (set by training) are not overridable. After the ranges,
the whole config is built once, so that rules across fields (|Csc| <= |Cs|, options that exclude
each other) are refused too.

A job's protocol split (`model.experiments.splits`) is checked with `check_split`: a Latin-square
split has 4 folds, the training-size curve needs its number of training scenes (and only it takes one).
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, fields
from typing import Any

from model.config import (
    LEARNING_RULES,
    OBJECT_MOTION_READERS,
    PROPRIOCEPTION_READINGS,
    MultiMTRNNConfig,
    mode_options,
)
from model.experiments.protocol import apply_overrides, default_config
from model.experiments.splits import SPLITS, SQUARE_FOLDS
from model.training.end_to_end.options import EndToEndOptions
from model.training.faithful import FaithfulOptions
from model.training.peer import PeerConfig
from server.services.errors import Invalid
from server.settings import CORES

MAX_EPOCHS = 5000  # per stage (Table 1's longest is 2000)
MAX_UNITS = 512  # per layer (Table 1's largest is 80)
MAX_TRAIN_SCENES = 48  # the size split trains on at most the 3 quarters of the 64 scenes it does not test
SQUARE_SPLITS = ("objects", "action-object")  # Latin squares: folds 0..SQUARE_FOLDS - 1


@dataclass(frozen=True)
class Range:
    """A value's type and its inclusive range (or its choices)."""

    kind: type
    low: float = -math.inf
    high: float = math.inf
    choices: tuple[str, ...] = ()

    def text(self) -> str:
        if self.kind is bool:
            return "true or false"
        if self.choices:
            return " or ".join(repr(c) for c in self.choices)
        return f"{'an integer' if self.kind is int else 'a number'} in {self.low:g}..{self.high:g}"

    def check(self, key: str, value: Any) -> Any:
        """`value` as this range's type; Invalid naming `key` otherwise."""
        ok = False
        if self.kind is bool:
            ok = isinstance(value, bool)
        elif self.kind is str:
            ok = value in self.choices
        elif isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value):
            whole = float(value).is_integer()
            value = float(value) if self.kind is float else int(value) if whole else value
            ok = (self.kind is float or whole) and self.low <= value <= self.high
        if not ok:
            raise Invalid(f"override {key}: must be {self.text()}, got {_shown(value)}")
        return value


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _ints(low: float, high: float) -> Range:
    return Range(int, low, high)


def _floats(low: float, high: float) -> Range:
    return Range(float, low, high)


FLAG = Range(bool)
EPOCHS, LAYER, FRACTION = _ints(1, MAX_EPOCHS), _ints(1, MAX_UNITS), _floats(0, 1)
RANGES: dict[str, Range] = {
    # MTRNN layers (Table 1) and the peer's sizes
    **dict.fromkeys(("cf", "cs", "csc", "hidden", "code"), LAYER),
    **dict.fromkeys(("tau_io", "tau_cf", "tau_cs"), _floats(1, 1000)),
    **dict.fromkeys(("weight_init", "csc_init"), _floats(0, 10)),
    "io_activation": Range(str, choices=("softmax", "logistic")),
    # training (3.1.4) and the peer's
    "optimiser": Range(str, choices=LEARNING_RULES),
    "zeta_gain": _floats(0, 10000),
    **dict.fromkeys(("lr", "lr_max"), _floats(0, 10)),
    **dict.fromkeys(("lr_min", "adam_lr", "alpha", "psi_s", "psi_v"), FRACTION),
    "xi_increase": _floats(1, 2),
    "xi_decrease": FRACTION,
    **dict.fromkeys(
        ("epochs_auditory", "epochs_somatosensory", "epochs_visual", "epochs_assemblies"), EPOCHS
    ),
    "epochs": EPOCHS,
    "progress_every": _ints(1, 1000),
    "threads": _ints(1, CORES),
    "binding": _floats(0, 100),
    "batch": _ints(0, 4096),
    "cosine": FLAG,
    "clip": _floats(0, 100),
    "stride": _ints(1, 16),
    "normalise": FLAG,
    "margin": _ints(0, 100),
    # end_to_end's options
    **dict.fromkeys(
        (
            "word_loss",
            "slot_softmax",
            "modality_experts",
            "hard_words",
            "vision_centroid",
            "normalise_inputs",
            "factorised_vision",
        ),
        FLAG,
    ),
    "word_points": _ints(1, 64),
    **dict.fromkeys(("word_from", "average_from", "weight_decay"), FRACTION),
    "selection_scenes": _ints(0, 16),
    "select_every": _ints(1, 1000),
    "input_noise": _floats(0, 10),
    "vision_window": _ints(0, 1000),
    "time_warp": _floats(0, 0.9),
    **dict.fromkeys(("recombine", "recombine_objects"), _floats(0, 100)),
    "recombine_pairs": _ints(0, 16),
    "hand_path": Range(str, choices=PROPRIOCEPTION_READINGS),
    "object_motion": Range(str, choices=OBJECT_MOTION_READERS),
    **dict.fromkeys(("auditory_epochs", "perception_epochs"), EPOCHS),
    **dict.fromkeys(("auditory_check_every", "joint_epochs"), _ints(0, MAX_EPOCHS)),
    "auditory_attempts": _ints(1, 10),
    # faithful's options
    "perception_targets": Range(str, choices=("recording", "scene")),
    "assemblies_solver": Range(str, choices=("lms", "optimum")),
}
# settings a mode's config carries but the mode does not read (overriding them would change nothing)
IGNORED: dict[str, dict[str, str]] = {
    "end_to_end": {
        "training.epochs_auditory": "options.auditory_epochs",
        "training.epochs_somatosensory": "options.perception_epochs",
        "training.epochs_visual": "options.perception_epochs",
        "training.epochs_assemblies": "options.perception_epochs",
    }
}
OPTIONS: dict[str, type | None] = {"faithful": FaithfulOptions, "end_to_end": EndToEndOptions, "peer": None}


def _leaves(config: dict, prefix: str = "") -> list[str]:
    out = []
    for key, value in config.items():
        if isinstance(value, dict):
            out += _leaves(value, f"{prefix}{key}.")
        else:
            out.append(f"{prefix}{key}")
    return out


def overridable(mode: str) -> list[str]:
    """Every key a job of `mode` may override."""
    options = OPTIONS[mode]
    keys = _leaves(default_config(mode)) + [f"options.{f.name}" for f in (fields(options) if options else ())]
    ignored = IGNORED.get(mode, {})
    return sorted(k for k in keys if k.rsplit(".", 1)[-1] in RANGES and k not in ignored)


def ranges_text() -> str:
    """Every overridable leaf with its range, for the API's description."""
    by_text: dict[str, list[str]] = {}
    for leaf, bound in RANGES.items():
        by_text.setdefault(bound.text(), []).append(leaf)
    return "; ".join(f"{', '.join(leaves)}: {text}" for text, leaves in by_text.items())


def check_overrides(
    mode: str, overrides: dict[str, Any], base: dict[str, Any] | None = None
) -> dict[str, Any]:
    """The mode's full config dict (`base`, default: the mode's defaults) with `overrides` applied,
    every key and value checked."""
    known = overridable(mode)
    checked = {}
    for key, value in overrides.items():
        if key not in known:
            near = difflib.get_close_matches(key, known, n=3)
            hint = f"; did you mean {', '.join(near)}?" if near else f"; it has: {', '.join(known)}"
            if key in IGNORED.get(mode, {}):
                hint = f": {mode} ignores it and reads {IGNORED[mode][key]}"
            raise Invalid(f"override {key!r} is not a setting of mode {mode}{hint}")
        checked[key] = RANGES[key.rsplit(".", 1)[-1]].check(key, value)
    config = apply_overrides(default_config(mode) if base is None else base, checked)
    try:
        if OPTIONS[mode] is None:
            PeerConfig.from_dict(config)
        else:
            mode_options(OPTIONS[mode], MultiMTRNNConfig.from_dict(config))  # type: ignore[arg-type]
    except (TypeError, ValueError) as err:
        raise Invalid(f"overrides: {err}") from None
    return config


def check_split(split: str, train_scenes: int | None = None, folds: int = 1, fold: int = 0) -> None:
    """Invalid unless `split` is one of `SPLITS` that has `folds` folds and fold `fold` (a
    Latin-square split has SQUARE_FOLDS) and, for the size split and only for it, 1..MAX_TRAIN_SCENES
    training scenes."""
    if split not in SPLITS:
        raise Invalid(f"split must be one of {', '.join(SPLITS)}, got {_shown(split)}")
    if split in SQUARE_SPLITS and (folds > SQUARE_FOLDS or fold >= SQUARE_FOLDS):
        asked = f"{folds} folds" if folds > SQUARE_FOLDS else f"fold {fold}"
        raise Invalid(
            f"the {split} split has {SQUARE_FOLDS} folds, 0..{SQUARE_FOLDS - 1} (its Latin squares "
            f"cover every pair in {SQUARE_FOLDS}): ask for at most {SQUARE_FOLDS} folds, got {asked}"
        )
    if split == "size":
        if not 1 <= (train_scenes or 0) <= MAX_TRAIN_SCENES:
            raise Invalid(
                f"the size split needs train_scenes, the scenes to train on, in 1..{MAX_TRAIN_SCENES} "
                f"(the curve: 8, 16, 32, 48), got {_shown(train_scenes)}"
            )
    elif train_scenes is not None:
        raise Invalid(f"train_scenes is the size split's; the {split} split trains on its own scenes")
