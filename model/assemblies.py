"""The cell assemblies (CAs) between perception and MTRNN_a (3.4, eqs. 16-17).

Assemblies are `nn.Module`s with `forward(c_s [B, csc_s], c_v [B, csc_v]) -> c_a0 [B, csc_a]`,
JSON keyword arguments exposed as `init_kwargs()`, and a `kind` name: `ASSEMBLIES` maps every
kind to its class, so a checkpoint (`model.checkpoint`) rebuilds them from
{"kind", "kwargs"} (`MultiMTRNN.assemblies_spec`).

- `CellAssemblies` ("linear"): the paper's, one linear layer fitted by LMS (`faithful`).
- `WordAssemblies` ("words"): a layer of word units, trained through the auditory loss
  (`end_to_end`, model/training/end_to_end/).
"""

from __future__ import annotations

import copy

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from model.mtrnn import scaled_logistic


class CellAssemblies(nn.Module):
    """The paper's CAs (eqs. 16-17): one linear layer from f(c_s,T), f(c_v,T) to z.

    eq. (17): z_i = sum_j w_ij f(c_s,T,j) + sum_k w_ik f(c_v,T,k) + b_i for i in I_a,Csc.
    eq. (16): trained by LMS between y = f(z) and f(c_a,0) (see `model.training.faithful.fit_assemblies`).
    The CAs' internal state z is the c_a,0 that starts MTRNN_a's generation.
    """

    kind = "linear"

    def __init__(self, csc_s: int, csc_v: int, csc_a: int, weight_init: float = 0.025, seed: int = 0) -> None:
        super().__init__()
        self._kwargs = {
            "csc_s": csc_s,
            "csc_v": csc_v,
            "csc_a": csc_a,
            "weight_init": weight_init,
            "seed": seed,
        }
        g = torch.Generator().manual_seed(seed)
        self.weight = nn.Parameter((torch.rand(csc_a, csc_s + csc_v, generator=g) * 2 - 1) * weight_init)
        self.bias = nn.Parameter((torch.rand(csc_a, generator=g) * 2 - 1) * weight_init)

    def init_kwargs(self) -> dict:
        return dict(self._kwargs)

    def forward(self, c_s: Tensor, c_v: Tensor) -> Tensor:
        x = torch.cat([scaled_logistic(c_s), scaled_logistic(c_v)], dim=-1)
        return x @ self.weight.T + self.bias  # eq. (17)


