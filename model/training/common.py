"""What every training mode shares: the trained model it returns, padded batches, the desired
utterance activity, the optimisers (3.1.4), progress reports, and the meta a checkpoint keeps."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import torch
from torch import Tensor

from model.config import LEARNING_RULES, MultiMTRNNConfig, TrainingConfig, mode_options
from model.data import SequenceSet
from model.encoding.utterance import PHONEMES, Lexicon, encode_utterance
from model.familiarity import Familiarity
from model.multimtrnn import Description, MultiMTRNN, somatosensory_inputs, visual_inputs
from model.training.adaptive_rates import AdaptiveRates

ProgressFn = Callable[[dict], None]
GENERATION_MARGIN = 10  # steps of silence after the longest training utterance (5 phoneme slots)


class Describer(Protocol):
    """A trained model that describes scenes: the MultiMTRNN, or the peer baseline."""

    def describe_batch(
        self, proprioception: Sequence[np.ndarray], vision: Sequence[np.ndarray], lexicon: Lexicon
    ) -> list[Description]: ...

    def describe(self, proprioception: np.ndarray, vision: np.ndarray, lexicon: Lexicon) -> Description: ...

    def state_dict(self) -> dict[str, Any]: ...


@dataclass
class TrainedModel:
    """A trained model, its loss history and what a checkpoint must remember."""

    model: Describer
    history: list[dict]  # {"stage", "epoch", "loss"} every `progress_every` epochs
    meta: dict  # mode, seed, ids, lexicon words, config, assemblies spec, seconds per stage
    csc: dict[str, np.ndarray] = field(default_factory=dict)  # learned training tables (c_0, c_T)
    familiarity: Familiarity | None = None  # how far a recording lies from the training set (`train`)

    @property
    def lexicon(self) -> Lexicon:
        return Lexicon(self.meta["lexicon"])


class Recipe(Protocol):
    """How a MultiMTRNN mode trains, given its ready config and options."""

    def __call__(
        self,
        data: SequenceSet,
        config: MultiMTRNNConfig,
        seed: int,
        progress: ProgressFn | None,
        options: Any,
    ) -> TrainedModel: ...


@dataclass(frozen=True)
class MultiMTRNNMode:
    """A training mode of the MultiMTRNN: called as `(data, config, seed, progress, options)` it makes
    `config` ready (`prepare`: None, a dict or a `MultiMTRNNConfig`), reads the mode's named options
    from `config.options` unless `options` are given, and runs `recipe` on `training.threads` threads."""

    recipe: Recipe
    options_class: type  # the mode's options dataclass (`model.config.mode_options`)

    def __call__(
        self,
        data: SequenceSet,
        config: MultiMTRNNConfig | dict | None = None,
        seed: int = 0,
        progress: ProgressFn | None = None,
        options: Any = None,
    ) -> TrainedModel:
        config = prepare(data, config)
        options = options or mode_options(self.options_class, config)
        with torch_threads(config.training.threads):
            return self.recipe(data, config, seed, progress, options)


@contextmanager
def torch_threads(threads: int) -> Iterator[None]:
    """torch on `threads` threads inside the block (one run per core is fastest), restored after."""
    before = torch.get_num_threads()
    torch.set_num_threads(threads)
    try:
        yield
    finally:
        torch.set_num_threads(before)


# --- batches ------------------------------------------------------------------------------------


@dataclass
class Batch:
    """A SequenceSet as padded tensors."""

    proprioception: Tensor  # [B, T_s, 5]
    proprioception_lengths: Tensor  # [B]
    vision: Tensor  # [B, T_v, F] (first config.visual.io columns)
    vision_lengths: Tensor  # [B]
    utterances: Tensor  # [B, T_a, |B|] desired softmax activity, padded with silence (uniform)
    utterance_lengths: Tensor  # [B] encoding length of each utterance


def generation_steps(utterances: Sequence[str], margin: int = GENERATION_MARGIN) -> int:
    """T_a: the longest encoding among `utterances` plus `margin` steps."""
    return max(len(encode_utterance(u)) for u in utterances) + margin


def encode_utterances(utterances: Sequence[str], steps: int) -> tuple[Tensor, Tensor]:
    """Desired activity [B, steps, |B|]: each encoding, then uniform activity (the encoding's own
    silence, 1/|B|) so the generator learns to stay quiet until step T_a."""
    out = torch.full((len(utterances), steps, len(PHONEMES)), 1.0 / len(PHONEMES))
    lengths = torch.zeros(len(utterances), dtype=torch.long)
    for i, u in enumerate(utterances):
        enc = torch.from_numpy(encode_utterance(u))
        n = min(len(enc), steps)
        out[i, :n] = enc[:n]
        lengths[i] = n
    return out, lengths


def make_batch(data: SequenceSet, config: MultiMTRNNConfig) -> Batch:
    p, p_len = somatosensory_inputs(data.proprioception, config, vision=data.vision)
    v, v_len = visual_inputs(data.vision, config)
    u, u_len = encode_utterances(data.utterances, config.generation_steps)
    return Batch(p, p_len, v, v_len, u, u_len)


def prepare(data: SequenceSet, config: MultiMTRNNConfig | dict | None) -> MultiMTRNNConfig:
    """A copy of `config` (default: Table 1) with T_a set from the training utterances."""
    if len(data) == 0:
        raise ValueError("cannot train on an empty SequenceSet")
    if not isinstance(config, dict):
        config = (config or MultiMTRNNConfig()).to_dict()
    config = MultiMTRNNConfig.from_dict(config)
    config.generation_steps = generation_steps(data.utterances)
    return config


# --- optimisers ---------------------------------------------------------------------------------


def make_optimiser(groups: list[dict], training: TrainingConfig) -> torch.optim.Optimizer:
    """The learning rule of `training.optimiser` over parameter groups (None: sign-based "rprop",
    the improved modes' rule; faithful resolves None to "paper" itself):

    - "paper": `AdaptiveRates`, the paper's rates times gradients (eqs. 7-10, 12). A group with
      "context_of": net is a c_0 or c_T table whose rate is zeta of `net` (eq. 10) times its
      optional "scale" (eq. 12: psi).
    - "rprop": `torch.optim.Rprop`, rates times the gradient's sign; a group's "scale" multiplies
      its rates (eq. 12's psi as a step size: a gradient scale would do nothing under a sign rule).
    - "adam": Adam, "scale" multiplies the group's learning rate.
    """
    rule = rule_of(training)
    out = []
    for g in groups:
        scale = g.get("scale", 1.0)
        params = [p for p in g["params"] if p.requires_grad]
        if not params:
            continue
        if rule == "paper":
            out.append({"params": params, "scale": scale, "context_of": g.get("context_of")})
        elif rule == "rprop":
            out.append(
                {
                    "params": params,
                    "lr": training.lr * scale,
                    "step_sizes": (training.lr_min * scale, training.lr_max * scale),
                }
            )
        else:
            out.append({"params": params, "lr": training.adam_lr * scale})
    if rule == "paper":
        return AdaptiveRates(
            out,
            lr=training.lr,
            etas=(training.xi_decrease, training.xi_increase),
            rate_bounds=(training.lr_min, training.lr_max),
            zeta_gain=training.zeta_gain,
        )
    if rule == "rprop":
        return torch.optim.Rprop(
            out,
            lr=training.lr,
            etas=(training.xi_decrease, training.xi_increase),
            step_sizes=(training.lr_min, training.lr_max),
        )
    return torch.optim.Adam(out, lr=training.adam_lr)


def rule_of(training: TrainingConfig) -> str:
    """The learning rule `training` names (None: "rprop"); ValueError for an unknown one."""
    rule = training.optimiser or "rprop"
    if rule not in LEARNING_RULES:
        raise ValueError(f"unknown optimiser {rule!r} ({', '.join(LEARNING_RULES)})")
    return rule


def uniform(shape: tuple[int, ...], scale: float, generator: torch.Generator) -> Tensor:
    """Initial values uniform in [-scale, scale]."""
    return (torch.rand(*shape, generator=generator) * 2 - 1) * scale


# --- progress and meta --------------------------------------------------------------------------


class ProgressReporter:
    """Collects history and calls `progress` every `every` epochs and at the last one. While a stage
    restarts from new weights (end_to_end's generator), `attempt` = (n, of) joins the reports."""

    def __init__(self, progress: ProgressFn | None, every: int, history: list[dict]) -> None:
        self.progress, self.every, self.history = progress, max(1, every), history
        self.attempt: tuple[int, int] | None = None

    def __call__(self, stage: str, epoch: int, epochs: int, loss: float, csc: Tensor | None = None) -> None:
        if epoch % self.every and epoch != epochs:
            return
        entry = {"stage": stage, "epoch": epoch, "epochs": epochs, "loss": loss}
        self.history.append(entry)
        if self.progress is not None:
            report = dict(entry)
            if self.attempt is not None:
                report["attempt"], report["attempts"] = self.attempt
            if csc is not None:
                report["csc"] = csc.detach().tolist()
            self.progress(report)


def base_meta(data: SequenceSet, config: MultiMTRNNConfig, model: MultiMTRNN, mode: str, seed: int) -> dict:
    """The meta every MultiMTRNN mode records (see `model.checkpoint`)."""
    return {
        "mode": mode,
        "seed": seed,
        "ids": list(data.ids),
        "lexicon": list(Lexicon.from_sentences(data.utterances).words),
        "generation_steps": config.generation_steps,
        "config": config.to_dict(),
        "assemblies": model.assemblies_spec(),
    }
