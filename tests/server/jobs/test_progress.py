"""A training job's progress says which attempt a restarting stage is on (end_to_end's generator
restarts from new weights until it says every word combination) and how long the stage has left."""

from __future__ import annotations

from pathlib import Path

from server.jobs.kinds import run_train, validate_train
from tests.app_builder import jobs_settings
from tests.model.tiny_corpus import tiny_corpus

RESTARTING = {
    "options.auditory_epochs": 6,
    "options.auditory_attempts": 2,
    "options.auditory_check_every": 0,  # no early stop: a tiny generator never says them all
    "options.perception_epochs": 4,
    "training.progress_every": 1,
}


def test_progress_of_a_restarted_stage_names_its_attempt_and_has_an_eta(tmp_path: Path) -> None:
    settings = jobs_settings(tmp_path, user_dir=tmp_path / "user")
    params = validate_train(
        {"mode": "end_to_end", "overrides": RESTARTING, "name": "tries"}, "job-1", settings
    )
    events: list[dict] = []
    result = run_train(params, events.append, tiny_corpus(), settings)
    auditory = [e for e in events if e["stage"] == "auditory"]
    assert [(e["attempt"], e["epoch"]) for e in auditory] == [(a, n) for a in (1, 2) for n in range(1, 7)]
    assert {e["attempts"] for e in auditory} == {2}
    perception = [e for e in events if e["stage"] == "perception"]
    assert perception and all("attempt" not in e for e in perception)
    for stage in (auditory[:6], auditory[6:], perception):  # each attempt and stage keeps its own pace
        assert stage[0]["eta"] is None and all(e["eta"] >= 0 for e in stage[1:])
        assert stage[-1]["eta"] == 0
    assert result["model"] == "tries" and (tmp_path / "user" / "models" / "tries" / "meta.json").is_file()
