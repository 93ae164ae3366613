"""The shipped models say, for every corpus recording, exactly what they said when the list was stored.

`tests/golden/descriptions.json` holds the text and phonemes each shipped model generated for each of
the 256 corpus recordings; a refactor that changes one word of one description fails here.
"""

import json
from pathlib import Path

import pytest

from data.corpus import load_corpus
from model import checkpoint
from model.encoding.utterance import Lexicon

GOLDEN = Path(__file__).resolve().parent / "golden" / "descriptions.json"
MODELS = Path(__file__).resolve().parents[1] / "data" / "artefacts" / "models"


@pytest.mark.slow
@pytest.mark.parametrize("name", ["default", "faithful"])
def test_shipped_model_describes_every_corpus_recording_as_stored(name: str) -> None:
    stored = json.loads(GOLDEN.read_text())[name]
    corpus = load_corpus()
    model, meta = checkpoint.load(MODELS / name)
    lexicon = Lexicon(meta["lexicon"])
    said = {}
    for entry in corpus.entries:
        d = model.describe(entry.proprioception, entry.vision, lexicon)
        said[entry.id] = {"text": d.text, "phonemes": " ".join(d.phonemes)}
    assert len(said) == 256
    changed = [rid for rid in stored if said[rid] != stored[rid]]
    assert not changed, f"{len(changed)} descriptions changed, first {changed[:5]}"
