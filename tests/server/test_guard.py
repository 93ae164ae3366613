"""The request guard (server.guard): own Host names, own Origin, the access token, the JSON size limit;
and how `mtrnn serve` bounds its connections (server.connections, server.commands.serve)."""

from __future__ import annotations

import argparse
import dataclasses
import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import uvicorn
from fastapi import FastAPI
from fastapi.testclient import TestClient
from starlette.websockets import WebSocketDisconnect

from server import connections
from server.commands import serve
from server.guard import allowed_hosts, cookie_name, host_name, is_loopback
from server.settings import Settings
from server.viewer import free_port
from tests.app_builder import JOBS_ROUTERS, build_app, jobs_settings, wait_until_up

OWN = "http://testserver"
EVIL = "http://evil.example"
TOKEN = "s3cret-token"


def _jobs_app(root: Path, **overrides: object) -> FastAPI:
    return build_app(jobs_settings(root, **overrides), routers=JOBS_ROUTERS)


@pytest.fixture()
def jobs_client(tmp_path: Path) -> Iterator[TestClient]:
    with TestClient(_jobs_app(tmp_path)) as c:
        yield c


@pytest.fixture()
def token_client(tmp_path: Path) -> Iterator[TestClient]:
    with TestClient(_jobs_app(tmp_path, token=TOKEN), follow_redirects=False) as c:
        yield c


def test_host_names_other_than_the_apps_own_get_400(jobs_client: TestClient) -> None:
    for host in ("evil.example", "evil.example:8000", "127.0.0.1.evil.example", ""):
        r = jobs_client.get("/api/jobs", headers={"host": host})
        assert r.status_code == 400, host
        assert "MTRNN_ALLOWED_HOSTS" in r.json()["detail"]
    for host in ("127.0.0.1:8000", "localhost", "LOCALHOST:1234", "[::1]:8000"):
        assert jobs_client.get("/api/jobs", headers={"host": host}).status_code == 200, host


def test_allowed_hosts_add_the_bound_address_and_are_configurable() -> None:
    assert allowed_hosts(Settings()) == {"127.0.0.1", "localhost", "::1"}
    assert "192.168.1.7" in allowed_hosts(Settings(host="192.168.1.7"))
    assert socket.gethostname().lower() in allowed_hosts(Settings(host="0.0.0.0"))
    assert allowed_hosts(Settings(allowed_hosts=("explorer.lab",))) == {"explorer.lab", "127.0.0.1"}
    assert host_name("[::1]:8000") == "::1" and host_name("Example.org:80") == "example.org"
    assert is_loopback("127.0.0.5") and is_loopback("::1") and is_loopback("localhost")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.168.1.7")


def test_a_cross_origin_form_post_to_describe_does_not_run(client: TestClient, exported) -> None:  # noqa: ANN001
    files = {"recording": (exported.zip.name, exported.zip.read_bytes())}
    for header in ({"origin": EVIL}, {"referer": f"{EVIL}/form.html"}, {"origin": "null"}):
        r = client.post("/api/describe", files=files, headers=header)
        assert r.status_code == 403, header
        assert "another origin" in r.json()["detail"]
    assert client.post("/api/describe", files=files, headers={"origin": OWN}).status_code == 200
    assert client.post("/api/describe", files=files).status_code == 200  # curl: no Origin


def test_a_cross_origin_job_start_or_cancel_is_refused(jobs_client: TestClient) -> None:
    body = {"kind": "train", "mode": "faithful", "name": "x"}
    assert jobs_client.post("/api/jobs", json=body, headers={"origin": EVIL}).status_code == 403
    assert jobs_client.post("/api/jobs/nope/cancel", headers={"origin": EVIL}).status_code == 403
    assert jobs_client.get("/api/jobs").json() == []  # nothing started
    # the app's own page, and a script without Origin, reach the route (404: no such job)
    assert jobs_client.post("/api/jobs/nope/cancel", headers={"origin": OWN}).status_code == 404
    assert jobs_client.post("/api/jobs/nope/cancel").status_code == 404
    assert jobs_client.get("/api/jobs", headers={"origin": EVIL}).status_code == 200  # reading is no change


def test_websockets_of_another_origin_are_refused(client: TestClient) -> None:
    with (
        pytest.raises(WebSocketDisconnect) as refused,
        client.websocket_connect("/api/viewer/ws", headers={"origin": EVIL}),
    ):
        pass
    assert refused.value.code == 1008
    with client.websocket_connect("/api/viewer/ws", headers={"origin": OWN}) as ws:
        assert ws.receive_json()["available"] is False


