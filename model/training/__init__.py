"""Training the MultiMTRNN: a registry of named modes behind one `train()`.

`faithful` is the paper's staged recipe (3.1.3-3.1.4, 3.2.1, 3.4.3); our readings of what the
paper leaves open are in docs/experiments/faithful.md:
1. MTRNN_a with a learnable c_0 per training *sentence* (3.3: the Csc "had to be trained
   individually for every sentence"; a scene's four recordings share one utterance, hence one
   c_a,0), init +-0.01, teacher forcing alpha = 0.1 (eq. 5), KLD on the softmax IO, full-batch
   BPTT, RPROP on weights, biases and c_0 (eqs. 7-9).
2. MTRNN_s and MTRNN_v with a learnable c_T per training recording (init +-1) and self-organisation
   forcing psi (eqs. 11-12): c_T sits in its own RPROP group whose rates are the weights' rates
   times psi (lr = psi * 0.05, rates in [psi * 1e-6, psi * 1.0]); psi = 0 leaves c_T fixed.
3. The cell assemblies fitted by LMS (eqs. 16-17) from the encoders' abstraction c_s,T, c_v,T of
   each training recording (what the CAs will see when describing a scene; the learned targets
   c_T are only what the encoders were pulled towards) to the learned c_a,0 of its utterance.

`FaithfulOptions` names the departures from that reading (all off by default).

Eq. (10) adapts zeta (c_0's rate) in proportion to the mean rate of the weights of unit i; we
give c_0 RPROP's own per-element rate adaptation instead (same initial rate, same xi+, xi- and
bounds), which needs no extra parameters either and follows the same sign rule.

Other modes (`end_to_end`, in `model.training.end_to_end`) register themselves with `register_mode`.
"""

from __future__ import annotations

import importlib
import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Literal

import numpy as np
import torch
from torch import Tensor, nn

from model.config import MultiMTRNNConfig, TrainingConfig, mode_options
from model.data import SequenceSet
from model.encoding.utterance import PHONEMES, Lexicon, encode_utterance
from model.mtrnn import MTRNN, context_abstraction_loss, kl_divergence, scaled_logistic
from model.multimtrnn import MultiMTRNN, pad_sequences

log = logging.getLogger(__name__)

ProgressFn = Callable[[dict], None]
GENERATION_MARGIN = 10  # steps of silence after the longest training utterance (5 phoneme slots)


@dataclass
class TrainedModel:
    """A trained MultiMTRNN, its loss history and what a checkpoint must remember."""

    model: MultiMTRNN
    history: list[dict]  # {"stage", "epoch", "loss"} every `progress_every` epochs
    meta: dict  # mode, seed, ids, lexicon words, config, assemblies spec, seconds per stage
    csc: dict[str, np.ndarray] = field(default_factory=dict)  # learned training tables (c_0, c_T)

    @property
    def lexicon(self) -> Lexicon:
        return Lexicon(self.meta["lexicon"])


ModeFn = Callable[[SequenceSet, MultiMTRNNConfig, int, "ProgressFn | None"], TrainedModel]
MODES: dict[str, ModeFn] = {}
_PLUGIN_MODULES = ("model.training.end_to_end", "model.training.peer")


def register_mode(name: str, fn: ModeFn) -> None:
    """Make `train(data, mode=name)` call `fn(data, config, seed, progress) -> TrainedModel`."""
    MODES[name] = fn


def available_modes() -> list[str]:
    _load_plugins()
    return sorted(MODES)


def _load_plugins() -> None:
    for module in _PLUGIN_MODULES:
        importlib.import_module(module)


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
    p, p_len = pad_sequences(data.proprioception, config.somatosensory.io)
    v, v_len = pad_sequences(data.vision, config.visual.io)
    u, u_len = encode_utterances(data.utterances, config.generation_steps)
    return Batch(p, p_len, v, v_len, u, u_len)


# --- optimisers ---------------------------------------------------------------------------------


def make_optimiser(groups: list[dict], training: TrainingConfig) -> torch.optim.Optimizer:
    """RPROP (3.1.4) or Adam over parameter groups; a group's optional "scale" multiplies its
    rates (eq. 12: c_T's step is psi * zeta)."""
    out = []
    for g in groups:
        scale = g.get("scale", 1.0)
        params = [p for p in g["params"] if p.requires_grad]
        if not params:
            continue
        if training.optimiser == "rprop":
            out.append(
                {
                    "params": params,
                    "lr": training.lr * scale,
                    "step_sizes": (training.lr_min * scale, training.lr_max * scale),
                }
            )
        else:
            out.append({"params": params, "lr": training.adam_lr * scale})
    if training.optimiser == "rprop":
        return torch.optim.Rprop(
            out,
            lr=training.lr,
            etas=(training.xi_decrease, training.xi_increase),
            step_sizes=(training.lr_min, training.lr_max),
        )
    if training.optimiser == "adam":
        return torch.optim.Adam(out, lr=training.adam_lr)
    raise ValueError(f"unknown optimiser {training.optimiser!r} (rprop or adam)")


