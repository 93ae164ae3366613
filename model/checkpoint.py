"""Checkpoints of every training mode: `model.safetensors` (weights) + `meta.json` (mode, config,
assemblies, seed, split, metrics, lexicon, T_a) + optional `training_csc.safetensors` (the learned
c_0 / c_T tables, for the Csc explorer) + optional `familiarity.safetensors` (the training set's
`model.familiarity.Familiarity`; `load_familiarity`, None for checkpoints written before it).
Loading never unpickles and rebuilds the model its meta["mode"] names: the peer baseline
(`model.training.peer`) or, for every other mode, a MultiMTRNN. Writing is atomic: everything goes
into a temporary sibling directory that then replaces `directory` in one rename.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
import torch
from safetensors.numpy import load_file as load_arrays
from safetensors.numpy import save_file as save_arrays
from safetensors.torch import load_file, save_file

from model.assemblies import ASSEMBLIES
from model.config import MultiMTRNNConfig
from model.familiarity import Familiarity
from model.multimtrnn import MultiMTRNN
from model.training.common import Describer
from model.training.peer import LEGACY, PeerConfig, PeerModel

WEIGHTS = "model.safetensors"
META = "meta.json"
TRAINING_CSC = "training_csc.safetensors"
FAMILIARITY = "familiarity.safetensors"
FORMAT_VERSION = 1


def _jsonable(value):
    """numpy scalars/arrays -> plain Python, recursively."""
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def _architecture(model: Describer) -> dict:
    """What `load` needs to rebuild `model` before its weights go in."""
    if isinstance(model, PeerModel):
        return {"peer_config": model.config.to_dict(), "generation_steps": model.generation_steps}
    return {
        "config": model.config.to_dict(),
        "assemblies": model.assemblies_spec(),
        "generation_steps": model.config.generation_steps,
    }


def save(
    model: Describer,
    directory: str | Path,
    meta: dict | None = None,
    training_csc: dict[str, np.ndarray] | None = None,
    familiarity: Familiarity | None = None,
) -> Path:
    """Write a checkpoint into `directory` (replaced atomically if it exists)."""
    directory = Path(directory)
    directory.parent.mkdir(parents=True, exist_ok=True)
    full_meta = dict(_jsonable(meta or {}))
    full_meta.update({"format": FORMAT_VERSION, **_architecture(model)})
    tmp = Path(tempfile.mkdtemp(prefix=f".{directory.name}.", dir=directory.parent))
    try:
        state = {k: v.detach().contiguous().clone() for k, v in model.state_dict().items()}
        save_file(state, str(tmp / WEIGHTS))
        if training_csc:
            save_file(
                {k: torch.as_tensor(np.ascontiguousarray(v)) for k, v in training_csc.items()},
                str(tmp / TRAINING_CSC),
            )
        if familiarity is not None:
            save_arrays(familiarity.arrays(), str(tmp / FAMILIARITY))
        (tmp / META).write_text(json.dumps(full_meta, indent=2, sort_keys=True))
        if directory.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{directory.name}.old.", dir=directory.parent))
            os.replace(directory, old / "x")
            os.replace(tmp, directory)
            shutil.rmtree(old)
        else:
            os.replace(tmp, directory)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return directory


def _multimtrnn(meta: dict, weights: dict[str, torch.Tensor]) -> MultiMTRNN:
    spec = meta["assemblies"]
    if spec["kind"] not in ASSEMBLIES:
        raise ValueError(f"checkpoint needs assemblies kind {spec['kind']!r}; known: {sorted(ASSEMBLIES)}")
    model = MultiMTRNN(
        MultiMTRNNConfig.from_dict(meta["config"]), assemblies=ASSEMBLIES[spec["kind"]](**spec["kwargs"])
    )
    model.load_state_dict(weights)
    return model


def _peer(meta: dict, weights: dict[str, torch.Tensor]) -> PeerModel:
    model = PeerModel(PeerConfig.from_dict({**LEGACY, **meta["peer_config"]}), int(meta["generation_steps"]))
    state = model.state_dict()  # a legacy checkpoint has no normalisation buffers: they stay identity
    state.update(weights)
    model.load_state_dict(state)
    return model


# the model a mode trains, rebuilt from meta and weights; a MultiMTRNN for every other mode
BUILDERS = {"peer": _peer}


def load(directory: str | Path) -> tuple[Describer, dict]:
    """Rebuild the model from `meta.json` and load its weights (no pickle anywhere)."""
    directory = Path(directory)
    meta = json.loads((directory / META).read_text())
    model = BUILDERS.get(meta.get("mode"), _multimtrnn)(meta, load_file(str(directory / WEIGHTS)))
    model.eval()
    return model, meta


def load_training_csc(directory: str | Path) -> dict[str, np.ndarray]:
    """The learned training tables (c_0 of MTRNN_a, c_T of the encoders), empty if not saved."""
    path = Path(directory) / TRAINING_CSC
    if not path.exists():
        return {}
    return {k: v.numpy() for k, v in load_file(str(path)).items()}


def load_familiarity(directory: str | Path) -> Familiarity | None:
    """The training set's familiarity saved with the model, None if the checkpoint has none."""
    path = Path(directory) / FAMILIARITY
    return Familiarity.from_arrays(load_arrays(str(path))) if path.exists() else None
