"""Describing: POST /api/scenes/{id}/describe, POST /api/describe (uploads), /api/uploads/{id}."""

from __future__ import annotations

import dataclasses
import json
import logging
from pathlib import Path

import numpy as np
import pytest
from explorer_artefacts import Exported, zip_bytes
from fastapi.testclient import TestClient
from hostile_cases import recording_members, zip_of

from data.corpus import load_corpus
from model.checkpoint import load, save
from model.encoding.utterance import PHONEMES, Lexicon, encode_utterance
from server.services.corpus import Corpus
from server.services.models import ModelRegistry
from server.settings import Settings


def test_describe_scene_is_the_models_answer(client: TestClient, settings: Settings) -> None:
    entry = load_corpus(settings.corpus_path).entries[0]
    body = client.post(f"/api/scenes/{entry.id}/describe").json()
    model, meta = load(settings.models_dir / "default")
    expected = model.describe(entry.proprioception, entry.vision, Lexicon(meta["lexicon"]))
    assert body["utterance"] == expected.text and body["phonemes"] == expected.phonemes
    assert np.allclose(body["activity"], expected.activity, atol=1e-4)
    assert np.allclose(body["csc"]["a"], expected.csc_a, atol=1e-5)
    assert len(body["csc"]["s"]) == len(body["csc"]["v"]) == len(body["csc"]["a"]) == 12
    assert body["phoneme_labels"] == list(PHONEMES)
    assert body["expected"] == entry.utterance and body["correct"] == (expected.text == entry.utterance)
    assert np.allclose(body["target_activity"], encode_utterance(entry.utterance), atol=1e-4)
    assert body["timings"]["model_ms"] > 0 and body["timings"]["total_ms"] >= body["timings"]["model_ms"]


def test_describe_unknown_scene_is_404(client: TestClient) -> None:
    assert client.post("/api/scenes/nope-0/describe").status_code == 404


@pytest.mark.parametrize("kind", ["zip", "npz"])
def test_upload_of_an_exported_recording_is_described(
    client: TestClient, settings: Settings, exported: Exported, kind: str
) -> None:
    path = getattr(exported, kind)
    response = client.post("/api/describe", files={"recording": (path.name, path.read_bytes())})
    assert response.status_code == 200, response.text
    body = response.json()
    assert body["source"] == "upload" and body["id"].startswith("upload-")
    assert body["expected"] == load_corpus(settings.corpus_path).by_id(exported.id).utterance
    assert isinstance(body["utterance"], str) and len(body["activity"][0]) == len(PHONEMES)
    assert body["target_activity"] is not None  # the export carries the teacher's utterance
    assert body["timings"]["read_ms"] > 0 and body["timings"]["encode_ms"] > 0
    detail = client.get(f"/api/uploads/{body['id']}").json()
    assert detail["source"] == "upload" and len(detail["joints"]) == detail["frames"]
    again = client.get(f"/api/uploads/{body['id']}/description").json()
    assert again["utterance"] == body["utterance"]
    frame = client.get(f"/api/scenes/{body['id']}/frames/0.jpg")
    assert frame.status_code == 200 and frame.headers["content-type"] == "image/jpeg"


@pytest.mark.parametrize(
    ("filename", "data", "message"),
    [
        ("rec.zip", b"", "empty"),
        ("rec.zip", b"this is not a zip file at all", "corrupt archive"),
        ("notes.txt", b"hello", "not a recording"),
        ("rec.zip", zip_bytes({"meta.json": b"{}"}), "joints.csv"),
        ("rec.zip", zip_bytes({"joints.csv": b"t,a,b\n0,1,2\n"}), "joints.csv"),
        ("rec.npz", zip_bytes({"joints.npy": b"garbage"}), "rec.npz"),
    ],
)
def test_malformed_uploads_get_4xx_with_the_readers_message(
    client: TestClient, filename: str, data: bytes, message: str
) -> None:
    response = client.post("/api/describe", files={"recording": (filename, data)})
    assert 400 <= response.status_code < 500
    assert message in response.json()["detail"]
    assert client.get("/api/health").status_code == 200  # still answering