def _uniform(shape: tuple[int, ...], scale: float, generator: torch.Generator) -> Tensor:
    return (torch.rand(*shape, generator=generator) * 2 - 1) * scale


class ProgressReporter:
    """Collects history and calls `progress` every `every` epochs and at the last one."""

    def __init__(self, progress: ProgressFn | None, every: int, history: list[dict]) -> None:
        self.progress, self.every, self.history = progress, max(1, every), history

    def __call__(self, stage: str, epoch: int, epochs: int, loss: float, csc: Tensor | None = None) -> None:
        if epoch % self.every and epoch != epochs:
            return
        entry = {"stage": stage, "epoch": epoch, "epochs": epochs, "loss": loss}
        self.history.append(entry)
        if self.progress is not None:
            report = dict(entry)
            if csc is not None:
                report["csc"] = csc.detach().tolist()
            self.progress(report)


# --- the stages ---------------------------------------------------------------------------------


def train_auditory(
    net: MTRNN,
    targets: Tensor,
    training: TrainingConfig,
    generator: torch.Generator,
    report: ProgressReporter,
    epochs: int | None = None,
    report_rows: Tensor | None = None,
) -> nn.Parameter:
    """MTRNN_a with context bias: learn weights, biases and one c_0 per sequence (eqs. 5-9).

    `report_rows` (optional) picks the c_0 rows the progress reports show, e.g. one per recording
    when the sequences are the distinct utterances. Returns the learned c_0 table [B, csc]."""
    c0 = nn.Parameter(_uniform((targets.shape[0], net.cfg.csc), net.cfg.csc_init, generator))
    optimiser = make_optimiser([{"params": [*net.parameters(), c0]}], training)
    epochs = training.epochs_auditory if epochs is None else epochs
    for epoch in range(1, epochs + 1):
        optimiser.zero_grad()
        output = net.generate(c0, targets.shape[1], teacher=targets, alpha=training.alpha)
        loss = kl_divergence(targets, output)
        loss.backward()
        optimiser.step()
        report("auditory", epoch, epochs, loss.item(), c0 if report_rows is None else c0[report_rows])
    return c0


def train_encoder(
    net: MTRNN,
    inputs: Tensor,
    lengths: Tensor,
    psi: float,
    training: TrainingConfig,
    generator: torch.Generator,
    report: ProgressReporter,
    stage: str,
    epochs: int,
    groups: Tensor | None = None,
) -> nn.Parameter:
    """MTRNN with context abstraction: weights learn from (1 - psi) of the Csc error at the final
    step (eq. 11), the targets c_T (init +-1) move with a psi-scaled step (eq. 12).

    `groups` [B] (optional) makes sequences share a target: sequence k is pulled towards row
    groups[k] (`FaithfulOptions.perception_targets = "scene"`). Returns the c_T table [G, csc]
    (G = B without groups; unchanged when psi = 0)."""
    rows = inputs.shape[0] if groups is None else int(groups.max()) + 1
    c_t = nn.Parameter(_uniform((rows, net.cfg.csc), net.cfg.csc_init, generator), requires_grad=psi > 0)
    optimiser = make_optimiser(
        [{"params": list(net.parameters())}, {"params": [c_t], "scale": psi}], training
    )
    for epoch in range(1, epochs + 1):
        optimiser.zero_grad()
        targets = c_t if groups is None else c_t[groups]
        loss = context_abstraction_loss(net, net.abstract(inputs, lengths), targets, psi)
        loss.backward()
        optimiser.step()
        report(stage, epoch, epochs, loss.item(), targets)
    return c_t


def assemblies_loss(assemblies: nn.Module, c_s: Tensor, c_v: Tensor, c_a0: Tensor) -> Tensor:
    """LMS between y = f(z) and f(c_a,0) (eq. 16), z = the assemblies' output (eq. 17)."""
    y = scaled_logistic(assemblies(c_s, c_v))
    return 0.5 * ((y - scaled_logistic(c_a0)) ** 2).sum(dim=1).mean()


