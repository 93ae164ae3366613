"""App jobs: a training job streams epochs, losses and Csc PCA points over SSE, saves a servable
model, can be cancelled, and jobs survive a server restart (unfinished ones marked interrupted)."""

from __future__ import annotations

import json
import signal
import time
from pathlib import Path

import httpx
import pytest
from fastapi import FastAPI
from fastapi.testclient import TestClient

from server.jobs.bounds import MAX_EPOCHS
from server.jobs.manager import JobManager
from server.settings import Settings
from tests.app_builder import JOBS_ROUTERS, build_app, explorer, jobs_settings, serve_jobs_app

TINY = {
    "training.epochs_auditory": 4,
    "training.epochs_somatosensory": 4,
    "training.epochs_visual": 4,
    "training.epochs_assemblies": 4,
    "training.progress_every": 1,
}
ENDLESS = {**TINY, "training.epochs_auditory": MAX_EPOCHS}  # the longest a job may ask for


def _settings(tmp_path: Path, **overrides: object) -> Settings:
    """The jobs-only app's settings with its own folder (models it trains, jobs table, run store)."""
    return jobs_settings(tmp_path, user_dir=tmp_path / "user", **overrides)


def _app(tmp_path: Path, **overrides: object) -> FastAPI:
    return build_app(_settings(tmp_path, **overrides), routers=JOBS_ROUTERS)


def _events(client: TestClient, job_id: str) -> list[dict]:
    out = []
    with client.stream("GET", f"/api/jobs/{job_id}/events") as response:
        assert response.headers["content-type"].startswith("text/event-stream")
        for line in response.iter_lines():
            if line.startswith("data: "):
                out.append(json.loads(line[6:]))
    return out


def _wait(predicate, timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.1)


@pytest.mark.slow
def test_a_training_job_streams_progress_with_csc_points_and_saves_a_model(tmp_path) -> None:
    with TestClient(_app(tmp_path)) as client:
        r = client.post(
            "/api/jobs", json={"kind": "train", "mode": "faithful", "name": "tiny", "overrides": TINY}
        )
        assert r.status_code == 201, r.text
        job_id = r.json()["id"]
        events = _events(client, job_id)
        job = client.get(f"/api/jobs/{job_id}").json()
    assert events[0]["type"] == "snapshot"
    progress = [e for e in events if e["type"] == "progress"]
    stages = {e["stage"] for e in progress}
    assert {"auditory", "somatosensory", "visual"} <= stages
    with_points = [e for e in progress if "points" in e]
    assert with_points and all(len(e["points"]) == len(e["labels"]) == 8 for e in with_points)
    assert all(len(p) == 2 for p in with_points[0]["points"])
    assert events[-1]["type"] == "done" and events[-1]["status"] == "done"
    assert job["status"] == "done" and job["result"]["model"] == "tiny"
    assert set(job["result"]["metrics"]) == {"train", "test", "mixed"}
    assert (tmp_path / "user" / "models" / "tiny" / "meta.json").is_file()
    assert not (tmp_path / "models" / "tiny").exists()  # not beside the shipped models
    from model.checkpoint import load

    model, meta = load(tmp_path / "user" / "models" / "tiny")
    assert meta["metrics"]["test"]["n"] == 8 and len(meta["split"]["train"]) == 8


def test_bad_job_requests_are_refused_with_a_reason(tmp_path) -> None:
    with TestClient(_app(tmp_path)) as client:
        r = client.post("/api/jobs", json={"kind": "train", "mode": "peer"})
        assert r.status_code == 422 and "mode" in r.json()["detail"]
        r = client.post(
            "/api/jobs", json={"kind": "train", "mode": "faithful", "overrides": {"training.nope": 1}}
        )
        assert r.status_code == 422 and "training.nope" in r.json()["detail"]
        assert client.get("/api/jobs/none").status_code == 404
        assert client.get("/api/jobs").json() == []


@pytest.mark.slow
def test_a_running_job_can_be_cancelled(tmp_path) -> None:
    with TestClient(_app(tmp_path)) as client:
        jobs = client.app.state.jobs
        job_id = client.post(
            "/api/jobs", json={"kind": "train", "mode": "faithful", "overrides": ENDLESS}, timeout=30
        ).json()["id"]
        _wait(lambda: (client.get(f"/api/jobs/{job_id}").json().get("progress") or {}).get("epoch", 0) > 2)
        assert client.post(f"/api/jobs/{job_id}/cancel").status_code == 200
        _wait(lambda: client.get(f"/api/jobs/{job_id}").json()["status"] == "cancelled", 30)
        assert not jobs.is_running(job_id)
        assert client.post(f"/api/jobs/{job_id}/cancel").status_code == 409


@pytest.mark.slow
def test_jobs_and_models_survive_a_server_restart_and_the_interrupted_job_is_marked(
    tmp_path, monkeypatch
) -> None:
    monkeypatch.setenv("MTRNN_USER_DIR", str(tmp_path / "user"))
    with serve_jobs_app(tmp_path) as (base, server):
        done_id = httpx.post(
            f"{base}/api/jobs",
            json={"kind": "train", "mode": "faithful", "name": "kept", "overrides": TINY},
            timeout=30,
        ).json()["id"]
        _wait(lambda: httpx.get(f"{base}/api/jobs/{done_id}", timeout=30).json()["status"] == "done", 180)
        live_id = httpx.post(
            f"{base}/api/jobs", json={"kind": "train", "mode": "faithful", "overrides": ENDLESS}, timeout=30
        ).json()["id"]
        _wait(lambda: httpx.get(f"{base}/api/jobs/{live_id}", timeout=30).json()["status"] == "running", 60)
        server.send_signal(signal.SIGKILL)
        server.wait()
    restarted = JobManager(_settings(tmp_path))
    status = {j["id"]: j["status"] for j in restarted.list()}
    restarted.shutdown()
    assert status == {done_id: "done", live_id: "interrupted"}
    assert (tmp_path / "user" / "jobs.sqlite").is_file()
    assert (tmp_path / "user" / "models" / "kept" / "meta.json").is_file()
    assert restarted.get(done_id)["result"]["model"] == "kept"


@pytest.mark.slow
def test_a_trained_model_joins_the_apps_registry_and_can_be_served(tmp_path) -> None:
    """With the whole app: the finished job's model is listed by /api/models and selectable there."""
    settings = explorer(tmp_path / "artefacts", run_dir=tmp_path / "runs", user_dir=tmp_path / "user")
    with TestClient(build_app(settings)) as client:
        r = client.post(
            "/api/jobs", json={"kind": "train", "mode": "faithful", "name": "fresh", "overrides": TINY}
        )
        assert r.status_code == 201, r.text
        events = _events(client, r.json()["id"])
        assert events[-1]["status"] == "done", events[-1]
        models = client.get("/api/models").json()
        assert "fresh" in [m["name"] for m in models["models"]]
        assert client.put("/api/models/selected", json={"name": "fresh"}).json()["selected"] == "fresh"
        assert client.get("/api/health").json()["model"] == "fresh"
