"""Peer baseline (`--mode peer`): a GRU encoder-decoder in the style of paired recurrent autoencoders.

Paired recurrent autoencoders (Yamada et al. 2018, "Paired recurrent autoencoders for
bidirectional translation between robot actions and linguistic descriptions") learn one
autoencoder per modality and bind their latent codes. Here, to describe scenes exactly as the
MultiMTRNN does (same inputs, same outputs, same folds, same metrics):

    proprioception [T, 5]  -> GRU -> code_s [12]  \\
                                                    -> fusion -> z [12] -> GRU decoder -> phonemes
    vision [T, 19]         -> GRU -> code_v [12]  /                 ^
    utterance [T_a, 44]    -> GRU -> code_l [12] --(binding)--------/  (language autoencoder)

Loss = KLD(decoder(z), utterance) (describe) + KLD(decoder(code_l), utterance) (reconstruct)
     + binding * |z - code_l|^2 (PRAE's binding of the two latent spaces).

The decoder produces the same softmax phoneme activity as MTRNN_a and runs closed-loop when it
describes; the code is fed to it at every step. While training, its input is alpha * the target of
the previous step + (1 - alpha) * its own previous output (eq. 5's mixing). code_s, code_v and z
play the roles of c_s,T, c_v,T and c_a,0, so the Csc measures and PCA panels apply unchanged.

Training (`PeerConfig` defaults; the comparisons were measured on the shipped corpus, fold 0):
- alpha = 0, trained closed-loop as it describes. With teacher forcing (alpha = 1) the decoder
  fitted the teacher-forced loss (78 % of training sentences exact when fed the targets) but
  described 0 % closed-loop (KL 3.7 teacher-forced vs 45 closed-loop): it had learned to copy
  its input, and the scene codes collapsed (std 0.05 across scenes).
- Minibatches of 32 recordings: 4 Adam steps per epoch instead of 1; full-batch closed-loop
  training had only halved the describe loss (53 -> 26) in 150 epochs.
- lr 5e-3 falling to 0 along a half cosine, gradient norm clipped at 1: lr 1e-2 learned
  faster but the closed loop blew up (loss 9 -> 106 within 10 epochs).
- Inputs standardised by the training set's feature mean and std (fitted in `train_peer`, kept as
  buffers in the checkpoint): colour and shape live in a few visual features whose raw range
  across scenes is ~0.03-0.25.
- The encoders read every 2nd step (60-120 -> 30-60 steps; the scenes change slowly), which
  halves their cost: 300 epochs take 80-105 s of one core. Every 4th step was cheaper (~77 s)
  but left the action of some training scenes wrong (train exact 0.90 vs 0.97 over 8 runs).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import torch
from torch import Tensor, nn

from model.data import SequenceSet
from model.encoding.utterance import PHONEMES, Lexicon, decode_text
from model.multimtrnn import Description, pad_sequences
from model.training.common import (
    ProgressFn,
    TrainedModel,
    encode_utterances,
    generation_steps,
    torch_threads,
)

# Training options of checkpoints saved before they existed: full-batch, constant lr, no clipping,
# raw inputs at every step.
LEGACY = {"batch": 0, "cosine": False, "clip": 0.0, "stride": 1, "normalise": False}


@dataclass
class PeerConfig:
    """Sizes and training of the peer baseline."""

    hidden: int = 64  # GRU units of every encoder and of the decoder
    code: int = 12  # latent code size, as |Csc| of the MultiMTRNN
    proprioception: int = 5
    vision: int = 19  # the paper's 19 visual features (the centroid is left out, as for MTRNN_v)
    phonemes: int = len(PHONEMES)
    alpha: float = 0.0  # teacher forcing of the decoder input in training (eq. 5; 0 = closed loop)
    binding: float = 1.0  # weight of |z - code_l|^2
    lr: float = 5e-3  # Adam
    batch: int = 32  # recordings per Adam step (0 = the whole training set)
    cosine: bool = True  # the learning rate falls from lr to 0 along a half cosine over the epochs
    clip: float = 1.0  # max gradient norm (0 = no clipping)
    stride: int = 2  # the encoders read every stride-th step of proprioception and vision
    normalise: bool = True  # standardise every input feature by the training set's mean and std
    epochs: int = 300
    margin: int = 10  # silent steps after the longest training utterance (as the MultiMTRNN modes)
    progress_every: int = 10

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> PeerConfig:
        return cls(**d)


class SequenceEncoder(nn.Module):
    """GRU over a padded batch; the code is tanh(W h_T) of each sequence's last valid step."""

    def __init__(self, inputs: int, hidden: int, code: int) -> None:
        super().__init__()
        self.gru = nn.GRU(inputs, hidden, batch_first=True)
        self.out = nn.Linear(hidden, code)
        self.register_buffer("mean", torch.zeros(inputs))  # input standardisation (identity until fitted)
        self.register_buffer("std", torch.ones(inputs))

    def fit_normalisation(self, x: Tensor, lengths: Tensor) -> None:
        """Mean and std of every feature over the valid steps of a padded batch."""
        valid = torch.cat([x[i, : int(n)] for i, n in enumerate(lengths)])
        self.mean.copy_(valid.mean(dim=0))
        self.std.copy_(valid.std(dim=0).clamp_min(1e-3))

    def forward(self, x: Tensor, lengths: Tensor) -> Tensor:
        states, _ = self.gru((x - self.mean) / self.std)
        last = states[torch.arange(x.shape[0]), lengths.long() - 1]
        return torch.tanh(self.out(last))


