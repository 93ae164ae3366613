"""What the explorer's tests serve: the real corpus code and a real (untrained) MultiMTRNN.

The corpus is the shipped one when it exists, otherwise eight recordings (two per action) built
with `data.corpus.build_corpus`. The models are MultiMTRNNs at the paper's sizes with random
weights (training is not what these tests are about), saved with `model.checkpoint.save`; their
meta.json says which recordings are their training set, as a trained model's does.
"""

from __future__ import annotations

import io
import zipfile
from dataclasses import dataclass
from pathlib import Path

from data.corpus import DEFAULT_PATH, build_corpus, load_corpus
from data.scenario import all_scenes
from model.checkpoint import save
from model.encoding.utterance import Lexicon
from model.multimtrnn import MultiMTRNN
from server.settings import Settings

SMALL_CORPUS = (
    "pull-red-apple-0",
    "pull-blue-dice-1",
    "push-blue-dice-1",
    "push-green-phone-0",
    "show-me-green-banana-2",
    "show-me-red-dice-0",
    "slide-yellow-phone-3",
    "slide-red-banana-1",
)


def build_artefacts(root: Path) -> Settings:
    """Corpus + two models under `root`; returns the Settings that serve them (no 3D viewer)."""
    if DEFAULT_PATH.is_file():
        corpus_path = DEFAULT_PATH
    else:
        corpus_path = build_corpus(seed=0, workers=2, out=root / "corpus.npz", recordings=SMALL_CORPUS)
    corpus = load_corpus(corpus_path)
    scenes = sorted({e.scene.id for e in corpus.entries})
    train = [e.id for e in corpus.entries if scenes.index(e.scene.id) % 2 == 0]  # split by scene
    lexicon = list(Lexicon.from_sentences(s.utterance for s in all_scenes()).words)
    for name, seed in (("default", 0), ("other", 1)):
        model = MultiMTRNN(seed=seed)
        meta = {"mode": "untrained", "seed": seed, "ids": train, "lexicon": lexicon}
        save(model, root / "models" / name, meta)
    return Settings(
        models_dir=root / "models",
        corpus_path=corpus_path,
        viser=False,
        run_dir=root / "runs",
        user_dir=root / "user",
    )


@dataclass(frozen=True)
class Exported:
    id: str
    zip: Path
    npz: Path


def zip_bytes(members: dict[str, bytes]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return buf.getvalue()
