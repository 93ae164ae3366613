"""A job's process lives as long as the server, whichever thread asked for it: it outlives the
(short-lived) thread that started it, and dies when the server is killed. An open event stream
does not hold the server's shutdown."""

from __future__ import annotations

import signal
import subprocess
import threading
import time
from collections.abc import Callable
from pathlib import Path

import httpx
import pytest

from server.jobs.bounds import MAX_EPOCHS
from server.jobs.manager import JobManager
from server.jobs.store import JobStore
from tests.app_builder import jobs_settings, serve_jobs_app

pytestmark = pytest.mark.slow
LONG = {
    "training.epochs_auditory": MAX_EPOCHS,  # the longest a job may ask for: it runs while we look
    "training.progress_every": 1,
}


def _wait(predicate: Callable[[], object], timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.1)


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except FileNotFoundError:
        return False
    return state not in ("Z", "X")  # a zombie has died


def _job_children(server: int) -> list[int]:
    """The server's child processes that run jobs (not multiprocessing's resource tracker)."""
    pids = []
    for task in Path(f"/proc/{server}/task").iterdir():
        for pid in (task / "children").read_text().split():
            cmdline = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ")
            if b"spawn_main" in cmdline:
                pids.append(int(pid))
    return pids


def test_a_job_started_from_a_short_lived_thread_outlives_that_thread(tmp_path: Path) -> None:
    manager = JobManager(jobs_settings(tmp_path, user_dir=tmp_path / "user"))
    started: list[dict] = []
    try:
        asker = threading.Thread(
            target=lambda: started.append(manager.start("train", {"mode": "faithful", "overrides": LONG}))
        )
        asker.start()
        asker.join()  # the thread that asked for the job has ended
        job_id = started[0]["id"]
        _wait(lambda: (manager.get(job_id)["progress"] or {}).get("epoch", 0) > 2)
        pid = manager.process_id(job_id)
        epoch = manager.get(job_id)["progress"]["epoch"]
        time.sleep(2.0)
        assert pid is not None and _alive(pid) and manager.is_running(job_id)
        _wait(lambda: manager.get(job_id)["progress"]["epoch"] > epoch, 30)  # still training
    finally:
        manager.shutdown()
    _wait(lambda: not _alive(pid), 30)


def _start_long_job(base: str) -> str:
    job = httpx.post(
        f"{base}/api/jobs", json={"kind": "train", "mode": "faithful", "overrides": LONG}, timeout=30
    )
    job_id = job.json()["id"]
    _wait(
        lambda: (
            (httpx.get(f"{base}/api/jobs/{job_id}", timeout=30).json().get("progress") or {}).get("epoch", 0)
            > 1
        )
    )
    return job_id


def test_killing_the_server_kills_its_jobs_process(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MTRNN_USER_DIR", str(tmp_path / "user"))
    with serve_jobs_app(tmp_path) as (base, server):
        _start_long_job(base)
        children = _job_children(server.pid)
        assert len(children) == 1 and _alive(children[0])
        server.send_signal(signal.SIGKILL)
        server.wait()
    _wait(lambda: not _alive(children[0]), 30)


def test_an_open_event_stream_does_not_hold_the_shutdown(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("MTRNN_USER_DIR", str(tmp_path / "user"))
    lines: list[str] = []
    with serve_jobs_app(tmp_path) as (base, server):
        job_id = _start_long_job(base)
        children = _job_children(server.pid)

        def listen() -> None:
            with httpx.stream("GET", f"{base}/api/jobs/{job_id}/events", timeout=None) as response:
                lines.extend(response.iter_lines())

        listener = threading.Thread(target=listen, daemon=True)
        listener.start()
        _wait(lambda: any(line.startswith("event: progress") for line in lines), 60)
        started = time.monotonic()
        server.terminate()  # SIGTERM: a graceful shutdown
        try:
            server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            pytest.fail("the server did not stop while an event stream was open")
        assert time.monotonic() - started < 20
    listener.join(timeout=10)
    assert not listener.is_alive()  # the stream ended with the server
    assert {j["id"]: j["status"] for j in JobStore(tmp_path / "user").jobs()} == {job_id: "interrupted"}
    _wait(lambda: not any(_alive(pid) for pid in children), 30)