class PhonemeDecoder(nn.Module):
    """GRU cell from a code to softmax phoneme activity [B, T_a, |B|], closed-loop: at every step it
    reads the code and its own previous output."""

    def __init__(self, code: int, hidden: int, phonemes: int) -> None:
        super().__init__()
        self.init = nn.Linear(code, hidden)
        self.cell = nn.GRUCell(phonemes + code, hidden)  # the code is fed at every step
        self.out = nn.Linear(hidden, phonemes)
        self.phonemes = phonemes

    def forward(self, code: Tensor, steps: int, teacher: Tensor | None = None, alpha: float = 0.0) -> Tensor:
        h = torch.tanh(self.init(code))
        y = torch.softmax(self.out(h), dim=-1)
        outputs = [y]
        for t in range(1, steps):
            # eq. (5): alpha * the previous target + (1 - alpha) * the previous output
            x = y if teacher is None or alpha == 0.0 else alpha * teacher[:, t - 1] + (1.0 - alpha) * y
            h = self.cell(torch.cat([x, code], dim=-1), h)
            y = torch.softmax(self.out(h), dim=-1)
            outputs.append(y)
        return torch.stack(outputs, dim=1)


class PeerModel(nn.Module):
    """Encoders, fusion, language encoder and decoder; `describe_batch` as the MultiMTRNN's."""

    def __init__(self, config: PeerConfig, generation_steps: int, seed: int = 0) -> None:
        super().__init__()
        c = config
        self.config, self.generation_steps = config, generation_steps
        with torch.random.fork_rng():  # seeded initialisation without touching the global generator
            torch.manual_seed(seed)
            self.somatosensory = SequenceEncoder(c.proprioception, c.hidden, c.code)
            self.visual = SequenceEncoder(c.vision, c.hidden, c.code)
            self.fusion = nn.Linear(2 * c.code, c.code)
            self.language = SequenceEncoder(c.phonemes, c.hidden, c.code)
            self.decoder = PhonemeDecoder(c.code, c.hidden, c.phonemes)

    def perceive(
        self, prop: Tensor, prop_len: Tensor, vis: Tensor, vis_len: Tensor
    ) -> tuple[Tensor, Tensor, Tensor]:
        k = self.config.stride
        prop_len, vis_len = (prop_len + k - 1) // k, (vis_len + k - 1) // k
        code_s = self.somatosensory(prop[:, ::k], prop_len)
        code_v = self.visual(vis[:, ::k], vis_len)
        return code_s, code_v, torch.tanh(self.fusion(torch.cat([code_s, code_v], dim=-1)))

    @torch.no_grad()
    def describe_batch(
        self, proprioception: Sequence[np.ndarray], vision: Sequence[np.ndarray], lexicon: Lexicon
    ) -> list[Description]:
        prop, prop_len = pad_sequences(proprioception, self.config.proprioception)
        vis, vis_len = pad_sequences(vision, self.config.vision)
        code_s, code_v, z = self.perceive(prop, prop_len, vis, vis_len)
        activity = self.decoder(z, self.generation_steps).numpy()
        out = []
        for i in range(len(activity)):
            phonemes, words, text = decode_text(activity[i], lexicon)
            out.append(
                Description(
                    text, words, phonemes, activity[i], code_s[i].numpy(), code_v[i].numpy(), z[i].numpy()
                )
            )
        return out

    def describe(self, proprioception: np.ndarray, vision: np.ndarray, lexicon: Lexicon) -> Description:
        return self.describe_batch([proprioception], [vision], lexicon)[0]


def _kld(target: Tensor, output: Tensor, eps: float = 1e-8) -> Tensor:
    """KL divergence of softmax activity, summed over units and steps t >= 1, mean over sequences
    (the loss of MTRNN_a, `model.mtrnn.kl_divergence`)."""
    t, o = target[:, 1:], output[:, 1:]
    return (t * (torch.log(t + eps) - torch.log(o + eps))).sum(dim=(1, 2)).mean()


