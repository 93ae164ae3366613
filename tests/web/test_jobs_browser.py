"""Browser: the jobs page starts a training job and shows it live (epochs, loss, Csc PCA points
moving), and the results page draws the report's figures with Plotly."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

ROOT = Path(__file__).resolve().parents[2]
SERVER_TESTS = ROOT / "tests" / "server"
sys.path.insert(0, str(ROOT / "tests" / "model"))

pytestmark = pytest.mark.browser


def _report(figures: Path, run_dir: Path) -> None:
    """A real (tiny) report: one faithful run on the tiny scene set, written by model.experiments.report."""
    from tests.model.tiny_data import TINY_OVERRIDES, tiny_sequence_set

    from model.experiments.protocol import apply_overrides, data_digest, default_config, execute_run, plan
    from model.experiments.report import build_report
    from model.experiments.runstore import RunStore

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
def jobs_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    from server.viewer import free_port

    tmp = tmp_path_factory.mktemp("jobs-web")
    _report(tmp / "figures", tmp / "report-runs")
    port = free_port()
    env = {
        **os.environ,
        "JOBS_RUN_DIR": str(tmp / "runs"),
        "JOBS_MODELS_DIR": str(tmp / "models"),
        "MTRNN_FIGURES_DIR": str(tmp / "figures"),
    }
    server = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "uvicorn",
            "--factory",
            "jobs_app:create",
            "--app-dir",
            str(SERVER_TESTS),
            "--port",
            str(port),
            "--log-level",
            "warning",
        ],
        env=env,
    )
    base = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 60
    while True:
        try:
            if httpx.get(f"{base}/api/jobs", timeout=1).status_code == 200:
                break
        except httpx.HTTPError:
            pass
        assert time.monotonic() < deadline, "the jobs app did not start"
        time.sleep(0.2)
    yield base
    server.terminate()
    server.wait(timeout=20)


@pytest.fixture()
def jobs_page(browser, jobs_server: str) -> Iterator[object]:  # noqa: ANN001 - playwright Browser
    context = browser.new_context(viewport={"width": 1400, "height": 1000}, base_url=jobs_server)
    page = context.new_page()
    page.set_default_timeout(120_000)
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.errors = errors  # type: ignore[attr-defined]
    yield page
    context.close()


def test_the_jobs_page_trains_a_model_live_and_offers_it_to_serve(jobs_page) -> None:  # noqa: ANN001
    page = jobs_page
    page.goto("/jobs.html")
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
    assert not page.errors


def test_the_results_page_draws_the_report_figures(jobs_page) -> None:  # noqa: ANN001
    page = jobs_page
    page.goto("/results.html")
    page.wait_for_selector("#modes-f1 .main-svg")
    assert page.locator("#modes-f1 .barlayer .trace").count() == 1  # faithful
    page.wait_for_selector("[id^=pca-faithful] .main-svg")
    page.select_option("#pca-colour", "colour")
    page.wait_for_selector("[id^=pca-faithful] .scatterlayer .trace")
    assert not page.errors
