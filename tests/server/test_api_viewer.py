"""The 3D viewer in the app: its cursor (REST and WebSocket, finite values only), viser's proxied client
(the camera passes, nothing else), the 3D view itself (no controls of its own, framed, quiet) and its
views (one per page, independent unless shared by id, at most `MAX_VIEWS` live)."""

from __future__ import annotations

import dataclasses
import json
import logging
import time
from collections.abc import Iterator
from contextlib import ExitStack

import msgspec
import numpy as np
import pytest
from fastapi import WebSocketDisconnect
from fastapi.testclient import TestClient
from viser import _messages

from data.corpus import load_corpus
from data.nao import forward_kinematics
from server.routes.viewer import MAX_CLIENT_MESSAGE, passes
from server.services.errors import Unavailable
from server.settings import Settings
from server.viewer import MAX_VIEWS, SceneViewer, ViewerPool
from tests.app_builder import build_app


@pytest.fixture(scope="module")
def with_viewer(settings: Settings) -> Iterator[TestClient]:
    with TestClient(build_app(dataclasses.replace(settings, viser=True))) as c:
        yield c


def test_without_the_viewer_the_cursor_says_so(client: TestClient) -> None:
    assert client.get("/api/viewer").json()["available"] is False
    assert client.post("/api/viewer?view=a", json={"t": 1.0}).status_code == 503


def test_show_seek_play_pause_move_one_cursor(with_viewer: TestClient, settings: Settings) -> None:
    entry = load_corpus(settings.corpus_path).entries[0]
    api = "/api/viewer?view=one"
    body = with_viewer.post(api, json={"show": entry.id, "t": 1.0, "speed": 2.0}).json()
    assert body["source"] == entry.id and body["t"] == pytest.approx(1.0)
    assert body["duration_s"] == pytest.approx((len(entry.joints) - 1) / 20.0)
    assert body["speed"] == 2.0 and body["playing"] is False
    body = with_viewer.post(api, json={"t": 1e6}).json()
    assert body["t"] == pytest.approx(body["duration_s"])  # clamped to the recording
    assert with_viewer.post(api, json={"playing": True}).json()["playing"] is True
    assert with_viewer.post(api, json={"playing": False}).json()["playing"] is False
    assert with_viewer.post(api, json={"show": "nope-0"}).status_code == 404
    viewer = with_viewer.app.state.services.viewer.get("one")
    with_viewer.post(api, json={"t": 0.0})
    hand = tuple(float(v) for v in viewer.joints[-1].position)
    with_viewer.post(api, json={"t": 1.5})
    assert tuple(float(v) for v in viewer.joints[-1].position) != hand  # the arm follows the cursor


def test_cursor_websocket_pushes_changes_and_takes_commands(
    with_viewer: TestClient, settings: Settings
) -> None:
    rid = load_corpus(settings.corpus_path).entries[1].id
    with with_viewer.websocket_connect("/api/viewer/ws?view=ws") as ws:
        assert ws.receive_json()["available"] is True
        ws.send_text(json.dumps({"show": rid, "t": 0.5}))
        state = ws.receive_json()
        while state["source"] != rid or state["t"] != pytest.approx(0.5):
            state = ws.receive_json()
        assert state["playing"] is False


def test_viser_client_is_served_and_its_socket_proxied(with_viewer: TestClient) -> None:
    page = with_viewer.get("/viser/v1/")
    assert page.status_code == 200 and '<div id="root">' in page.text
    with with_viewer.websocket_connect("/viser/v1", subprotocols=["viser-v1.1.1"]) as ws:
        assert ws.accepted_subprotocol == "viser-v1.1.1"
        assert len(ws.receive_bytes()) > 0  # viser's first scene messages


def test_non_finite_values_are_refused_and_playback_survives(
    with_viewer: TestClient, settings: Settings
) -> None:
    rid = load_corpus(settings.corpus_path).entries[0].id
    with_viewer.post("/api/viewer?view=nan", json={"show": rid, "t": 0.5, "speed": 1.0})
    viewer = with_viewer.app.state.services.viewer.get("nan")
    for body in ('{"t": NaN}', '{"t": Infinity}', '{"speed": NaN}', '{"speed": -Infinity}'):
        r = with_viewer.post(
            "/api/viewer?view=nan", content=body, headers={"content-type": "application/json"}
        )
        assert r.status_code == 422, body
    for call in (viewer.seek, viewer.set_speed):
        with pytest.raises(ValueError, match="finite"):
            call(float("nan"))
    with with_viewer.websocket_connect("/api/viewer/ws?view=nan") as ws:
        ws.receive_json()
        ws.send_text('{"t": NaN}')
        assert "finite" in ws.receive_json()["detail"]  # answered, and the socket stays open
        ws.send_text(json.dumps({"t": 0.0, "playing": True}))
        state = ws.receive_json()
        while state["t"] < 0.3:  # the playback thread moves the cursor
            state = ws.receive_json()
    assert viewer.state()["speed"] == 1.0
    with_viewer.post("/api/viewer?view=nan", json={"playing": False})


