"""What the perception stage reads and how it varies it: standardised inputs (`InputNormaliser`,
folded into the encoders afterwards), the reading points of each sequence, and `PerceptionBatch`
with its augmentations (input noise, another teacher's tempo, vision windows)."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import torch
from torch import Tensor

from model.mtrnn import MTRNN


@dataclass
class InputNormaliser:
    """Per-input standardisation x' = (x - mean) / std from the training recordings.

    RPROP steps are sign-based, so an input that varies little (a shape distance) would otherwise
    need many epochs before it moves the encoder. The map is affine, so after training it is
    folded into the encoder's input weights and biases (`fold_into`): the trained MTRNN reads the
    raw features like any other and `MultiMTRNN.describe` needs nothing extra.
    """

    mean: Tensor  # [io]
    std: Tensor  # [io]

    @classmethod
    def fit(cls, inputs: Tensor, lengths: Tensor) -> InputNormaliser:
        valid = torch.arange(inputs.shape[1])[None, :] < lengths[:, None]
        steps = inputs[valid]
        return cls(steps.mean(dim=0), steps.std(dim=0).clamp(min=1e-3))

    def __call__(self, inputs: Tensor) -> Tensor:
        return (inputs - self.mean) / self.std

    @torch.no_grad()
    def fold_into(self, net: MTRNN) -> None:
        """W x' + b = (W / std) x + (b - W mean / std), for every unit the inputs reach (eq. 3)."""
        io = net.cfg.io
        w_in = net.masked_weight()[:, :io]
        net.bias -= w_in @ (self.mean / self.std)
        net.weight[:, :io] /= self.std


def reading_points(lengths: Tensor, points: int, start: float) -> Tensor:
    """Step indices [B, points], evenly from `start` of each sequence's length to its last step."""
    fractions = torch.linspace(start, 1.0, points) if points > 1 else torch.ones(1)
    steps = torch.ceil(fractions[None, :] * lengths[:, None].float()).long() - 1
    return steps.clamp(min=0)


def csc_at(net: MTRNN, inputs: Tensor, lengths: Tensor, steps: Tensor) -> Tensor:
    """Csc internal states of `net` reading `inputs` at `steps` [B, P] -> [B, P, csc]."""
    _, trajectory = net.abstract(inputs, lengths, return_states=True)
    rows = torch.arange(inputs.shape[0])[:, None]
    return trajectory[rows, steps][..., net.csc_slice]


@dataclass
class PerceptionBatch:
    """What the perception stage reads: padded (normalised) inputs and the heard words."""

    proprioception: Tensor
    proprioception_lengths: Tensor
    vision: Tensor
    vision_lengths: Tensor
    heard: Tensor  # p* [B, words]

    def subset(self, idx: list[int]) -> PerceptionBatch:
        return PerceptionBatch(*(getattr(self, f.name)[idx] for f in fields(self)))

    def with_noise(self, std: float, generator: torch.Generator) -> PerceptionBatch:
        """The same recordings with Gaussian noise of `std` on every input."""

        def noisy(x: Tensor) -> Tensor:
            return x + std * torch.randn(x.shape, generator=generator)

        return replace(self, proprioception=noisy(self.proprioception), vision=noisy(self.vision))

    def time_warped(self, warp: float, generator: torch.Generator) -> PerceptionBatch:
        """Each recording (both senses) replayed at its own random speed in [1 - warp, 1 + warp],
        by linear interpolation between steps: the tempo of another teacher."""
        speed = 1 + warp * (2 * torch.rand(len(self.heard), generator=generator) - 1)

        def replay(x: Tensor, lengths: Tensor) -> tuple[Tensor, Tensor]:
            new_lengths = (lengths / speed).round().long().clamp(min=2)
            last = (lengths - 1)[:, None].float()
            at = torch.arange(int(new_lengths.max()))[None, :] * last / (new_lengths - 1)[:, None]
            at = torch.minimum(at, last)
            before = at.floor().long()
            after = torch.minimum(before + 1, last.long())
            share = (at - before)[..., None]
            rows = torch.arange(len(x))[:, None]
            out = x[rows, before] * (1 - share) + x[rows, after] * share
            padding = torch.arange(out.shape[1])[None, :] >= new_lengths[:, None]
            return out.masked_fill(padding[..., None], 0.0), new_lengths

        proprioception, proprioception_lengths = replay(self.proprioception, self.proprioception_lengths)
        vision, vision_lengths = replay(self.vision, self.vision_lengths)
        return replace(
            self,
            proprioception=proprioception,
            proprioception_lengths=proprioception_lengths,
            vision=vision,
            vision_lengths=vision_lengths,
        )

    def vision_windows(self, width: int, generator: torch.Generator) -> PerceptionBatch:
        """Each recording's vision cut to a random window of `width` frames (whole if shorter)."""
        lengths = self.vision_lengths.clamp(max=width)
        room = (self.vision_lengths - lengths + 1).float()
        starts = (torch.rand(len(lengths), generator=generator) * room).long()
        steps = (starts[:, None] + torch.arange(int(lengths.max()))[None, :]).clamp(
            max=self.vision.shape[1] - 1
        )
        rows = torch.arange(len(lengths))[:, None]
        return replace(self, vision=self.vision[rows, steps], vision_lengths=lengths)
