"""Training a model on a SequenceSet: one `train()` over a plain dict of modes.

- `faithful` (`faithful.py`): the paper's staged recipe (3.1.3-3.1.4, 3.2.1, 3.4.3).
- `end_to_end` (`end_to_end/`): the cell assemblies and encoders learn through the auditory loss.
- `peer` (`peer.py`): a GRU encoder-decoder baseline that describes scenes the same way.

Every mode is a function `(data, config, seed, progress) -> TrainedModel` that takes its own
config (a dataclass, its dict, or None for the defaults); what they share is in `common.py`.
`train()` also fits the model's `Familiarity` (`model/familiarity.py`) on the training recordings.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import torch

from model.config import MultiMTRNNConfig
from model.data import SequenceSet
from model.familiarity import Familiarity, vision_columns
from model.training.common import ProgressFn, TrainedModel
from model.training.end_to_end import train_end_to_end
from model.training.faithful import train_faithful
from model.training.peer import PeerConfig, train_peer

log = logging.getLogger(__name__)

ModeFn = Callable[[SequenceSet, Any, int, "ProgressFn | None"], TrainedModel]
MODES: dict[str, ModeFn] = {"faithful": train_faithful, "end_to_end": train_end_to_end, "peer": train_peer}
# each mode's config class (`model.experiments.protocol.default_config` gives its defaults as a dict)
CONFIGS: dict[str, type[MultiMTRNNConfig] | type[PeerConfig]] = {
    "faithful": MultiMTRNNConfig,
    "end_to_end": MultiMTRNNConfig,
    "peer": PeerConfig,
}


def train(
    data: SequenceSet,
    mode: str = "faithful",
    config: Any = None,
    seed: int = 0,
    progress: ProgressFn | None = None,
) -> TrainedModel:
    """Train `mode` on `data` with its config (a `CONFIGS[mode]`); deterministic for a given seed."""
    if mode not in MODES:
        raise ValueError(f"unknown training mode {mode!r}; available: {sorted(MODES)}")
    torch.manual_seed(seed)
    np.random.seed(seed % 2**32)
    start = time.perf_counter()
    result = MODES[mode](data, config, seed, progress)
    result.meta.setdefault("seconds_total", time.perf_counter() - start)
    if len(data) > 1:  # familiarity calibrates on leave-one-out distances: it needs two recordings
        result.familiarity = Familiarity.fit(
            data.proprioception, data.vision, ids=data.ids, vision_columns=vision_columns(result.meta)
        )
    log.info(
        "trained %s (seed %d) on %d sequences in %.1f s", mode, seed, len(data), time.perf_counter() - start
    )
    return result


__all__ = ["CONFIGS", "MODES", "TrainedModel", "train"]
