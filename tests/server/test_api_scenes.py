"""GET /api/health, /api/scenes (filters, and what the served model says about each recording),
/api/scenes/{id}, frames, pages and static files."""

from __future__ import annotations

import threading
import time

import cv2
import numpy as np
import pytest
from fastapi.testclient import TestClient

from data.corpus import load_corpus
from data.nao import JOINT_NAMES
from model.metrics import sentence_exact
from server.services.survey import SurveyService
from server.settings import Settings
from tests.app_builder import build_app


def test_health_names_the_served_model_and_corpus_size(client: TestClient, settings: Settings) -> None:
    body = client.get("/api/health").json()
    assert body == {
        "status": "ok",
        "model": "default",
        "scenes": len(load_corpus(settings.corpus_path).entries),
        "viewer": False,
    }


def test_scene_list_carries_metadata_and_the_models_split(client: TestClient, settings: Settings) -> None:
    body = client.get("/api/scenes").json()
    corpus = load_corpus(settings.corpus_path)
    assert body["total"] == len(corpus.entries) == len(body["scenes"])
    first = body["scenes"][0]
    entry = corpus.entries[0]
    assert first["id"] == entry.id and first["utterance"] == entry.utterance
    assert (first["action"], first["colour"], first["shape"]) == (
        entry.scene.action,
        entry.scene.colour,
        entry.scene.shape,
    )
    assert {s["split"] for s in body["scenes"]} == {"train", "test"}


def _surveyed(client: TestClient, timeout: float = 300.0) -> list[dict]:
    """The scene list once the served model's survey has filled in what it says."""
    deadline = time.monotonic() + timeout
    while True:
        scenes = client.get("/api/scenes").json()["scenes"]
        if all(s["said"] is not None for s in scenes):
            return scenes
        assert time.monotonic() < deadline, "the survey did not finish"
        time.sleep(0.2)


def test_each_scene_says_what_the_served_model_says_and_whether_it_is_right(client: TestClient) -> None:
    scenes = _surveyed(client)
    assert all(s["correct"] is sentence_exact(s["said"], s["utterance"]) for s in scenes)
    first = scenes[0]
    summary = client.get(f"/api/scenes/{first['id']}").json()["summary"]
    assert (summary["said"], summary["correct"]) == (first["said"], first["correct"])
    described = client.post(f"/api/scenes/{first['id']}/describe").json()
    assert described["utterance"] == first["said"]  # the survey's answer is the describe answer


def test_the_scene_list_does_not_wait_for_the_survey(
    settings: Settings, monkeypatch: pytest.MonkeyPatch
) -> None:
    gate = threading.Event()
    describe_all = SurveyService._describe_all

    def held_back(self: SurveyService, lm: object) -> object:  # the survey, held back until the gate opens
        gate.wait(timeout=120)
        return describe_all(self, lm)  # type: ignore[arg-type]

    monkeypatch.setattr(SurveyService, "_describe_all", held_back)
    with TestClient(build_app(settings)) as c:
        try:
            started = time.perf_counter()
            scenes = c.get("/api/scenes").json()["scenes"]
            assert time.perf_counter() - started < 60  # answered while the survey waits
            assert scenes and all(s["said"] is None and s["correct"] is None for s in scenes)
            assert c.get(f"/api/scenes/{scenes[0]['id']}").json()["summary"]["said"] is None
        finally:
            gate.set()
        assert all(isinstance(s["correct"], bool) for s in _surveyed(c))


def test_scene_filters_combine(client: TestClient) -> None:
    pulls = client.get("/api/scenes", params={"action": "pull"}).json()["scenes"]
    assert pulls and all(s["action"] == "pull" for s in pulls)
    shows = client.get("/api/scenes", params={"action": "show-me", "split": "test"}).json()["scenes"]
    assert all(s["action"] == "show me" and s["split"] == "test" for s in shows)
    red = client.get("/api/scenes", params={"q": "red"}).json()["scenes"]
    assert red and all("red" in s["utterance"] for s in red)
    assert client.get("/api/scenes", params={"variant": 7}).status_code == 422


def test_scene_detail_has_joints_and_encodings(client: TestClient, settings: Settings) -> None:
    entry = load_corpus(settings.corpus_path).entries[0]
    body = client.get(f"/api/scenes/{entry.id}").json()
    assert body["joint_names"] == list(JOINT_NAMES)
    assert np.allclose(body["joints"], entry.joints, atol=1e-4)
    assert np.allclose(body["proprioception"], entry.proprioception, atol=1e-4)
    assert np.array(body["vision"]).shape == entry.vision.shape
    assert body["frames"] == len(entry.joints) and body["summary"]["id"] == entry.id


def test_unknown_scene_is_404_with_a_message(client: TestClient) -> None:
    response = client.get("/api/scenes/fly-purple-cat-9")
    assert response.status_code == 404
    assert "no recording 'fly-purple-cat-9'" in response.json()["detail"]


def test_camera_frames_are_jpegs_with_an_optional_pipeline_overlay(
    client: TestClient, settings: Settings
) -> None:
    rid = load_corpus(settings.corpus_path).entries[0].id
    plain = client.get(f"/api/scenes/{rid}/frames/10.jpg")
    overlay = client.get(f"/api/scenes/{rid}/frames/10.jpg", params={"overlay": True})
    thumb = client.get(f"/api/scenes/{rid}/frames/10.jpg", params={"width": 80})
    for r in (plain, overlay, thumb):
        assert r.status_code == 200 and r.headers["content-type"] == "image/jpeg"
    a = cv2.imdecode(np.frombuffer(plain.content, np.uint8), cv2.IMREAD_COLOR)
    b = cv2.imdecode(np.frombuffer(overlay.content, np.uint8), cv2.IMREAD_COLOR)
    t = cv2.imdecode(np.frombuffer(thumb.content, np.uint8), cv2.IMREAD_COLOR)
    assert a.shape == b.shape == (240, 320, 3) and t.shape[1] == 80
    assert np.abs(a.astype(int) - b.astype(int)).mean() > 0.5  # contour and rays drawn
    assert client.get(f"/api/scenes/{rid}/frames/100000.jpg").status_code == 404


def test_pages_plotly_and_the_app_shell_are_served(client: TestClient) -> None:
    pages = client.get("/api/pages").json()["pages"]
    assert {"scenes", "scene", "upload", "csc", "latent", "glossary"} <= set(pages)
    assert "MultiMTRNN explorer" in client.get("/").text
    plotly = client.get("/vendor/plotly.min.js")
    assert plotly.status_code == 200 and len(plotly.content) > 1_000_000
    assert client.get("/openapi.json").json()["info"]["title"] == "MultiMTRNN explorer"