def test_the_3d_view_has_no_controls_of_its_own_and_frames_the_scene(
    with_viewer: TestClient, settings: Settings
) -> None:
    entry = load_corpus(settings.corpus_path).entries[2]
    with_viewer.post("/api/viewer?view=frame", json={"show": entry.id})
    viewer = with_viewer.app.state.services.viewer.get("frame")
    assert viewer.server.gui._gui_input_handle_from_uuid == {}  # the page's controls are the only ones
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
    with_viewer.post("/api/viewer?view=proxy", json={})
    server = with_viewer.app.state.services.viewer.get("proxy").server
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
    with with_viewer.websocket_connect("/viser/proxy", subprotocols=["viser-v1.1.1"]) as ws:
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


def test_two_views_move_independently(with_viewer: TestClient, settings: Settings) -> None:
    entries = load_corpus(settings.corpus_path).entries
    with_viewer.post("/api/viewer?view=a", json={"show": entries[0].id, "t": 1.0})
    with_viewer.post("/api/viewer?view=b", json={"show": entries[1].id, "t": 0.2})
    a, b = (with_viewer.app.state.services.viewer.get(v) for v in "ab")
    assert a is not b and a.port != b.port  # a viser server each
    hand = tuple(float(v) for v in b.joints[-1].position)
    with_viewer.post("/api/viewer?view=a", json={"t": 2.0, "playing": True, "speed": 4.0})
    state = with_viewer.get("/api/viewer?view=b").json()
    assert state["source"] == entries[1].id and state["t"] == pytest.approx(0.2)
    assert state["playing"] is False and state["speed"] == 1.0
    assert tuple(float(v) for v in b.joints[-1].position) == hand  # b's arm stays
    assert with_viewer.get("/api/viewer?view=a").json()["source"] == entries[0].id
    with_viewer.post("/api/viewer?view=a", json={"playing": False})
    fresh = with_viewer.get("/api/viewer?view=never-seen").json()
    assert fresh["available"] is True and fresh["source"] is None
    assert "never-seen" not in with_viewer.app.state.services.viewer.views()  # a GET starts nothing


def test_the_same_view_id_shares_the_view(with_viewer: TestClient, settings: Settings) -> None:
    rid = load_corpus(settings.corpus_path).entries[3].id
    with (
        with_viewer.websocket_connect("/api/viewer/ws?view=shared") as one,
        with_viewer.websocket_connect("/api/viewer/ws?view=shared") as two,
    ):
        one.receive_json(), two.receive_json()
        one.send_text(json.dumps({"show": rid, "t": 0.7}))
        state = two.receive_json()
        while state["source"] != rid or state["t"] != pytest.approx(0.7):
            state = two.receive_json()
    assert with_viewer.get("/api/viewer?view=shared").json()["t"] == pytest.approx(0.7)


def test_view_ids_are_checked(with_viewer: TestClient) -> None:
    for view in ("a/b", "x" * 33, "", "a%20b"):
        assert with_viewer.post(f"/api/viewer?view={view}", json={}).status_code == 422, view
    assert with_viewer.post("/api/viewer", json={}).status_code == 422  # no view, no shared default
    assert with_viewer.get("/viser/a!b/").status_code == 422
    with with_viewer.websocket_connect("/api/viewer/ws") as ws:
        assert "?view=" in ws.receive_json()["detail"]


def test_a_ninth_view_replaces_an_idle_one_or_is_refused(with_viewer: TestClient) -> None:
    pool = with_viewer.app.state.services.viewer
    with ExitStack() as stack:
        held = [f"held{k}" for k in range(MAX_VIEWS)]
        for view in held:
            ws = stack.enter_context(with_viewer.websocket_connect(f"/api/viewer/ws?view={view}"))
            assert ws.receive_json()["available"] is True
        assert sorted(pool.views()) == sorted(held)  # the idle views were replaced
        busy = with_viewer.post("/api/viewer?view=ninth", json={})
        assert busy.status_code == 503 and "in use" in busy.json()["detail"]
        with with_viewer.websocket_connect("/api/viewer/ws?view=ninth") as ws:
            assert "in use" in ws.receive_json()["detail"]
        with pytest.raises(WebSocketDisconnect) as refused:  # the proxy refuses the upgrade
            with_viewer.websocket_connect("/viser/ninth", subprotocols=["viser-v1.1.1"]).__enter__()
        assert refused.value.code == 1013  # try again later
        assert len(pool.views()) == MAX_VIEWS
    assert with_viewer.post("/api/viewer?view=ninth", json={}).status_code == 200
    assert len(pool.views()) == MAX_VIEWS and "ninth" in pool.views() and "held0" not in pool.views()


def test_the_pool_replaces_the_least_recently_used_view() -> None:
    pool = ViewerPool(forward_kinematics, size=2)
    try:
        for view in ("a", "b", "a"):
            pool.acquire(view)
            pool.release(view)
        evicted = pool.get("b")
        pool.acquire("c")
        assert pool.views() == ["a", "c"] and evicted._stop.is_set()  # b's playback and viser stopped
        pool.acquire("a")
        with pytest.raises(Unavailable, match="in use"):
            pool.acquire("d")  # a and c are held
    finally:
        pool.close()
