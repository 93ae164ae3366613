"""The one model registry: the model folders the app can serve, each loaded once, one of them served.

A model folder holds `model.safetensors` and `meta.json` (`model.checkpoint`). The registry finds
the folders under `settings.models_dir` (the shipped models) and then under the app's own
`settings.user_dir / "models"` (models trained in the app; a name shipped already is skipped),
loads a model the first time it is asked for, knows which one is served, and reads each model's
training and test recordings from its meta with one rule (`split_ids`). Finished training jobs
add their folder (`register`).

Each loaded model carries its `model.familiarity.Familiarity` (how far a recording lies from its
training recordings): the one saved in its checkpoint, else (models trained before familiarity
existed, such as the shipped ones) fitted once on load from the corpus recordings its meta["ids"]
name, when the registry was given the corpus (`recordings`); None when neither is at hand.
"""

from __future__ import annotations

import json
import logging
import threading
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from model import checkpoint
from model.data import scene_key
from model.encoding.utterance import Lexicon
from model.familiarity import Familiarity, vision_columns
from model.multimtrnn import MultiMTRNN
from server.services.corpus import Corpus
from server.services.errors import NotFound, Unavailable
from server.settings import Settings

logger = logging.getLogger(__name__)

Recordings = Callable[[], Mapping[str, Any]]  # the corpus entries by id (proprioception, vision, ...)


def split_ids(meta: dict, corpus_ids: Iterable[str]) -> tuple[frozenset[str], frozenset[str]]:
    """Training and test ids from meta.json: its ``split: {train, test}``, else its training ``ids``
    with the rest of the corpus as the test set (ids may be recording ids or scene ids)."""
    split = meta.get("split") or {}
    if split.get("train") or split.get("test"):
        return frozenset(split.get("train", [])), frozenset(split.get("test", []))
    train = frozenset(meta.get("ids") or [])
    return train, frozenset(rid for rid in corpus_ids if rid not in train)


@dataclass
class LoadedModel:
    """One model as the app serves it."""

    name: str
    path: Path
    model: MultiMTRNN
    lexicon: Lexicon
    meta: dict
    train_ids: frozenset[str]  # recording ids or scene ids the model was trained on
    test_ids: frozenset[str]
    familiarity: Familiarity | None = None  # how far a recording lies from the training recordings

    @property
    def mode(self) -> str:
        return str(self.meta.get("mode", "unknown"))

    def split_of(self, rid: str, scene_id: str = "") -> str:
        """'train' or 'test' for a recording (or its scene), 'unknown' for one outside both."""
        if rid in self.train_ids or scene_id in self.train_ids:
            return "train"
        if rid in self.test_ids or scene_id in self.test_ids:
            return "test"
        return "unknown"


def user_models(settings: Settings) -> Path:
    """The app's own models folder: where its training jobs save their models."""
    return settings.user_dir / "models"


def discover(root: Path) -> dict[str, Path]:
    """Model folders under `root` (those with a meta.json), by name, in name order."""
    if not root.is_dir():
        return {}
    return {p.name: p for p in sorted(root.iterdir()) if (p / checkpoint.META).is_file()}


class ModelRegistry:
    """The models of one app. `lock` serialises calls into a model (describe, generate)."""

    def __init__(
        self,
        models_dir: Path,
        corpus_ids: list[str],
        preferred: str,
        corpus_lexicon: Lexicon | None,
        user_models_dir: Path | None = None,
        recordings: Recordings | None = None,
    ) -> None:
        self.dirs = discover(models_dir)  # shipped first, then the app's own
        for name, path in discover(user_models_dir).items() if user_models_dir else ():
            if name in self.dirs:
                logger.warning("model %s in %s has the name of a shipped model: skipped", name, path)
            else:
                self.dirs[name] = path
        if not self.dirs:
            raise FileNotFoundError(
                f"no model under {models_dir} (expected <name>/model.safetensors + meta.json); "
                "train one with `make model`"
            )
        self.lock = threading.RLock()
        self._corpus_ids, self._corpus_lexicon, self._recordings = corpus_ids, corpus_lexicon, recordings
        self._loaded: dict[str, LoadedModel] = {}
        self._served = self._load(preferred if preferred in self.dirs else next(iter(self.dirs)))

    @classmethod
    def serving(cls, settings: Settings, corpus: Corpus) -> ModelRegistry:
        """The registry of the shipped and the app's models over `corpus`, serving `settings.model` first."""
        return cls(
            settings.models_dir,
            list(corpus.entries),
            settings.model,
            corpus.lexicon,
            user_models(settings),
            lambda: corpus.entries,
        )

    def _load(self, name: str) -> LoadedModel:
        with self.lock:
            if name not in self._loaded:
                model, meta = checkpoint.load(self.dirs[name])
                words = meta.get("lexicon")
                lexicon = Lexicon(words) if words else self._corpus_lexicon
                if lexicon is None:
                    raise Unavailable(f"model {name!r} has no lexicon and the corpus is empty")
                train, test = split_ids(meta, self._corpus_ids)
                familiarity = checkpoint.load_familiarity(self.dirs[name]) or self._fit_familiarity(
                    name, meta
                )
                self._loaded[name] = LoadedModel(
                    name, self.dirs[name], model, lexicon, meta, train, test, familiarity
                )
            return self._loaded[name]

    def _fit_familiarity(self, name: str, meta: dict) -> Familiarity | None:
        """Familiarity fitted on the corpus recordings meta["ids"] names (recording or scene ids)."""
        ids = set(meta.get("ids") or [])
        entries = self._recordings() if self._recordings is not None else {}
        picked = [e for rid, e in entries.items() if rid in ids or scene_key(rid) in ids]
        if len(picked) < 2:
            logger.info(
                "model %s: no familiarity (its checkpoint has none, its recordings are not at hand)", name
            )
            return None
        familiarity = Familiarity.fit(
            [e.proprioception for e in picked],
            [e.vision for e in picked],
            [e.object_found for e in picked],
            [e.id for e in picked],
            vision_columns(meta),
        )
        logger.info(
            "model %s: its checkpoint has no familiarity; fitted on the %d corpus recordings it learned from",
            name,
            len(picked),
        )
        return familiarity

    @property
    def served(self) -> LoadedModel:
        return self._served

    def names(self) -> list[str]:
        return list(self.dirs)

    def get(self, name: str | None = None) -> LoadedModel:
        """The named model (default: the served one), loaded once from its checkpoint."""
        if name is None:
            return self._served
        if name not in self.dirs:
            raise NotFound(f"no model {name!r}; available: {', '.join(self.names())}")
        return self._load(name)

    def select(self, name: str) -> LoadedModel:
        """Serve another model: every later answer comes from it."""
        if name not in self.dirs:
            raise NotFound(f"no model {name!r}; available: {sorted(self.dirs)}")
        self._served = self._load(name)
        return self._served

    def metas(self) -> dict[str, dict]:
        """meta.json of every model (read from disk for those not loaded yet)."""
        return {
            name: self._loaded[name].meta
            if name in self._loaded
            else json.loads((path / checkpoint.META).read_text())
            for name, path in self.dirs.items()
        }

    def modes(self) -> dict[str, str]:
        """Training mode of every model (from its meta.json, without loading the weights)."""
        return {name: str(meta.get("mode", "unknown")) for name, meta in self.metas().items()}

    def register(self, name: str, path: Path) -> None:
        """A model a training job has just written joins the registry."""
        self.dirs[name] = path
        logger.info("model %r joins the registry (%s)", name, path)
