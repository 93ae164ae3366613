"""The live description: GET /api/scenes/{id}/timeline, and the timeline of the upload describe answer."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from pathlib import Path

import pytest
from explorer_artefacts import Exported
from fastapi.testclient import TestClient

from data.corpus import load_corpus
from data.world import FPS
from server.settings import Settings
from tests.app_builder import build_app

SHIPPED = Path(__file__).resolve().parents[2] / "data" / "artefacts" / "models"


def assert_one_entry_per_step(body: dict, frames: int) -> None:
    assert len(body["t"]) == len(body["utterance"]) == len(body["words"]) == frames
    assert body["fps"] == FPS and body["t"][:3] == [0.0, round(1 / FPS, 3), round(2 / FPS, 3)]
    settles = body["settles"]["words"]
    assert [s["word"] for s in settles] == body["words"][-1]
    assert all(0 <= s["step"] < frames and s["t"] == round(s["step"] / FPS, 3) for s in settles)


def test_timeline_of_a_corpus_scene_has_a_step_per_frame_and_ends_on_its_description(
    client: TestClient, settings: Settings
) -> None:
    entry = load_corpus(settings.corpus_path).entries[0]
    body = client.get(f"/api/scenes/{entry.id}/timeline").json()
    assert body["id"] == entry.id and body["model"] == "default" and body["mode"] == "untrained"
    assert_one_entry_per_step(body, len(entry.joints))
    described = client.post(f"/api/scenes/{entry.id}/describe").json()
    assert body["utterance"][-1] == described["utterance"] and body["words"][-1] == described["words"]
    assert body["slots"] == {} and body["settles"]["slots"] == {}  # the paper's linear CAs: no word units
    other = client.get(f"/api/scenes/{entry.id}/timeline", params={"model": "other"}).json()
    assert other["model"] == "other" and len(other["utterance"]) == len(entry.joints)


@pytest.mark.parametrize(
    ("path", "message"),
    [
        ("/api/scenes/nope-0/timeline", "no recording"),
        ("/api/scenes/upload-000000000000/timeline", "no upload"),
        ("/api/scenes/pull-red-apple-0/timeline?model=missing", "no model"),
    ],
)
def test_unknown_recordings_uploads_and_models_are_404(client: TestClient, path: str, message: str) -> None:
    response = client.get(path)
    assert response.status_code == 404 and message in response.json()["detail"]


def test_the_upload_describe_answer_carries_its_timeline(client: TestClient, exported: Exported) -> None:
    path = exported.zip
    body = client.post("/api/describe", files={"recording": (path.name, path.read_bytes())}).json()
    frames = client.get(f"/api/uploads/{body['id']}").json()["frames"]
    timeline = body["timeline"]
    assert timeline["id"] == body["id"] and timeline["model"] == body["model"]
    assert_one_entry_per_step(timeline, frames)
    assert timeline["utterance"][-1] == body["utterance"]
    again = client.get(f"/api/scenes/{body['id']}/timeline").json()  # the scene view's request
    assert again["utterance"] == timeline["utterance"] and again["settles"] == timeline["settles"]


@pytest.fixture(scope="module")
def shipped(settings: Settings, tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    """The app serving the shipped models (default: end_to_end, with word units)."""
    tmp = tmp_path_factory.mktemp("shipped")
    served = dataclasses.replace(settings, models_dir=SHIPPED, run_dir=tmp / "runs", user_dir=tmp / "app")
    with TestClient(build_app(served)) as c:
        yield c


def test_an_end_to_end_timeline_has_each_slots_word_probabilities_per_step(shipped: TestClient) -> None:
    rid = "slide-red-apple-0"  # a recording the shipped default describes right
    body = shipped.get(f"/api/scenes/{rid}/timeline").json()
    frames = len(body["t"])
    assert body["mode"] == "end_to_end" and list(body["slots"]) == ["action", "colour", "shape"]
    assert body["slots"]["action"]["words"] == ["pull", "push", "show me", "slide"]
    for track in body["slots"].values():
        probability = track["probability"]
        assert len(probability) == len(track["words"]) and all(len(p) == frames for p in probability)
        assert all(abs(sum(p[t] for p in probability) - 1) < 1e-3 for t in range(frames))
    described = shipped.post(f"/api/scenes/{rid}/describe").json()
    assert body["utterance"][-1] == described["utterance"]
    slots = body["settles"]["slots"]
    assert [slots[k]["word"] for k in ("action", "colour", "shape")] == ["slide", "red", "apple"]
    action = slots["action"]["step"]  # from then on, the action's word unit wins
    probability = body["slots"]["action"]["probability"]
    slide = body["slots"]["action"]["words"].index("slide")
    assert all(max(range(4), key=lambda k: probability[k][t]) == slide for t in range(action, frames))
