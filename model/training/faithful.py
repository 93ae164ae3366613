"""Training mode `faithful`: the paper's staged recipe (3.1.3-3.1.4, 3.2.1, 3.4.3); our readings of what the
paper leaves open are in docs/experiments/faithful.md:
1. MTRNN_a with a learnable c_0 per training *sentence* (3.3: the Csc "had to be trained
   individually for every sentence"; a scene's four recordings share one utterance, hence one
   c_a,0), init +-0.01, teacher forcing alpha = 0.1 (eq. 5), KLD on the softmax IO, full-batch
   BPTT, every element learning by its adapted rate times its gradient (eqs. 7-9), c_0's rate
   zeta following the weights' (eq. 10, `model.training.adaptive_rates`).
2. MTRNN_s and MTRNN_v with a learnable c_T per training recording (init +-1) and self-organisation
   forcing psi (eqs. 11-12): the weights learn from (1 - psi) of the Csc error, c_T steps by
   psi * zeta times its gradient; psi = 0 leaves c_T fixed.
3. The cell assemblies fitted by LMS (eqs. 16-17) from the encoders' abstraction c_s,T, c_v,T of
   each training recording (what the CAs will see when describing a scene; the learned targets
   c_T are only what the encoders were pulled towards) to the learned c_a,0 of its utterance, by
   the same rule.

Every stage sums its error over the time steps of a sequence (eqs. 7-8) and averages it over the
sequences (summed, MTRNN_a diverges: docs/experiments/faithful.md). `TrainingConfig.optimiser` =
"rprop" (sign-based RPROP) or "adam" are named alternatives, and `FaithfulOptions` names the other
departures from that reading (all off by default).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from typing import Literal

import torch
from torch import Tensor, nn

from model.config import MultiMTRNNConfig, TrainingConfig, mode_options
from model.data import SequenceSet
from model.mtrnn import MTRNN, context_abstraction_loss, kl_divergence, scaled_logistic
from model.multimtrnn import MultiMTRNN
from model.training.common import (
    Batch,
    MultiMTRNNMode,
    ProgressFn,
    ProgressReporter,
    TrainedModel,
    base_meta,
    encode_utterances,
    make_batch,
    make_optimiser,
    prepare,
    torch_threads,
    uniform,
)


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
    c0 = nn.Parameter(uniform((targets.shape[0], net.cfg.csc), net.cfg.csc_init, generator))
    optimiser = make_optimiser(
        [{"params": list(net.parameters())}, {"params": [c0], "context_of": net}], training
    )
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
    c_t = nn.Parameter(uniform((rows, net.cfg.csc), net.cfg.csc_init, generator), requires_grad=psi > 0)
    optimiser = make_optimiser(
        [{"params": list(net.parameters())}, {"params": [c_t], "scale": psi, "context_of": net}], training
    )
    for epoch in range(1, epochs + 1):
        optimiser.zero_grad()
        targets = c_t if groups is None else c_t[groups]
        produced = net.abstract(inputs, lengths)
        loss = context_abstraction_loss(net, produced, targets, psi)
        loss.backward()
        optimiser.step()
        report(stage, epoch, epochs, loss.item(), targets)
    return c_t


def assemblies_loss(assemblies: nn.Module, c_s: Tensor, c_v: Tensor, c_a0: Tensor) -> Tensor:
    """LMS between y = f(z) and f(c_a,0) (eq. 16), z = the assemblies' output (eq. 17), averaged
    over recordings."""
    y = scaled_logistic(assemblies(c_s, c_v))
    return (0.5 * ((y - scaled_logistic(c_a0)) ** 2).sum(dim=1)).mean()


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


def _check(options: FaithfulOptions) -> None:
    if options.perception_targets not in ("recording", "scene"):
        raise ValueError(f"unknown perception_targets {options.perception_targets!r}")
    if options.assemblies_solver not in ("lms", "optimum"):
        raise ValueError(f"unknown assemblies_solver {options.assemblies_solver!r}")


def _staged(
    data: SequenceSet,
    config: MultiMTRNNConfig,
    seed: int,
    progress: ProgressFn | None,
    options: FaithfulOptions,
) -> TrainedModel:
    """The paper's staged recipe (module docstring)."""
    _check(options)
    return _Staged(data, config, seed, progress).run(options)


train_faithful = MultiMTRNNMode(_staged, FaithfulOptions)

# what only the later stages read: configs that differ in these alone share stage 1 (MTRNN_a)
LATER_STAGES = ("psi_s", "psi_v", "epochs_somatosensory", "epochs_visual", "epochs_assemblies")


def _stage_one(config: MultiMTRNNConfig) -> str:
    training = replace(config.training, **{name: 0 for name in LATER_STAGES})
    return repr(replace(config, training=training, options={}).to_dict())