def fit_assemblies(
    assemblies: nn.Module,
    c_s: Tensor,
    c_v: Tensor,
    c_a0: Tensor,
    training: TrainingConfig,
    report: ProgressReporter,
    epochs: int | None = None,
) -> None:
    """Associate the Csc states of the three nets in the CAs (eqs. 16-17), full batch."""
    c_s, c_v, c_a0 = c_s.detach(), c_v.detach(), c_a0.detach()
    optimiser = make_optimiser([{"params": list(assemblies.parameters())}], training)
    epochs = training.epochs_assemblies if epochs is None else epochs
    for epoch in range(1, epochs + 1):
        optimiser.zero_grad()
        loss = assemblies_loss(assemblies, c_s, c_v, c_a0)
        loss.backward()
        optimiser.step()
        report("assemblies", epoch, epochs, loss.item())


def solve_assemblies(
    assemblies: nn.Module, c_s: Tensor, c_v: Tensor, c_a0: Tensor, iterations: int = 2000
) -> float:
    """`FaithfulOptions.assemblies_solver = "optimum"`: the minimum of eq. (16) itself, i.e. where
    the LMS rule converges, instead of a fixed number of RPROP epochs.

    eq. (17) is linear, so least squares of z onto c_a,0 (float64) gives a near-optimal start;
    L-BFGS then minimises eq. (16) (the error on f(z) vs f(c_a,0)) from there. Needs the paper's
    linear `CellAssemblies` (a `weight` [csc_a, csc_s + csc_v] and a `bias`). Returns the LMS
    error of the solution."""
    c_s, c_v, c_a0 = c_s.detach().double(), c_v.detach().double(), c_a0.detach().double()
    x = torch.cat([scaled_logistic(c_s), scaled_logistic(c_v), torch.ones(len(c_s), 1).double()], dim=1)
    start = torch.linalg.lstsq(x, c_a0).solution  # z = x @ start
    weight = start[:-1].T.clone().requires_grad_()
    bias = start[-1].clone().requires_grad_()

    def lms() -> Tensor:  # eq. (16) with eq. (17)'s z
        y = scaled_logistic(x[:, :-1] @ weight.T + bias)
        return 0.5 * ((y - scaled_logistic(c_a0)) ** 2).sum(dim=1).mean()

    optimiser = torch.optim.LBFGS(
        [weight, bias],
        max_iter=iterations,
        tolerance_grad=1e-10,
        tolerance_change=1e-14,
        history_size=50,
        line_search_fn="strong_wolfe",
    )

    def closure() -> Tensor:
        optimiser.zero_grad()
        loss = lms()
        loss.backward()
        return loss

    optimiser.step(closure)
    with torch.no_grad():
        assemblies.weight.copy_(weight)
        assemblies.bias.copy_(bias)
    return assemblies_loss(assemblies, c_s.float(), c_v.float(), c_a0.float()).item()


@dataclass
class FaithfulOptions:
    """Departures from the paper's reading in `faithful` (docs/experiments/faithful.md); the
    defaults are the paper. Recorded in the checkpoint meta under "faithful"."""

    # One learnable c_T per training recording (3.2.1, 3.4.3: per sequence) or one per scene,
    # shared by the scene's recordings (its utterance names the scene: the grammar is unambiguous).
    perception_targets: Literal["recording", "scene"] = "recording"
    # eq. (16) descended by the RPROP variant for `epochs_assemblies`, or minimised to convergence.
    assemblies_solver: Literal["lms", "optimum"] = "lms"


def distinct_rows(utterances: Sequence[str]) -> tuple[list[str], Tensor]:
    """The distinct utterances in first-seen order and, per recording, the row of its utterance."""
    distinct = list(dict.fromkeys(utterances))
    row = {u: i for i, u in enumerate(distinct)}
    return distinct, torch.tensor([row[u] for u in utterances])


def prepare(data: SequenceSet, config: MultiMTRNNConfig | None) -> MultiMTRNNConfig:
    """A copy of `config` (default: Table 1) with T_a set from the training utterances."""
    if len(data) == 0:
        raise ValueError("cannot train on an empty SequenceSet")
    config = MultiMTRNNConfig.from_dict((config or MultiMTRNNConfig()).to_dict())
    config.generation_steps = generation_steps(data.utterances)
    return config


def base_meta(data: SequenceSet, config: MultiMTRNNConfig, model: MultiMTRNN, mode: str, seed: int) -> dict:
    """The meta every mode records (see `model.checkpoint`)."""
    return {
        "mode": mode,
        "seed": seed,
        "ids": list(data.ids),
        "lexicon": list(Lexicon.from_sentences(data.utterances).words),
        "generation_steps": config.generation_steps,
        "config": config.to_dict(),
        "assemblies": model.assemblies_spec(),
    }