def peer_config(config: PeerConfig | dict | None) -> PeerConfig:
    """The peer's own config: a `PeerConfig` or its dict; anything else (None, or a MultiMTRNN's
    config handed to every mode alike) means `PeerConfig`'s defaults."""
    if isinstance(config, dict):
        return PeerConfig.from_dict(config)
    return config if isinstance(config, PeerConfig) else PeerConfig()


def train_peer(
    data: SequenceSet,
    config: PeerConfig | dict | None = None,
    seed: int = 0,
    progress: ProgressFn | None = None,
) -> TrainedModel:
    """Minibatch Adam on describe + reconstruct + binding (module docstring); deterministic for a seed."""
    with torch_threads(1):  # one run per core (as the MultiMTRNN modes)
        return _Training(data, peer_config(config), seed).run(progress)


class _Training:
    """One peer training: the model, its padded inputs and targets, the optimiser."""

    def __init__(self, data: SequenceSet, config: PeerConfig, seed: int) -> None:
        self.data, self.config, self.seed = data, config, seed
        self.steps = generation_steps(data.utterances, config.margin)
        self.model = PeerModel(config, self.steps, seed)
        self.prop, self.prop_len = pad_sequences(data.proprioception, config.proprioception)
        self.vis, self.vis_len = pad_sequences(data.vision, config.vision)
        self.target, self.target_len = encode_utterances(data.utterances, self.steps)
        if config.normalise:
            self.model.somatosensory.fit_normalisation(self.prop, self.prop_len)
            self.model.visual.fit_normalisation(self.vis, self.vis_len)
        self.optimiser = torch.optim.Adam(self.model.parameters(), lr=config.lr)

    def run(self, progress: ProgressFn | None) -> TrainedModel:
        config, model = self.config, self.model
        schedule = (
            torch.optim.lr_scheduler.CosineAnnealingLR(self.optimiser, config.epochs)
            if config.cosine
            else None
        )
        shuffle = torch.Generator().manual_seed(self.seed)  # minibatch order, deterministic for a seed
        history: list[dict] = []
        started = time.perf_counter()
        for epoch in range(1, config.epochs + 1):
            totals = self.epoch(shuffle)
            if schedule is not None:
                schedule.step()
            if epoch % max(1, config.progress_every) == 0 or epoch == config.epochs:
                history.append(self.report(epoch, totals, progress))
        model.eval()
        meta = {
            "mode": "peer",
            "seed": self.seed,
            "ids": list(self.data.ids),
            "lexicon": list(Lexicon.from_sentences(self.data.utterances).words),
            "generation_steps": self.steps,
            "peer_config": config.to_dict(),
            "seconds_total": time.perf_counter() - started,
        }
        return TrainedModel(model, history, meta)

    def epoch(self, shuffle: torch.Generator) -> Tensor:
        """One pass over the minibatches; the sums of (loss, describe, binding) over recordings."""
        config, model, steps = self.config, self.model, self.steps
        size = config.batch if config.batch > 0 else len(self.data)
        totals = torch.zeros(3)
        for batch in torch.randperm(len(self.data), generator=shuffle).split(size):
            self.optimiser.zero_grad()
            _, _, z = model.perceive(
                self.prop[batch], self.prop_len[batch], self.vis[batch], self.vis_len[batch]
            )
            code_l = model.language(self.target[batch], self.target_len[batch])
            tgt = self.target[batch]
            both = model.decoder(torch.cat([z, code_l]), steps, torch.cat([tgt, tgt]), config.alpha)
            describe, reconstruct = _kld(tgt, both[: len(z)]), _kld(tgt, both[len(z) :])
            binding = ((z - code_l) ** 2).sum(dim=1).mean()
            loss = describe + reconstruct + config.binding * binding
            loss.backward()
            if config.clip > 0:
                nn.utils.clip_grad_norm_(model.parameters(), config.clip)
            self.optimiser.step()
            totals += len(batch) * torch.stack([loss, describe, binding]).detach()
        return totals

    def report(self, epoch: int, totals: Tensor, progress: ProgressFn | None) -> dict:
        """The history entry of `epoch`; `progress` also gets the fused codes z of every recording."""
        loss_mean, describe_mean, binding_mean = (totals / len(self.data)).tolist()
        entry = {
            "stage": "peer",
            "epoch": epoch,
            "epochs": self.config.epochs,
            "loss": loss_mean,
            "describe": describe_mean,
            "binding": binding_mean,
        }
        if progress is not None:
            with torch.no_grad():
                _, _, z = self.model.perceive(self.prop, self.prop_len, self.vis, self.vis_len)
            progress({**entry, "csc": z.tolist()})
        return entry