def train_faithful_variants(
    data: SequenceSet,
    configs: Sequence[MultiMTRNNConfig | dict | None],
    seed: int,
    progress: ProgressFn | None = None,
) -> list[TrainedModel]:
    """Faithful trainings of one seed whose configs differ only in what the later stages read
    (`LATER_STAGES`: psi_s, psi_v and the encoders' and assemblies' budgets, as in the psi_s sweep,
    Fig. 9) and in `FaithfulOptions`: MTRNN_a learns once and every variant starts its encoders from
    it. Each result is what `train_faithful(data, config, seed)` gives (the nets start from the
    same seed); its meta["seconds"]["auditory"] is the shared stage's time."""
    prepared = [prepare(data, config) for config in configs]
    if len({_stage_one(config) for config in prepared}) > 1:
        raise ValueError(f"variants may differ only in {LATER_STAGES} and the faithful options")
    shared: tuple[dict, Tensor, float] | None = None
    results = []
    for config in prepared:
        options = mode_options(FaithfulOptions, config)
        _check(options)
        with torch_threads(config.training.threads):
            staged = _Staged(data, config, seed, progress)
            if shared is None:
                c_a0 = staged.auditory()
                shared = (staged.model.auditory.state_dict(), c_a0, staged.seconds["auditory"])
            else:
                staged.model.auditory.load_state_dict(shared[0])
                staged.seconds["auditory"] = shared[2]
            results.append(staged.run(options, shared[1]))
    return results


class _Staged:
    """One faithful training: the model, its batch and the stages' shared bookkeeping."""

    def __init__(self, data: SequenceSet, config: MultiMTRNNConfig, seed: int, progress: ProgressFn | None):
        config.training = replace(config.training, optimiser=config.training.optimiser or "paper")
        self.data, self.config, self.seed = data, config, seed
        self.training = config.training
        self.model = MultiMTRNN(config, seed=seed)
        self.batch: Batch = make_batch(data, config)
        self.sentences, self.sentence_of = distinct_rows(data.utterances)
        self.history: list[dict] = []
        self.report = ProgressReporter(progress, self.training.progress_every, self.history)
        self.seconds: dict[str, float] = {}

    def run(self, options: FaithfulOptions, c_a0: Tensor | None = None) -> TrainedModel:
        """The three stages; with `c_a0` (each recording's) MTRNN_a is taken as already trained."""
        c_a0 = self.auditory() if c_a0 is None else c_a0
        groups = self.sentence_of if options.perception_targets == "scene" else None
        targets = {stage: self.encoder(stage, groups) for stage in ("somatosensory", "visual")}
        self.assemblies(c_a0, options.assemblies_solver)
        meta = base_meta(self.data, self.config, self.model, "faithful", self.seed)
        meta["seconds"] = self.seconds
        meta["faithful"] = asdict(options)
        csc = {  # one row per training recording (meta["ids"])
            "auditory_c0": c_a0.numpy().copy(),
            "somatosensory_cT": targets["somatosensory"].numpy().copy(),
            "visual_cT": targets["visual"].numpy().copy(),
        }
        self.model.eval()
        return TrainedModel(self.model, self.history, meta, csc)

    def auditory(self) -> Tensor:
        """3.3: one c_a,0 per sentence, its targets the distinct utterances' encodings; returns
        each recording's c_a,0 (its sentence's)."""
        start = time.perf_counter()
        c_sentence = train_auditory(
            self.model.auditory,
            encode_utterances(self.sentences, self.config.generation_steps)[0],
            self.training,
            torch.Generator().manual_seed(self.seed + 1),
            self.report,
            report_rows=self.sentence_of,
        )
        self.seconds["auditory"] = time.perf_counter() - start
        return c_sentence.detach()[self.sentence_of]

    def encoder(self, stage: str, groups: Tensor | None) -> Tensor:
        """MTRNN_s or MTRNN_v (eqs. 11-12); returns each recording's learned c_T."""
        start = time.perf_counter()
        somatosensory = stage == "somatosensory"
        b, t = self.batch, self.training
        table = train_encoder(
            self.model.somatosensory if somatosensory else self.model.visual,
            b.proprioception if somatosensory else b.vision,
            b.proprioception_lengths if somatosensory else b.vision_lengths,
            t.psi_s if somatosensory else t.psi_v,
            t,
            torch.Generator().manual_seed(self.seed + (2 if somatosensory else 3)),
            self.report,
            stage,
            t.epochs_somatosensory if somatosensory else t.epochs_visual,
            groups,
        )
        self.seconds[stage] = time.perf_counter() - start
        return table.detach() if groups is None else table.detach()[groups]

    def assemblies(self, c_a0: Tensor, solver: str) -> None:
        """The CAs from the encoders' abstraction to each recording's c_a,0 (eqs. 16-17)."""
        start = time.perf_counter()
        b = self.batch
        with torch.no_grad():
            c_s, c_v = self.model.abstract(
                b.proprioception, b.vision, b.proprioception_lengths, b.vision_lengths
            )
        if solver == "optimum":
            loss = solve_assemblies(self.model.assemblies, c_s, c_v, c_a0)
            self.report("assemblies", 1, 1, loss)
        else:
            fit_assemblies(self.model.assemblies, c_s, c_v, c_a0, self.training, self.report)
        self.seconds["assemblies"] = time.perf_counter() - start
