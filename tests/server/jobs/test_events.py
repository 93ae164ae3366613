"""What job events carry to a client: strict, finite JSON (NaN and infinities as null, in the SSE
stream and in the REST answers) and errors without paths or tracebacks (those go to the log)."""

from __future__ import annotations

import json
import logging
import math
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient

from server.jobs.events import finite, public_error, sse
from server.settings import DEFAULT_JOB_DATA
from tests.app_builder import JOBS_ROUTERS, build_app, jobs_settings


def _strict(text: str) -> object:
    def refuse(token: str) -> None:
        raise ValueError(f"not JSON: {token}")

    return json.loads(text, parse_constant=refuse)


def test_non_finite_numbers_become_null_everywhere() -> None:
    event = {"loss": math.nan, "points": [[math.inf, 1.0]], "eta": np.float32("-inf"), "n": np.int64(3)}
    assert finite(event) == {"loss": None, "points": [[None, 1.0]], "eta": None, "n": 3}
    message = sse({"type": "progress", **event})
    assert message.startswith("event: progress\ndata: ") and message.endswith("\n\n")
    assert _strict(message.split("data: ", 1)[1])["loss"] is None


def test_an_error_message_keeps_no_absolute_path() -> None:
    err = FileNotFoundError(2, "No such file or directory", "/home/someone/secret/corpus.npz")
    text = public_error(err)
    assert text.startswith("FileNotFoundError:") and "corpus.npz" in text
    assert "/home" not in text and "secret" not in text
    assert len(public_error(ValueError("x" * 5000))) <= 500


def test_a_stored_nan_progress_is_answered_as_null(tmp_path: Path) -> None:
    settings = jobs_settings(tmp_path, user_dir=tmp_path / "user", max_jobs=0)
    with TestClient(build_app(settings, routers=JOBS_ROUTERS)) as client:
        job_id = client.post("/api/jobs", json={"kind": "train", "mode": "faithful"}).json()["id"]
        client.app.state.jobs.store.update(job_id, progress={"type": "progress", "loss": math.nan})
        r = client.get(f"/api/jobs/{job_id}")
        assert r.status_code == 200 and _strict(r.text)["progress"]["loss"] is None
        assert client.get("/api/jobs").status_code == 200


@pytest.mark.slow
def test_a_failed_job_says_what_failed_without_paths_and_logs_the_traceback(tmp_path: Path, caplog) -> None:  # noqa: ANN001
    missing = tmp_path / "nowhere" / "corpus.npz"  # the job's data cannot be loaded
    settings = jobs_settings(
        tmp_path, user_dir=tmp_path / "user", job_data=DEFAULT_JOB_DATA, corpus_path=missing
    )
    caplog.set_level(logging.ERROR, logger="server.jobs.manager")
    with TestClient(build_app(settings, routers=JOBS_ROUTERS)) as client:
        job_id = client.post(
            "/api/jobs", json={"kind": "train", "mode": "faithful", "preset": "quick"}
        ).json()["id"]
        with client.stream("GET", f"/api/jobs/{job_id}/events") as response:
            events = [_strict(line[6:]) for line in response.iter_lines() if line.startswith("data: ")]
        job = client.get(f"/api/jobs/{job_id}").json()
    assert events[-1]["type"] == "error" and job["status"] == "failed"
    for error in (events[-1]["error"], job["error"]):
        assert str(tmp_path) not in error and "Traceback" not in error and "corpus.npz" in error
    logged = "\n".join(r.getMessage() for r in caplog.records)
    assert "Traceback" in logged and job_id in logged