def test_upload_without_the_recording_field_is_422(client: TestClient) -> None:
    response = client.post("/api/describe", files={"file": ("rec.zip", b"PK")})
    assert response.status_code == 422 and "'recording'" in response.json()["detail"]
    response = client.post("/api/describe", content=b"not multipart", headers={"content-type": "text/plain"})
    assert 400 <= response.status_code < 500


def test_upload_over_the_size_cap_is_413(client: TestClient, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("server.routes.describe.MAX_UPLOAD_BYTES", 4096)
    big = b"PK\x03\x04" + bytes(10_000)
    response = client.post("/api/describe", files={"recording": ("big.zip", big)})
    assert response.status_code == 413 and "limit" in response.json()["detail"]
    # a body only slightly over the cap is caught while reading, not from the header
    response = client.post("/api/describe", files={"recording": ("big.zip", big[:5000])})
    assert response.status_code == 413
    assert client.get("/api/health").json()["status"] == "ok"


def test_unknown_upload_is_404(client: TestClient) -> None:
    assert client.get("/api/uploads/upload-000000000000").status_code == 404


def test_a_corpus_recording_is_familiar_to_the_model_that_learned_from_it(
    client: TestClient, settings: Settings
) -> None:
    """The untrained test models' checkpoints have no familiarity: the registry fits it from the
    corpus recordings their meta["ids"] name, so their training recordings score 1."""
    meta = json.loads((settings.models_dir / "default" / "meta.json").read_text())
    trained_on, rest = (
        meta["ids"][0],
        next(e for e in load_corpus(settings.corpus_path).entries if e.id not in meta["ids"]),
    )
    body = client.post(f"/api/scenes/{trained_on}/describe").json()
    assert body["familiarity"] == {"proprioception": 1.0, "vision": 1.0} and body["warnings"] == []
    held_out = client.post(f"/api/scenes/{rest.id}/describe").json()["familiarity"]
    assert all(0 < held_out[k] <= 1 for k in ("proprioception", "vision"))


def test_a_far_off_upload_is_unfamiliar_and_says_why(client: TestClient) -> None:
    """20 s of a motionless arm at the middle of its joint ranges, a red block on grey."""
    data = zip_of(recording_members(steps=400))
    body = client.post("/api/describe", files={"recording": ("still.zip", data)}).json()
    assert body["familiarity"]["proprioception"] < 0.05
    assert "the arm's postures are far outside what the model learned from" in body["warnings"]
    assert any(
        w.startswith("the recording is much longer than any the model learned from (20.0 s")
        for w in body["warnings"]
    )
    again = client.get(f"/api/uploads/{body['id']}/description").json()
    assert again["familiarity"] == body["familiarity"] and again["warnings"] == body["warnings"]


def test_familiarity_is_documented_in_openapi(client: TestClient) -> None:
    schemas = client.get("/openapi.json").json()["components"]["schemas"]
    fields = schemas["Familiarity"]["properties"]
    assert fields["proprioception"]["maximum"] == 1 and fields["vision"]["minimum"] == 0
    assert "nearest training recording" in fields["proprioception"]["description"]
    assert (
        "unlike what the model learned from"
        in schemas["Description"]["properties"]["warnings"]["description"]
    )


def test_the_registry_fits_familiarity_once_for_an_old_checkpoint_and_says_so(
    settings: Settings, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    corpus = Corpus.load(settings)
    with caplog.at_level(logging.INFO, logger="server.services.models"):
        registry = ModelRegistry.serving(dataclasses.replace(settings, user_dir=tmp_path), corpus)
    assert "its checkpoint has no familiarity; fitted on the" in caplog.text
    fitted = registry.served.familiarity
    assert fitted is not None and registry.get("default").familiarity is fitted
    model, meta = load(settings.models_dir / "default")
    save(model, tmp_path / "models" / "saved", meta, familiarity=fitted)
    caplog.clear()
    with caplog.at_level(logging.INFO, logger="server.services.models"):
        saved = ModelRegistry(tmp_path / "models", list(corpus.entries), "saved", corpus.lexicon).served
    assert saved.familiarity is not None and "fitted on the" not in caplog.text
    e = corpus.entries[meta["ids"][0]]
    assert saved.familiarity.score(e.proprioception, e.vision) == fitted.score(e.proprioception, e.vision)
