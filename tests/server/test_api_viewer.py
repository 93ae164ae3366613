"""The 3D viewer in the app: its cursor (REST and WebSocket, finite values only), viser's proxied client
(the camera passes, nothing else) and the 3D view itself (no controls of its own, framed, quiet)."""

from __future__ import annotations

import dataclasses
import json
import logging
import time
from collections.abc import Iterator

import msgspec
import numpy as np
import pytest
from fastapi.testclient import TestClient
from viser import _messages

from data.corpus import load_corpus
from data.nao import forward_kinematics
from server.routes.viewer import MAX_CLIENT_MESSAGE, passes
from server.settings import Settings
from server.viewer import SceneViewer
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


def test_non_finite_values_are_refused_and_playback_survives(
    with_viewer: TestClient, settings: Settings
) -> None:
    rid = load_corpus(settings.corpus_path).entries[0].id
    viewer = with_viewer.app.state.services.viewer
    with_viewer.post("/api/viewer", json={"show": rid, "t": 0.5, "speed": 1.0})
    for body in ('{"t": NaN}', '{"t": Infinity}', '{"speed": NaN}', '{"speed": -Infinity}'):
        r = with_viewer.post("/api/viewer", content=body, headers={"content-type": "application/json"})
        assert r.status_code == 422, body
    for call in (viewer.seek, viewer.set_speed):
        with pytest.raises(ValueError, match="finite"):
            call(float("nan"))
    with with_viewer.websocket_connect("/api/viewer/ws") as ws:
        ws.receive_json()
        ws.send_text('{"t": NaN}')
        assert "finite" in ws.receive_json()["detail"]  # answered, and the socket stays open
        ws.send_text(json.dumps({"t": 0.0, "playing": True}))
        state = ws.receive_json()
        while state["t"] < 0.3:  # the playback thread moves the cursor
            state = ws.receive_json()
    assert viewer.state()["speed"] == 1.0
    with_viewer.post("/api/viewer", json={"playing": False})


def test_the_3d_view_has_no_controls_of_its_own_and_frames_the_scene(
    with_viewer: TestClient, settings: Settings
) -> None:
    viewer = with_viewer.app.state.services.viewer
    assert viewer.server.gui._gui_input_handle_from_uuid == {}  # the page's controls are the only ones
    entry = load_corpus(settings.corpus_path).entries[2]
    with_viewer.post("/api/viewer", json={"show": entry.id})
    camera = viewer.server.initial_camera
    axis = camera.look_at - camera.position
    points = [viewer.table.position, *(h.position for h in viewer.objects.values())]
    points += [h.position for h in viewer.joints]
    for t in np.linspace(0, viewer.state()["duration_s"], 5):
        viewer.seek(float(t))
        points += [h.position for h in viewer.joints]
    for p in points:
        to_p = np.asarray(p) - camera.position
        angle = np.arccos(np.dot(axis, to_p) / np.linalg.norm(axis) / np.linalg.norm(to_p))
        assert angle < 0.8 * camera.fov / 2, p  # inside the view, with a margin


def test_viser_prints_nothing_to_the_console(
    capfd: pytest.CaptureFixture, caplog: pytest.LogCaptureFixture
) -> None:
    with caplog.at_level(logging.INFO):
        viewer = SceneViewer(forward_kinematics)
        viewer.close()
    out, err = capfd.readouterr()
    assert "viser" not in out + err and "http://" not in out + err
    assert str(viewer.port) not in caplog.text  # no second address in the app's log


def _viser_message(message: object) -> bytes:
    return msgspec.msgpack.encode(message.as_serializable_dict())


def test_the_proxy_passes_the_camera_and_drops_everything_else(
    with_viewer: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    server = with_viewer.app.state.services.viewer.server
    shared: list[bool] = []
    monkeypatch.setattr(server, "request_share_url", lambda *a, **k: shared.append(True))
    camera = _messages.ViewerCameraMessage(
        wxyz=(1.0, 0.0, 0.0, 0.0), position=(0.1, 0.2, 0.3), fov=1.0, near=0.01, far=10.0,
        image_height=480, image_width=640, look_at=(0.0, 0.0, 0.0), up_direction=(0.0, 0.0, 1.0),
    )  # fmt: skip
    assert passes(_viser_message(camera))
    hostile = [
        _viser_message(_messages.ShareUrlRequest()),
        _viser_message(_messages.GuiUpdateMessage(uuid="x", updates={"value": float("nan")})),
        b"\xc1 not msgpack",
        msgspec.msgpack.encode(["ViewerCameraMessage"]),
        _viser_message(camera) + b"\0" * MAX_CLIENT_MESSAGE,
    ]
    assert not any(passes(m) for m in hostile)
    with with_viewer.websocket_connect("/viser", subprotocols=["viser-v1.1.1"]) as ws:
        ws.receive_bytes()
        for message in hostile:
            ws.send_bytes(message)
        ws.send_text("text frames are not viser's")
        ws.send_bytes(_viser_message(camera))
        deadline = time.monotonic() + 10
        while not any(np.allclose(c.camera.position, (0.1, 0.2, 0.3)) for c in server.get_clients().values()):
            assert time.monotonic() < deadline, "the camera message did not reach viser"
            time.sleep(0.05)
    assert shared == []  # no share URL (public tunnel) was requested
