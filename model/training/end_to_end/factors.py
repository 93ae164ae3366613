"""An object's colour and its shape as two things (issue 16): which of the paper's visual features
carry which, which heard slot each tells, and the two options built on that split.

The 19 features of MTRNN_v (`model.encoding.vision`, Fig. 7) are factorised by construction: 16
salient distances of the contour (the shape) and the mean R, G, B inside it (the colour); the
optional centroid is where the object lies. A single MTRNN_v mixes them into one c_v, so the word
units can learn *objects* ("a red apple") and guess the colour of a colour x shape pair never seen.

- `recoloured` (option `recombine_objects`): a recording whose colour columns come from another
  recording of another colour, its colour word following them: every colour with every shape.
- `factorise` (option `factorised_vision`): MTRNN_v as two disjoint pathways in one net (its
  connectivity mask, eq. 3, confines the colour inputs to a group of Cf, Cs and Csc units and the
  others to the rest) and the word units of the colour slot reading only the colour group's Csc,
  those of the shape slot only the other group's (`WordAssemblies(visual_readout=...)`).

Which slot the colour columns tell (and which the shape columns) is read off the training
recordings, not given: the slot whose heard word explains most of the variance of the recordings'
mean features (eta squared, `explaining_slot`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch
from torch import Tensor

from model.config import MTRNNConfig
from model.encoding.vision import SECTORS
from model.mtrnn import MTRNN, connectivity_mask

SHAPE_COLUMNS = tuple(range(SECTORS))  # the 16 salient distances
COLOUR_COLUMNS = (SECTORS, SECTORS + 1, SECTORS + 2)  # mean R, G, B
COLOUR_SHARE = 0.25  # of MTRNN_v's Cf, Cs and Csc units given to the colour pathway


def explaining_slot(
    heard: Tensor, sizes: Sequence[int], means: np.ndarray, exclude: Sequence[int] = ()
) -> int:
    """The slot (not in `exclude`) whose heard word explains most of the variance of `means`
    [B, columns] (per-recording mean features): eta squared, averaged over the columns."""
    total = ((means - means.mean(axis=0)) ** 2).sum(axis=0) + 1e-12
    best, best_eta = -1, -1.0
    for k, block in enumerate(heard.split(list(sizes), dim=-1)):
        if k in exclude:
            continue
        word = block.argmax(dim=-1).numpy()
        between = sum(
            (word == w).sum() * (means[word == w].mean(axis=0) - means.mean(axis=0)) ** 2
            for w in np.unique(word)
        )
        eta = float((between / total).mean())
        if eta > best_eta:
            best, best_eta = k, eta
    return best


def colour_and_shape_slots(
    heard: Tensor, sizes: Sequence[int], vision: Sequence[np.ndarray]
) -> tuple[int, int]:
    """(colour slot, shape slot) of the heard words, from the recordings' mean features."""
    means = np.stack([v.mean(axis=0) for v in vision])
    colour = explaining_slot(heard, sizes, means[:, COLOUR_COLUMNS])
    return colour, explaining_slot(heard, sizes, means[:, SHAPE_COLUMNS], exclude=(colour,))


def recoloured(
    vision: Tensor,
    lengths: Tensor,
    heard: Tensor,
    sizes: Sequence[int],
    colour_slot: int,
    generator: torch.Generator,
) -> tuple[Tensor, Tensor]:
    """Every recording with the colour columns of a donor recording heard with another colour word,
    the donor's colour track resampled to the recipient's length (linear interpolation), and the
    heard words with the donor's colour word. Returns (vision, heard) of the recoloured batch.
    A recording without a donor (every other one has its colour) keeps its own."""
    offsets = np.cumsum([0, *sizes])
    block = slice(int(offsets[colour_slot]), int(offsets[colour_slot + 1]))
    colour = heard[:, block].argmax(dim=-1)
    other = (colour[:, None] != colour[None, :]).float()
    other[other.sum(dim=1) == 0] = torch.eye(len(colour))[other.sum(dim=1) == 0]
    donor = torch.multinomial(other, 1, generator=generator)[:, 0]
    last = (lengths - 1).clamp(min=1).float()
    at = torch.arange(vision.shape[1])[None, :] * (lengths[donor] - 1)[:, None] / last[:, None]
    at = torch.minimum(at, (lengths[donor] - 1)[:, None].float())
    before = at.floor().long()
    after = torch.minimum(before + 1, (lengths[donor] - 1)[:, None])
    share = (at - before)[..., None]
    columns = list(COLOUR_COLUMNS)
    track = (
        vision[donor[:, None], before][..., columns] * (1 - share)
        + vision[donor[:, None], after][..., columns] * share
    )
    valid = (torch.arange(vision.shape[1])[None, :] < lengths[:, None])[..., None]
    out = vision.clone()
    out[..., columns] = torch.where(valid, track, vision[..., columns])
    words = heard.clone()
    words[:, block] = heard[donor, block]
    return out, words


def pathway_groups(cfg: MTRNNConfig) -> Tensor:
    """1 for the colour pathway's units of MTRNN_v, 0 for the other's: the colour input columns,
    and the first `COLOUR_SHARE` of the Cf units, of the Csc units and of the other Cs units."""
    io = torch.zeros(cfg.io)
    io[[c for c in COLOUR_COLUMNS if c < cfg.io]] = 1

    def first(n: int) -> Tensor:
        out = torch.zeros(n)
        out[: max(1, round(COLOUR_SHARE * n))] = 1
        return out

    return torch.cat([io, first(cfg.cf), first(cfg.csc), first(cfg.cs - cfg.csc)])


def csc_pathways(cfg: MTRNNConfig) -> tuple[list[int], list[int]]:
    """The Csc unit indices (within c_v) of the colour pathway and of the shape pathway."""
    csc = pathway_groups(cfg)[cfg.io + cfg.cf : cfg.io + cfg.cf + cfg.csc]
    return torch.nonzero(csc == 1)[:, 0].tolist(), torch.nonzero(csc == 0)[:, 0].tolist()


@torch.no_grad()
def factorise(net: MTRNN) -> None:
    """Cut MTRNN_v into the two pathways of `pathway_groups`: its connectivity mask keeps only the
    connections within a group (the weights across are zeroed). The mask is a buffer of the net,
    so a checkpoint keeps it and `model.checkpoint.load` restores it with the weights."""
    groups = pathway_groups(net.cfg)
    net.mask.copy_(connectivity_mask(net.cfg) * (groups[:, None] == groups[None, :]).float())
    net.weight.mul_(net.mask)
