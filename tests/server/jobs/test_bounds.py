"""Job parameters are bounded before a job is queued: every number, every override key (the mode's
own settings) and value (its documented range), and the model's name (pattern, free): 422 naming
the field, 409 for a taken name. These jobs never start: the queue is paused (max_jobs = 0)."""

from __future__ import annotations

from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from server.jobs.bounds import check_overrides, overridable
from server.services.errors import Invalid
from server.settings import CORES
from tests.app_builder import JOBS_ROUTERS, build_app, jobs_settings

TRAIN = {"kind": "train", "mode": "end_to_end"}
EVALUATE = {"kind": "evaluate", "mode": "peer"}


@pytest.fixture()
def client(tmp_path: Path):  # noqa: ANN201
    settings = jobs_settings(tmp_path, user_dir=tmp_path / "user", max_jobs=0)  # queued, never started
    with TestClient(build_app(settings, routers=JOBS_ROUTERS)) as c:
        yield c


def _refused(client: TestClient, body: dict, status: int = 422) -> str:
    r = client.post("/api/jobs", json=body)
    assert r.status_code == status, r.text
    detail = r.json()["detail"]
    if isinstance(detail, str):
        return detail
    return "; ".join(f"{'.'.join(map(str, d['loc']))}: {d['msg']}" for d in detail)  # pydantic's


@pytest.mark.parametrize(
    ("body", "named"),
    [
        ({**TRAIN, "overrides": {"options.auditory_epochs": 1e9}}, "options.auditory_epochs"),
        ({**TRAIN, "mode": "faithful", "overrides": {"training.epochs_auditory": 1e9}}, "epochs_auditory"),
        ({**TRAIN, "overrides": {"auditory.cf": 100_000}}, "auditory.cf"),
        ({**EVALUATE, "overrides": {"hidden": 100_000}}, "hidden"),
        ({**EVALUATE, "overrides": {"epochs": 0}}, "epochs"),
        ({**TRAIN, "overrides": {"training.threads": CORES + 1}}, "training.threads"),
        ({**TRAIN, "overrides": {"training.lr": "fast"}}, "training.lr"),
        ({**TRAIN, "overrides": {"options.word_loss": 1}}, "options.word_loss"),
        ({**TRAIN, "overrides": {"auditory.io": 3}}, "auditory.io"),  # fixed by the encodings
        ({**TRAIN, "overrides": {"generation_steps": 9}}, "generation_steps"),
        ({**TRAIN, "overrides": {"training.epochs_auditory": 10}}, "options.auditory_epochs"),  # ignored
        ({**TRAIN, "overrides": {"auditory.csc": 200}}, "Csc"),  # |Csc| <= |Cs|
        ({**TRAIN, "overrides": {"options.recombine": 1, "options.slot_softmax": False}}, "recombine"),
        ({**TRAIN, "overrides": {f"k{i}": 1 for i in range(65)}}, "overrides"),
        ({**EVALUATE, "workers": CORES + 1}, "workers"),
        ({**EVALUATE, "folds": 11}, "folds"),
        ({**EVALUATE, "inits": 0}, "inits"),
        ({**TRAIN, "seed": 10**12}, "seed"),
        ({**TRAIN, "fold": -1}, "fold"),
        ({**TRAIN, "name": "x" * 300}, "name"),
        ({**TRAIN, "name": "My_Model"}, "name"),
        ({**TRAIN, "name": ""}, "name"),
        ({**TRAIN, "preset": "instant"}, "preset"),
    ],
)
def test_out_of_bounds_parameters_are_refused_naming_the_field(
    client: TestClient, body: dict, named: str
) -> None:
    assert named in _refused(client, body)
    assert client.get("/api/jobs").json() == []  # nothing was queued


def test_a_name_taken_by_a_shipped_model_an_app_model_or_an_unfinished_job_is_a_conflict(
    client: TestClient, tmp_path: Path
) -> None:
    (tmp_path / "models" / "shipped").mkdir(parents=True)
    (tmp_path / "user" / "models" / "mine").mkdir(parents=True)
    assert "shipped model" in _refused(client, {**TRAIN, "name": "shipped"}, 409)
    assert "a model" in _refused(client, {**TRAIN, "name": "mine"}, 409)
    first = client.post("/api/jobs", json={**TRAIN, "name": "wanted"})
    assert first.status_code == 201 and first.json()["status"] == "queued"
    assert "unfinished job" in _refused(client, {**TRAIN, "name": "wanted"}, 409)
    assert client.post(f"/api/jobs/{first.json()['id']}/cancel").json()["status"] == "cancelled"
    assert client.post("/api/jobs", json={**TRAIN, "name": "wanted"}).status_code == 201  # free again


def test_jobs_beyond_max_jobs_wait_in_the_queue_with_their_position(client: TestClient) -> None:
    ids = [client.post("/api/jobs", json={**TRAIN, "seed": s}).json()["id"] for s in range(3)]
    assert [client.get(f"/api/jobs/{i}").json()["position"] for i in ids] == [1, 2, 3]
    assert client.post(f"/api/jobs/{ids[0]}/cancel").status_code == 200
    jobs = {j["id"]: j for j in client.get("/api/jobs").json()}
    assert jobs[ids[0]]["status"] == "cancelled" and jobs[ids[0]].get("position") is None
    assert [jobs[i]["position"] for i in ids[1:]] == [1, 2]
    assert client.post(f"/api/jobs/{ids[0]}/cancel").status_code == 409  # neither queued nor running


def test_a_default_model_name_follows_the_pattern(client: TestClient) -> None:
    job = client.post("/api/jobs", json=TRAIN).json()
    assert job["params"]["name"].startswith("end-to-end-f0-s0-")


def test_every_overridable_key_has_a_documented_range() -> None:
    schema = build_app(jobs_settings(Path("/nonexistent")), routers=JOBS_ROUTERS).openapi()
    described = schema["components"]["schemas"]["JobRequest"]["properties"]["overrides"]["description"]
    for mode in ("faithful", "end_to_end", "peer"):
        for key in overridable(mode):
            assert key.rsplit(".", 1)[-1] in described


def test_values_in_range_are_applied_to_the_modes_config() -> None:
    config = check_overrides("end_to_end", {"options.auditory_epochs": 300, "training.lr": 1})
    assert config["options"]["auditory_epochs"] == 300 and config["training"]["lr"] == 1.0
    assert check_overrides("peer", {"epochs": 20.0})["epochs"] == 20
    with pytest.raises(Invalid, match="integer"):
        check_overrides("peer", {"epochs": 2.5})
