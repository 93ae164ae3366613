"""Browser: lesson 7's objects panel. With a model trained on a fold of the objects split it draws
the grid of that fold's held-out objects (titled, axes labelled) and the words said for them; for a
fold without one it says so and offers the training job, whose request it posts through the job API."""

from __future__ import annotations

import json
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.app_builder import build_app, lesson_world, serve_in_thread

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "server"))
from test_generalising_objects import _save_objects_model  # noqa: E402

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def base_url(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """The synthetic lesson world with one (untrained) model of fold 1 of the objects split."""
    settings, load = lesson_world(tmp_path_factory.mktemp("objects-world"))
    _save_objects_model(settings.user_dir, 1)
    with serve_in_thread(build_app(settings, load)) as url:
        yield url


def test_the_objects_panel_shows_a_folds_held_out_objects_or_offers_to_train_a_model(page) -> None:  # noqa: ANN001
    page.goto("/#/lessons?lesson=generalising&ofold=1")
    page.wait_for_selector("#objects-words tbody tr")
    assert page.locator("#objects-words tbody tr").count() == 4
    titles = page.evaluate(
        "(() => { const l = document.getElementById('objects-grid').layout;"
        " return [l.title.text, l.xaxis.title.text, l.yaxis.title.text]; })()"
    )
    assert "objects-1 (fold 1)" in titles[0] and titles[1:] == ["shape", "colour"]
    assert page.locator("#objects-train").is_hidden()
    posted: list[dict] = []

    def job(route) -> None:  # noqa: ANN001 - the lesson's request, answered as a job that failed at once
        posted.append(json.loads(route.request.post_data))
        route.fulfill(status=201, json={"id": "j1", "status": "queued", "position": 1})

    page.route("**/api/jobs", job)
    page.route(
        "**/api/jobs/j1", lambda r: r.fulfill(json={"id": "j1", "status": "failed", "error": "stopped"})
    )
    page.focus("#objects-fold")
    page.keyboard.press("ArrowUp")  # fold 0: no model of the app was trained on it
    page.wait_for_selector("#objects-train:not([hidden])")
    assert "No model" in page.inner_text("#objects-status") and "ofold=0" in page.url
    page.focus("#objects-train")
    page.keyboard.press("Enter")
    page.wait_for_selector("#objects-status .error, #objects-status [role=alert]")
    assert posted == [
        {"kind": "train", "mode": "end_to_end", "split": "objects", "fold": 0, "preset": "quick"}
    ]
    assert "failed" in page.inner_text("#objects-status")
    assert not page.errors
