"""App jobs on the protocol's other splits: `split` (and the size split's `train_scenes`) checked
before a job is queued (422 naming the problem), and a real training job on held-out objects."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from model.experiments.runstore import RunStore
from tests.app_builder import JOBS_ROUTERS, build_app, jobs_settings

SQUARE_DATA = "tests.model.experiments.square_data:square_sequence_set"  # a full colour x shape grid
TINY = {
    "training.epochs_auditory": 3,
    "training.epochs_somatosensory": 2,
    "training.epochs_visual": 2,
    "training.epochs_assemblies": 2,
    "training.progress_every": 1,
}


def _events(client: TestClient, job_id: str) -> list[dict]:
    with client.stream("GET", f"/api/jobs/{job_id}/events") as response:
        return [json.loads(line[6:]) for line in response.iter_lines() if line.startswith("data: ")]


@pytest.mark.parametrize(
    ("body", "says"),
    [
        ({"kind": "train", "mode": "faithful", "split": "colours"}, "split"),
        ({"kind": "train", "mode": "faithful", "split": "objects", "fold": 4}, "got fold 4"),
        ({"kind": "evaluate", "mode": "peer", "split": "action-object", "folds": 5}, "at most 4 folds"),
        ({"kind": "evaluate", "mode": "peer", "split": "size"}, "the size split needs train_scenes"),
        ({"kind": "train", "mode": "faithful", "split": "size", "train_scenes": 49}, "train_scenes"),
        ({"kind": "train", "mode": "faithful", "split": "size", "train_scenes": 0}, "train_scenes"),
        ({"kind": "train", "mode": "faithful", "train_scenes": 8}, "train_scenes is the size split's"),
    ],
)
def test_a_job_on_a_split_it_cannot_run_is_refused_before_it_is_queued(tmp_path: Path, body, says) -> None:
    settings = jobs_settings(tmp_path, user_dir=tmp_path / "user", max_jobs=0)
    with TestClient(build_app(settings, routers=JOBS_ROUTERS)) as client:
        r = client.post("/api/jobs", json=body)
        assert r.status_code == 422, r.text
        assert says in json.dumps(r.json()["detail"])
        assert client.get("/api/jobs").json() == []


@pytest.mark.slow
def test_a_training_job_on_the_objects_split_never_sees_the_held_out_objects(tmp_path: Path) -> None:
    settings = jobs_settings(tmp_path, user_dir=tmp_path / "user", job_data=SQUARE_DATA)
    with TestClient(build_app(settings, routers=JOBS_ROUTERS)) as client:
        body = {"kind": "train", "mode": "faithful", "split": "objects", "fold": 2, "overrides": TINY}
        r = client.post("/api/jobs", json=body)
        assert r.status_code == 201, r.text
        events = _events(client, r.json()["id"])
        job = client.get(f"/api/jobs/{r.json()['id']}").json()
        evaluation = client.post(
            "/api/jobs",
            json={"kind": "evaluate", "mode": "faithful", "split": "objects", "folds": 1, "overrides": TINY},
        ).json()
        assert _events(client, evaluation["id"])[-1]["type"] == "done"
    assert events[-1]["type"] == "done", events[-1]
    assert job["result"]["model"].startswith("faithful-objects-f2-s0-")
    assert job["result"]["metrics"]["test"]["n"] == 4 and job["result"]["metrics"]["train"]["n"] == 12
    meta = json.loads((tmp_path / "user" / "models" / job["result"]["model"] / "meta.json").read_text())
    assert meta["split_kind"] == "objects" and meta["fold"] == 2
    held = {" ".join(rid.split("-")[-3:-1]) for rid in meta["split"]["test"]}
    assert held == {"blue dice", "green phone", "red apple", "yellow banana"}  # fold 2's Latin square
    assert not held & {" ".join(rid.split("-")[-3:-1]) for rid in meta["split"]["train"]}
    (run,) = RunStore(tmp_path / "user" / "runs").runs()
    assert run.split == "objects" and run.metrics["test"]["n"] == 4
