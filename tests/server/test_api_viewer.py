"""The 3D viewer in the app: its shared cursor (REST and WebSocket) and viser's proxied client."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient

from data.corpus import load_corpus
from server.settings import Settings
from tests.app_builder import build_app


@pytest.fixture(scope="module")
def with_viewer(settings: Settings) -> Iterator[TestClient]:
    with TestClient(build_app(dataclasses.replace(settings, viser=True))) as c:
        yield c


def test_without_the_viewer_the_cursor_says_so(client: TestClient) -> None:
    assert client.get("/api/viewer").json()["available"] is False
    assert client.post("/api/viewer", json={"t": 1.0}).status_code == 503


def test_show_seek_play_pause_move_one_cursor(with_viewer: TestClient, settings: Settings) -> None:
    entry = load_corpus(settings.corpus_path).entries[0]
    body = with_viewer.post("/api/viewer", json={"show": entry.id, "t": 1.0, "speed": 2.0}).json()
    assert body["source"] == entry.id and body["t"] == pytest.approx(1.0)
    assert body["duration_s"] == pytest.approx((len(entry.joints) - 1) / 20.0)
    assert body["speed"] == 2.0 and body["playing"] is False
    body = with_viewer.post("/api/viewer", json={"t": 1e6}).json()
    assert body["t"] == pytest.approx(body["duration_s"])  # clamped to the recording
    assert with_viewer.post("/api/viewer", json={"playing": True}).json()["playing"] is True
    assert with_viewer.post("/api/viewer", json={"playing": False}).json()["playing"] is False
    assert with_viewer.post("/api/viewer", json={"show": "nope-0"}).status_code == 404
    viewer = with_viewer.app.state.services.viewer
    with_viewer.post("/api/viewer", json={"t": 0.0})
    hand = tuple(float(v) for v in viewer.joints[-1].position)
    with_viewer.post("/api/viewer", json={"t": 1.5})
    assert tuple(float(v) for v in viewer.joints[-1].position) != hand  # the arm follows the cursor


def test_cursor_websocket_pushes_changes_and_takes_commands(
    with_viewer: TestClient, settings: Settings
) -> None:
    rid = load_corpus(settings.corpus_path).entries[1].id
    with with_viewer.websocket_connect("/api/viewer/ws") as ws:
        assert ws.receive_json()["available"] is True
        ws.send_text(json.dumps({"show": rid, "t": 0.5}))
        state = ws.receive_json()
        while state["source"] != rid or state["t"] != pytest.approx(0.5):
            state = ws.receive_json()
        assert state["playing"] is False


def test_viser_client_is_served_and_its_socket_proxied(with_viewer: TestClient) -> None:
    page = with_viewer.get("/viser/")
    assert page.status_code == 200 and '<div id="root">' in page.text
    with with_viewer.websocket_connect("/viser", subprotocols=["viser-v1.1.1"]) as ws:
        assert ws.accepted_subprotocol == "viser-v1.1.1"
        assert len(ws.receive_bytes()) > 0  # viser's first scene messages