class WordAssemblies(nn.Module):
    """CAs with a layer of word units between the perception Csc and c_a,0 (`end_to_end`):

    z = W_s f(c_s,T) + W_v f(c_v,T) + b          eq. (17), one unit per heard word
    p = softmax of z within each slot           (or a logistic per word), winner-take-all
    c_a,0 = E p + e                             the assemblies' projection into MTRNN_a

    `visual_readout` (one entry per slot: the c_v units its word units read, or None for all)
    masks W_v: with a factorised MTRNN_v (model/training/end_to_end/factors.py) the colour words
    read only the colour pathway's Csc and the shape words only the shape pathway's.
    """

    kind = "words"

    def __init__(
        self,
        csc_s: int,
        csc_v: int,
        csc_a: int,
        slots: list[list[str]],
        slot_softmax: bool = True,
        hard: bool = True,
        weight_init: float = 0.025,
        seed: int = 0,
        visual_readout: list[list[int] | None] | None = None,
    ) -> None:
        super().__init__()
        self._kwargs = {
            "csc_s": csc_s,
            "csc_v": csc_v,
            "csc_a": csc_a,
            "slots": [list(s) for s in slots],
            "slot_softmax": slot_softmax,
            "hard": hard,
            "weight_init": weight_init,
            "seed": seed,
        }
        if visual_readout is not None:  # only then: earlier checkpoints' kwargs stay as they were
            self._kwargs["visual_readout"] = [None if r is None else list(r) for r in visual_readout]
        self.sizes = [len(s) for s in slots]
        self.slot_softmax, self.hard = slot_softmax, hard
        words = sum(self.sizes)
        g = torch.Generator().manual_seed(seed)

        def uniform(*shape: int) -> nn.Parameter:
            return nn.Parameter((torch.rand(*shape, generator=g) * 2 - 1) * weight_init)

        self.weight_s, self.bias_s = uniform(words, csc_s), uniform(words)  # W_s and its share of b
        self.weight_v, self.bias_v = uniform(words, csc_v), uniform(words)  # W_v and its share of b
        self.projection, self.projection_bias = uniform(csc_a, words), uniform(csc_a)  # E, e
        # not in the state dict: rebuilt from the kwargs, so earlier checkpoints load unchanged
        self.register_buffer("readout_v", self._readout_mask(visual_readout, csc_v), persistent=False)
        with torch.no_grad():
            self.weight_v.mul_(self.readout_v)

    def _readout_mask(self, visual_readout: list[list[int] | None] | None, csc_v: int) -> Tensor:
        """[words, csc_v]: 1 where a word unit reads a c_v unit."""
        mask = torch.ones(sum(self.sizes), csc_v)
        if visual_readout is None:
            return mask
        if len(visual_readout) != len(self.sizes):
            raise ValueError(
                f"visual_readout needs one entry per slot ({len(self.sizes)}), got {len(visual_readout)}"
            )
        start = 0
        for size, units in zip(self.sizes, visual_readout, strict=True):
            if units is not None:
                if not units or not all(0 <= u < csc_v for u in units):
                    raise ValueError(f"visual_readout units must be in 0..{csc_v - 1}, got {units}")
                mask[start : start + size] = 0
                mask[start : start + size, units] = 1
            start += size
        return mask

    @property
    def words(self) -> list[str]:
        return [w for s in self._kwargs["slots"] for w in s]

    @property
    def slots(self) -> list[list[str]]:
        """The phrases of each slot, in the order of their word units."""
        return [list(s) for s in self._kwargs["slots"]]

    @torch.no_grad()
    def redraw_projection(self, generator: torch.Generator) -> None:
        """New initial E, e (a fresh start of the auditory stage)."""
        for p in (self.projection, self.projection_bias):
            p.copy_((torch.rand(p.shape, generator=generator) * 2 - 1) * self._kwargs["weight_init"])

    def init_kwargs(self) -> dict:
        return copy.deepcopy(self._kwargs)

    def modality_logits(self, c_s: Tensor, c_v: Tensor) -> tuple[Tensor, Tensor]:
        """Each encoder's share of eq. (17): W_s f(c_s) + b_s and W_v f(c_v) + b_v [..., words]."""
        return scaled_logistic(c_s) @ self.weight_s.T + self.bias_s, self.visual_logits(c_v)

    def visual_logits(self, c_v: Tensor) -> Tensor:
        """MTRNN_v's share of eq. (17), W_v f(c_v) + b_v, each word unit reading its c_v units."""
        return scaled_logistic(c_v) @ (self.weight_v * self.readout_v).T + self.bias_v

    def word_logits(self, c_s: Tensor, c_v: Tensor) -> Tensor:
        """z of eq. (17) for the word units."""
        z_s, z_v = self.modality_logits(c_s, c_v)
        return z_s + z_v

    def word_activity(self, z: Tensor, hard: bool) -> Tensor:
        """p: softmax within each slot (or a logistic per word); one-hot winners when `hard`."""
        if not self.slot_softmax:
            p = torch.sigmoid(z)
            return (p > 0.5).to(p.dtype) if hard else p
        parts = []
        for zk in z.split(self.sizes, dim=-1):
            pk = torch.softmax(zk, dim=-1)
            parts.append(F.one_hot(pk.argmax(dim=-1), pk.shape[-1]).to(pk.dtype) if hard else pk)
        return torch.cat(parts, dim=-1)

    def slot_probabilities(self, c_s: Tensor, c_v: Tensor) -> list[Tensor]:
        """Each slot's word-unit activity p before winner-take-all [..., phrases]: the softmax of
        eq. (17)'s z within the slot (or each word's logistic)."""
        return list(self.word_activity(self.word_logits(c_s, c_v), hard=False).split(self.sizes, dim=-1))

    def speak(self, p: Tensor) -> Tensor:
        """c_a,0 = E p + e."""
        return p @ self.projection.T + self.projection_bias

    def forward(self, c_s: Tensor, c_v: Tensor) -> Tensor:
        return self.speak(self.word_activity(self.word_logits(c_s, c_v), self.hard))

    def word_loss(self, z: Tensor, target: Tensor) -> Tensor:
        """Cross-entropy of the word units against the heard words p* (broadcast over points)."""
        target = target.expand_as(z)
        if not self.slot_softmax:
            return F.binary_cross_entropy_with_logits(z, target)
        loss = z.new_zeros(())
        for zk, tk in zip(z.split(self.sizes, dim=-1), target.split(self.sizes, dim=-1), strict=True):
            loss = loss - (tk * torch.log_softmax(zk, dim=-1)).sum(dim=-1).mean()
        return loss / len(self.sizes)


ASSEMBLIES: dict[str, type[nn.Module]] = {"linear": CellAssemblies, "words": WordAssemblies}
