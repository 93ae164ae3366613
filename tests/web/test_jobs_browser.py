"""Browser: the jobs page starts a training job and shows it live (a progress bar, epochs, loss, Csc
PCA points moving, every plot titled), shows a queued job's position and a restarted stage's
attempt, and the results page draws the report's figures with Plotly."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from server.jobs.bounds import MAX_EPOCHS
from tests.app_builder import serve_jobs_app

pytestmark = pytest.mark.browser


def _report(figures: Path, run_dir: Path) -> None:
    """A real (tiny) report: one faithful run on the tiny scene set, written by model.experiments.report."""
    from model.experiments.protocol import apply_overrides, data_digest, default_config, execute_run, plan
    from model.experiments.report import build_report
    from model.experiments.runstore import RunStore
    from tests.model.tiny_data import TINY_OVERRIDES, tiny_sequence_set

    data = tiny_sequence_set()
    store = RunStore(run_dir)
    specs = plan(
        "evaluate", "faithful", 1, 1, apply_overrides(default_config(), TINY_OVERRIDES), data_digest(data)
    )
    store.register(specs)
    outcome = execute_run(data, specs[0])
    checkpoint = store.write_checkpoint(outcome.key, outcome.checkpoint)
    store.finish(outcome.key, outcome.metrics, outcome.seconds, str(checkpoint))
    build_report(store, figures.parent / "RESULTS.md", figures, data)


@pytest.fixture(scope="module")
def base_url(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """The jobs-only app (tests/app_builder.py: jobs on the tiny scene set) showing a real tiny report."""
    tmp = tmp_path_factory.mktemp("jobs-web")
    _report(tmp / "figures", tmp / "report-runs")
    with pytest.MonkeyPatch.context() as env:
        env.setenv("MTRNN_USER_DIR", str(tmp / "user"))  # the app's own models, jobs and runs
        with serve_jobs_app(tmp, tmp / "figures") as (url, _):
            yield url


@pytest.fixture()
def jobs_page(page):  # noqa: ANN001, ANN201 - a playwright Page
    """The app's page (conftest.py) with time for a training job. The jobs-only app has no model
    registry: the header's model selector is given an empty one."""
    page.set_default_timeout(120_000)
    page.route("**/api/models", lambda route: route.fulfill(json={"selected": None, "models": []}))
    return page


def test_the_jobs_page_trains_a_model_live_and_offers_it_to_serve(jobs_page) -> None:  # noqa: ANN001
    page = jobs_page
    page.goto("/#/jobs")
    page.select_option("select[name=kind]", "train")
    page.select_option("select[name=mode]", "faithful")
    page.click("#start-job")
    page.wait_for_selector("#csc-plot[data-epoch]")  # the Csc PCA is drawn from SSE progress
    first = int(page.get_attribute("#csc-plot", "data-epoch"))
    page.wait_for_function(f"Number(document.querySelector('#csc-plot').dataset.epoch) !== {first}")
    assert page.locator("#csc-plot .scatterlayer .point").count() == 8  # one point per training recording
    assert page.locator("#loss-plot .scatterlayer .trace").count() >= 1
    page.wait_for_selector("#live-status[data-status=done]")
    page.wait_for_selector("#result-table")
    assert page.locator("#result-table tbody tr").count() == 3  # train, test, mixed
    page.wait_for_selector("tr[data-status=done] button.serve")
    assert float(page.get_attribute("#live-progress", "value")) == 1.0
    for plot in ("#loss-plot", "#csc-plot"):
        titles = page.evaluate(
            f"""(() => {{ const l = document.querySelector('{plot}').layout;
            return [l.title.text, l.xaxis.title.text, l.yaxis.title.text]; }})()"""
        )
        assert all(titles), (plot, titles)
    assert not page.errors


def test_a_job_beyond_the_running_ones_shows_its_place_in_the_queue(jobs_page, base_url: str) -> None:  # noqa: ANN001
    page = jobs_page
    long = {"kind": "train", "mode": "faithful", "overrides": {"training.epochs_auditory": MAX_EPOCHS}}
    running = httpx.post(f"{base_url}/api/jobs", json=long, timeout=30).json()["id"]  # max_jobs: 1 here
    waiting = httpx.post(f"{base_url}/api/jobs", json=long, timeout=30).json()
    try:
        assert waiting["status"] == "queued" and waiting["position"] == 1
        page.goto("/#/jobs")
        page.wait_for_selector(f"tr[data-job='{waiting['id']}'] >> text=queued, position 1")
        page.wait_for_selector(f"tr[data-job='{running}'][data-status=running] progress")
    finally:
        for job_id in (waiting["id"], running):
            httpx.post(f"{base_url}/api/jobs/{job_id}/cancel", timeout=30)
    assert not page.errors


def test_progress_names_the_attempt_of_a_restarted_stage_and_the_time_left(jobs_page) -> None:  # noqa: ANN001
    page = jobs_page
    page.goto("/#/jobs")
    page.wait_for_selector("#job-form")
    text = page.evaluate(
        """import('/pages/jobs.js').then((m) => m.progressText({ status: "running", progress: {
            type: "progress", stage: "auditory", epoch: 30, epochs: 1500, loss: 0.1,
            attempt: 2, attempts: 3, eta: 125 } }))"""
    )
    assert text == "auditory, attempt 2 of 3: epoch 30/1500, loss 0.1000, about 2 min left"
    labels = page.locator("select[name=preset] option").all_inner_texts()
    assert len(labels) == 2 and all("about" in label for label in labels)  # measured, per mode
    page.select_option("select[name=mode]", "faithful")
    assert page.locator("select[name=preset] option").all_inner_texts() != labels


def test_the_results_page_draws_the_report_figures(jobs_page) -> None:  # noqa: ANN001
    page = jobs_page
    page.goto("/#/results")
    page.wait_for_selector("#modes-f1 .main-svg")
    assert page.locator("#modes-f1 .barlayer .trace").count() == 1  # faithful
    page.wait_for_selector("[id^=pca-faithful] .main-svg")
    page.select_option("#pca-colour", "colour")
    page.wait_for_selector("[id^=pca-faithful] .scatterlayer .trace")
    assert not page.errors


def test_the_split_is_chosen_by_keyboard_and_the_size_split_asks_for_its_scenes(
    jobs_page, base_url: str
) -> None:  # noqa: ANN001
    page = jobs_page
    page.goto("/#/jobs")
    page.wait_for_selector("#job-split")
    assert page.locator("label:has(#job-split)").inner_text().startswith("split")
    assert page.locator("#job-train-scenes").is_hidden()
    page.focus("#job-split")
    for _ in range(3):  # scenes -> objects -> action-object -> size
        page.keyboard.press("ArrowDown")
    assert page.input_value("#job-split") == "size"
    assert page.locator("#job-train-scenes").is_visible()
    page.fill("#job-train-scenes", "2")
    page.select_option("select[name=mode]", "faithful")
    page.click("#start-job")
    row = page.wait_for_selector("tr[data-job] >> text=faithful, size split (2 scenes)")
    job_id = row.evaluate("el => el.closest('tr').dataset.job")
    job = httpx.get(f"{base_url}/api/jobs/{job_id}", timeout=30).json()
    httpx.post(f"{base_url}/api/jobs/{job_id}/cancel", timeout=30)
    assert job["params"]["split"] == "size" and job["params"]["train_scenes"] == 2
    page.select_option("#job-split", "objects")
    assert page.get_attribute("input[name=fold]", "max") == "3"
    assert not page.errors
