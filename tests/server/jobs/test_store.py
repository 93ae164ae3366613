"""The jobs table (server.jobs.store): jobs outlive the server, and unfinished ones are marked."""

from server.jobs.store import JobStore


def test_jobs_active_at_a_restart_are_marked_interrupted(tmp_path) -> None:
    store = JobStore(tmp_path)
    store.put("j1", "train", {"mode": "faithful"}, "running")
    store.put("j2", "train", {"mode": "faithful"}, "done")
    store.update("j1", progress={"epoch": 3})
    reopened = JobStore(tmp_path)
    assert reopened.mark_interrupted(("queued", "running")) == ["j1"]
    jobs = {j["id"]: j for j in reopened.jobs()}
    assert jobs["j1"]["status"] == "interrupted" and jobs["j1"]["progress"] == {"epoch": 3}
    assert jobs["j2"]["status"] == "done"