def train_faithful(
    data: SequenceSet,
    config: MultiMTRNNConfig,
    seed: int,
    progress: ProgressFn | None = None,
    options: FaithfulOptions | None = None,
) -> TrainedModel:
    """The paper's staged recipe (module docstring)."""
    options = options or mode_options(FaithfulOptions, config)
    if options.perception_targets not in ("recording", "scene"):
        raise ValueError(f"unknown perception_targets {options.perception_targets!r}")
    if options.assemblies_solver not in ("lms", "optimum"):
        raise ValueError(f"unknown assemblies_solver {options.assemblies_solver!r}")
    training = config.training
    model = MultiMTRNN(config, seed=seed)
    batch = make_batch(data, config)
    sentences, sentence_of = distinct_rows(data.utterances)
    history: list[dict] = []
    report = ProgressReporter(progress, training.progress_every, history)
    seconds: dict[str, float] = {}

    start = time.perf_counter()
    # 3.3: one c_a,0 per sentence; its targets are the distinct utterances' encodings
    c_sentence = train_auditory(
        model.auditory,
        encode_utterances(sentences, config.generation_steps)[0],
        training,
        torch.Generator().manual_seed(seed + 1),
        report,
        report_rows=sentence_of,
    )
    c_a0 = c_sentence.detach()[sentence_of]  # each recording: its sentence's c_a,0
    seconds["auditory"] = time.perf_counter() - start

    groups = sentence_of if options.perception_targets == "scene" else None
    targets = {}
    for stage, net, inputs, lengths, psi, epochs, offset in (
        (
            "somatosensory",
            model.somatosensory,
            batch.proprioception,
            batch.proprioception_lengths,
            training.psi_s,
            training.epochs_somatosensory,
            2,
        ),
        (
            "visual",
            model.visual,
            batch.vision,
            batch.vision_lengths,
            training.psi_v,
            training.epochs_visual,
            3,
        ),
    ):
        start = time.perf_counter()
        table = train_encoder(
            net,
            inputs,
            lengths,
            psi,
            training,
            torch.Generator().manual_seed(seed + offset),
            report,
            stage,
            epochs,
            groups,
        )
        targets[stage] = table.detach() if groups is None else table.detach()[groups]
        seconds[stage] = time.perf_counter() - start

    start = time.perf_counter()
    with torch.no_grad():
        c_s, c_v = model.abstract(
            batch.proprioception, batch.vision, batch.proprioception_lengths, batch.vision_lengths
        )
    if options.assemblies_solver == "optimum":
        loss = solve_assemblies(model.assemblies, c_s, c_v, c_a0)
        report("assemblies", 1, 1, loss)
    else:
        fit_assemblies(model.assemblies, c_s, c_v, c_a0, training, report)
    seconds["assemblies"] = time.perf_counter() - start

    meta = base_meta(data, config, model, "faithful", seed)
    meta["seconds"] = seconds
    meta["faithful"] = asdict(options)
    csc = {  # one row per training recording (meta["ids"])
        "auditory_c0": c_a0.numpy().copy(),
        "somatosensory_cT": targets["somatosensory"].numpy().copy(),
        "visual_cT": targets["visual"].numpy().copy(),
    }
    model.eval()
    return TrainedModel(model, history, meta, csc)


register_mode("faithful", train_faithful)


def train(
    data: SequenceSet,
    mode: str = "faithful",
    config: MultiMTRNNConfig | None = None,
    seed: int = 0,
    progress: ProgressFn | None = None,
) -> TrainedModel:
    """Train a MultiMTRNN on `data` with the named mode; deterministic for a given seed."""
    _load_plugins()
    if mode not in MODES:
        raise ValueError(f"unknown training mode {mode!r}; available: {sorted(MODES)}")
    config = prepare(data, config)
    threads = torch.get_num_threads()
    torch.set_num_threads(config.training.threads)
    torch.manual_seed(seed)
    np.random.seed(seed % 2**32)
    try:
        start = time.perf_counter()
        result = MODES[mode](data, config, seed, progress)
        result.meta.setdefault("seconds_total", time.perf_counter() - start)
        log.info(
            "trained %s (seed %d) on %d sequences in %.1f s",
            mode,
            seed,
            len(data),
            time.perf_counter() - start,
        )
        return result
    finally:
        torch.set_num_threads(threads)