def test_json_bodies_over_the_limit_get_413_before_parsing(tmp_path: Path) -> None:
    with TestClient(_jobs_app(tmp_path, max_json_bytes=1000)) as c:
        big = b'{"kind": "train", "name": "' + b"x" * 2000 + b'"}'
        r = c.post("/api/jobs", content=big, headers={"content-type": "application/json"})
        assert r.status_code == 413 and "1,000 bytes" in r.json()["detail"]

        def chunked() -> Iterator[bytes]:  # no Content-Length: counted while received
            yield big[:600]
            yield big[600:]

        assert c.post("/api/jobs", content=chunked()).status_code == 413
        assert c.post("/api/jobs", json={"kind": "nope"}).status_code == 422  # small: parsed by the route
        assert c.get("/api/jobs").status_code == 200


def test_with_a_token_every_request_needs_it(token_client: TestClient) -> None:
    c = token_client
    r = c.get("/api/jobs")
    assert r.status_code == 401 and "?token=" in r.json()["detail"]
    assert c.get("/", headers={"authorization": "Bearer wrong"}).status_code == 401
    assert c.get("/api/jobs", headers={"authorization": f"Bearer {TOKEN}"}).status_code == 200
    assert c.get("/api/jobs", params={"token": "wrong"}).status_code == 401
    with pytest.raises(WebSocketDisconnect), c.websocket_connect("/api/viewer/ws"):
        pass


def test_the_token_in_the_url_becomes_a_strict_cookie_and_a_clean_url(token_client: TestClient) -> None:
    c = token_client
    r = c.get("/", params={"token": TOKEN, "x": "1"})
    assert r.status_code == 303 and r.headers["location"] == "/?x=1"
    cookie = r.headers["set-cookie"]
    assert cookie.startswith(f"{cookie_name(Settings())}={TOKEN};")
    assert "HttpOnly" in cookie and "SameSite=Strict" in cookie and "Path=/" in cookie
    assert c.get("/api/jobs").status_code == 200  # the client now sends the cookie
    assert c.post("/api/jobs/nope/cancel", headers={"origin": OWN}).status_code == 404
    assert c.get("/index.html").status_code == 200


def test_serve_refuses_a_non_loopback_address_without_a_token(
    capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("MTRNN_TOKEN", raising=False)
    args = argparse.Namespace(host="0.0.0.0", port=None, model=None, no_viewer=True, token=None)
    assert serve.run(args) == 2
    message = capsys.readouterr().err
    assert "--token" in message and "MTRNN_TOKEN" in message
    assert serve.url_of("0.0.0.0", 8000, "abc") == "http://localhost:8000/?token=abc"
    assert serve.url_of("127.0.0.1", 8000, None) == "http://localhost:8000/"


def test_serve_runs_uvicorn_with_its_limits() -> None:
    config = connections.uvicorn_config(FastAPI(), Settings(port=8123))
    assert config.limit_concurrency == connections.MAX_CONNECTIONS
    assert config.timeout_keep_alive == connections.KEEP_ALIVE_S
    assert config.h11_max_incomplete_event_size == connections.MAX_HEADER_BYTES
    assert config.timeout_graceful_shutdown == connections.GRACEFUL_SHUTDOWN_S
    assert config.http is connections.DeadlineH11Protocol


def _closed_within(port: int, payload: bytes, seconds: float) -> bool:
    """Whether the server closes a connection that sent `payload` and then nothing."""
    with socket.create_connection(("127.0.0.1", port)) as s:
        s.sendall(payload)
        s.settimeout(seconds)
        try:
            while s.recv(4096):
                pass
        except TimeoutError:
            return False
        return True


def test_slow_headers_and_bodies_are_cut_off(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(connections, "HEADER_TIMEOUT_S", 0.5)
    monkeypatch.setattr(connections, "BODY_TIMEOUT_S", 0.5)
    monkeypatch.setattr(connections, "KEEP_ALIVE_S", 30)
    port = free_port()
    settings = dataclasses.replace(jobs_settings(tmp_path), port=port)
    server = uvicorn.Server(connections.uvicorn_config(_jobs_app(tmp_path), settings))
    server.config.log_level = "warning"
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    try:
        wait_until_up(f"http://127.0.0.1:{port}/api/jobs", 30, thread.is_alive)
        start = time.monotonic()
        assert _closed_within(port, b"GET /api/jobs HTTP/1.1\r\nHost: localhost\r\n", 5.0)
        assert time.monotonic() - start < 3.0
        body_started = b"POST /api/jobs HTTP/1.1\r\nHost: localhost\r\nContent-Length: 100\r\n\r\n{"
        assert _closed_within(port, body_started, 5.0)
        assert _closed_within(port, b"", 5.0)  # connected, sent nothing
    finally:
        server.should_exit = True
        thread.join(timeout=10)
