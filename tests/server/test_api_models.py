"""GET /api/models and PUT /api/models/selected: which model answers."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient

from data.corpus import load_corpus
from server.settings import Settings
from tests.app_builder import build_app


@pytest.fixture()
def fresh(settings: Settings) -> Iterator[TestClient]:
    """An app of its own: selecting a model must not leak into the other tests."""
    with TestClient(build_app(settings)) as c:
        yield c


def test_models_lists_every_checkpoint_with_its_meta(fresh: TestClient) -> None:
    body = fresh.get("/api/models").json()
    assert body["selected"] == "default"
    assert [m["name"] for m in body["models"]] == ["default", "other"]
    assert body["models"][0]["selected"] and body["models"][0]["meta"]["seed"] == 0
    assert body["models"][1]["meta"]["seed"] == 1


def test_selecting_a_model_changes_every_answer(fresh: TestClient, settings: Settings) -> None:
    rid = load_corpus(settings.corpus_path).entries[0].id
    before = fresh.post(f"/api/scenes/{rid}/describe").json()
    csc_before = fresh.get("/api/csc", params={"space": "a"}).json()
    body = fresh.put("/api/models/selected", json={"name": "other"}).json()
    assert body["selected"] == "other"
    after = fresh.post(f"/api/scenes/{rid}/describe").json()
    assert after["model"] == "other" and after["csc"]["a"] != before["csc"]["a"]
    assert fresh.get("/api/health").json()["model"] == "other"
    assert fresh.get("/api/csc", params={"space": "a"}).json()["model"] == "other" != csc_before["model"]


def test_selecting_an_unknown_model_is_404(fresh: TestClient) -> None:
    response = fresh.put("/api/models/selected", json={"name": "nope"})
    assert response.status_code == 404 and "available" in response.json()["detail"]
