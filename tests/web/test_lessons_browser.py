"""The lessons in Debian chromium (Playwright): each lesson loads, every live control is moved and
the view changes with numbers or plots from the server; ?hide= hides controls; answers reveal.

By default the app runs in-process on the shipped corpus and model when both exist (MTRNN_CORPUS,
MTRNN_MODELS_DIR, MTRNN_MODEL can point at others), else on the synthetic world of
tests/server/lesson_world.py. With MTRNN_LESSONS_URL=http://host:port the test drives that running
app instead, and with MTRNN_LESSON_SCREENSHOTS=<dir> it saves one screenshot per lesson.
"""

from __future__ import annotations

import dataclasses
import json
import os
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import cv2
import httpx
import pytest
from browser_helpers import assert_titled, plot_titles

from data.corpus import DEFAULT_PATH
from data.scenario import Scene
from model.experiments.runstore import RunSpec, RunStore
from server.settings import Settings
from tests.app_builder import build_app, lesson_world, serve_in_thread
from tests.server.lesson_world import render

pytestmark = pytest.mark.browser
playwright = pytest.importorskip("playwright.sync_api")
SHOTS = os.environ.get("MTRNN_LESSON_SCREENSHOTS")

# The cursor of this page's own 3D view (its id is the viser iframe's path: /viser/<view>/).
VIEWED_CURSOR = (
    "fetch('/api/viewer?view=' + new URL(document.getElementById('viser-frame').src).pathname.split('/')[2])"
    ".then((r) => r.json())"
)


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, bool]]:
    """(URL of the app, whether it runs on the synthetic world with a synthetic run store)."""
    external = os.environ.get("MTRNN_LESSONS_URL")
    if external:
        yield external.rstrip("/"), False
        return
    shipped = Settings.from_env(viser=True)
    corpus = shipped.corpus_path or DEFAULT_PATH
    synthetic = not (corpus.is_file() and (shipped.models_dir / shipped.model / "meta.json").is_file())
    if synthetic:  # a stored sweep to show, and a short live cosine run
        runs = _stored_sweeps(tmp_path_factory.mktemp("runs"))
        app = build_app(
            *lesson_world(tmp_path_factory.mktemp("world"), viser=True, run_dir=runs, cosine_epochs=60)
        )
    else:  # the shipped corpus and models (the screenshots show them) and the real run store
        app = build_app(dataclasses.replace(shipped, corpus_path=corpus))
    with serve_in_thread(app) as url:
        httpx.get(f"{url}/api/lessons", timeout=60)  # the lessons' survey of the corpus
        yield url, synthetic


def _stored_sweeps(run_dir: Path) -> Path:
    """A run store holding a small psi_s sweep and cosine sweep, as model.experiments.sweeps records them."""
    store = RunStore(run_dir)
    for k, psi in enumerate((1e-4, 5e-4, 2e-3)):
        for init in range(2):
            spec = RunSpec("psi_s", "faithful", 0, init, init, {}, {"psi_s": psi})
            store.register([spec])
            metrics = {
                "mixed": {"f1": 0.5 + 0.1 * k + 0.01 * init, "edit_distance": 0.4 - 0.05 * k},
                "train": {"csc.somatosensory.d_avg": 1.0 - 0.2 * k, "csc.somatosensory.d_rel": 0.8},
            }
            store.finish(spec.key, metrics, 1.0)
    for k, psi in enumerate((0.0, 5e-5, 2e-4)):
        spec = RunSpec("cosine", f"cosine:{psi}", 0, 0, 0, {}, {"psi": psi})
        store.register([spec])
        store.finish(spec.key, {"cosine": {"epochs": 200 + k, "d_avg": 1.3, "d_rel": 0.95 + 0.01 * k}}, 1.0)
    return run_dir


@pytest.fixture(scope="module")
def base_url(served: tuple[str, bool]) -> str:
    return served[0]


@pytest.fixture()
def page(browser, base_url: str) -> Iterator:  # noqa: ANN001 - a Playwright browser
    context = browser.new_context(viewport={"width": 1400, "height": 1000})
    pg = context.new_page()
    errors: list[str] = []
    pg.on("pageerror", lambda e: errors.append(str(e)))
    pg.base = base_url  # type: ignore[attr-defined]
    yield pg
    context.close()
    assert not errors, errors


def _open(  # noqa: ANN001
    page, lesson: str, query: str = "", shown: str | None = None, plot: str | None = None
) -> None:
    """Open a lesson in the app and wait until it shows `shown` (a selector) and draws `plot` (an id)."""
    page.goto(f"{page.base}/#/lessons?lesson={lesson}{query}")
    page.wait_for_selector(f"#lesson-{lesson}")
    if shown:
        page.wait_for_selector(shown)
    if plot:
        page.wait_for_function(f"() => document.getElementById('{plot}').data")


def _changes(page, read: Callable[[], object], act: Callable[[], None], timeout: float = 30.0) -> object:  # noqa: ANN001
    """Do `act` and wait until `read()` differs from before; return the new value."""
    before = read()
    act()
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        now = read()
        if now != before:
            return now
        page.wait_for_timeout(100)
    raise AssertionError(f"the view did not change (still {before!r})")


def _slide(page, selector: str, value: float) -> None:  # noqa: ANN001
    page.eval_on_selector(
        selector,
        "(el, v) => { el.value = v; el.dispatchEvent(new Event('input', { bubbles: true })); }",
        value,
    )


def _plot(page, el_id: str, path: str = "data") -> Callable[[], str]:  # noqa: ANN001
    """Reads a Plotly figure's data (or layout) as JSON: a plot that changed was redrawn."""
    return lambda: page.evaluate(
        f"() => {{ const d = document.getElementById('{el_id}'); "
        f"return d && d.{path} ? JSON.stringify(d.{path}) : ''; }}"
    )


def _text(page, selector: str) -> Callable[[], str]:  # noqa: ANN001
    return lambda: (
        page.eval_on_selector(selector, "el => el.textContent") if page.query_selector(selector) else ""
    )


def _shot(page, lesson: str) -> None:  # noqa: ANN001
    if SHOTS:
        page.wait_for_timeout(800)
        Path(SHOTS).mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(Path(SHOTS) / f"{lesson}.png"), full_page=True)


def _reveal(page, lesson: str) -> None:  # noqa: ANN001
    """Reveal the "try this" answer, check it reads well, and save the lesson's screenshot."""
    page.click("button.reveal")
    page.wait_for_selector(".try .answer:not([hidden])")
    assert len(page.inner_text(".try .answer")) > 80
    text = page.inner_text(".lesson")
    for broken in ("null", "undefined", "NaN", "[object"):
        assert broken not in text, f"{broken!r} shown on the page"
    assert_titled(plot_titles(page), allow_none=True)
    _shot(page, lesson)


def test_timescales_tau_scene_and_the_shared_time_cursor(page) -> None:  # noqa: ANN001
    _open(page, "timescales", shown="#half-life", plot="layer-Cs")
    half = _changes(page, _text(page, "#half-life"), lambda: _slide(page, "#tau", 70))
    assert "48" in str(half)  # ln 0.5 / ln(1 - 1/70) = 48.2 steps, from the server
    assert "tau=70" in page.url
    _changes(page, _plot(page, "layer-Cs"), lambda: page.select_option("#scene", index=5))
    cursor = _plot(page, "layer-IO", "layout.shapes")
    _changes(page, cursor, lambda: _slide(page, "#time", 20))
    assert page.evaluate("() => document.getElementById('layer-Cf').layout.shapes[0].x0") == 20
    _reveal(page, "timescales")


def test_speaking_text_and_the_four_constants(page) -> None:  # noqa: ANN001
    _open(page, "speaking", shown="#arpabet")
    _changes(page, _text(page, "#arpabet"), lambda: page.fill("#utterance", "the bookkeeper."))
    page.wait_for_function("() => document.getElementById('exact').textContent.includes('exact')")
    assert "✓" in page.inner_text("#exact")
    _changes(page, _text(page, "#exact"), lambda: _slide(page, "#nu", 1))
    assert "✗" in page.inner_text("#exact")
    _slide(page, "#nu", 2)
    page.wait_for_function("() => document.getElementById('exact').textContent.includes('✓')")
    _changes(page, _plot(page, "softmax-plot"), lambda: _slide(page, "#sigma2", 2))
    _changes(page, _plot(page, "spike-plot"), lambda: _slide(page, "#omega", 8))
    _changes(page, _plot(page, "softmax-plot"), lambda: _slide(page, "#gamma", 8))
    page.fill("#utterance", "push the florbix.")
    page.wait_for_selector("#speech-error .error")
    assert "florbix" in page.inner_text("#speech-error")
    page.fill("#utterance", "slide the red apple.")
    page.wait_for_function("() => !document.querySelector('#speech-error .error')")
    _reveal(page, "speaking")


def test_seeing_frames_colour_window_and_an_upload(page, tmp_path: Path) -> None:  # noqa: ANN001
    _open(page, "seeing", shown="#stages img")
    _changes(page, _text(page, "#seeing-source"), lambda: _slide(page, "#frame", 5))
    assert "frame 5" in page.inner_text("#seeing-source")
    mean_shift = lambda: page.get_attribute("#stages img[data-stage=mean_shift]", "src")  # noqa: E731
    _changes(page, mean_shift, lambda: _slide(page, "#colour-radius", 60))
    picture = tmp_path / "mine.png"
    frame = render(Scene("slide", "yellow", "banana"))[0]
    cv2.imwrite(str(picture), cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
    _changes(page, _text(page, "#seeing-source"), lambda: page.set_input_files("#image-file", str(picture)))
    assert "mine.png" in page.inner_text("#seeing-source")
    _changes(page, _plot(page, "feature-plot"), lambda: page.select_option("#scene", index=7))
    assert "frame 0" in page.inner_text("#seeing-source")  # back to the corpus
    _slide(page, "#colour-radius", 24)
    page.wait_for_function("() => document.getElementById('radius-value').textContent === '24'")
    _reveal(page, "seeing")


def test_feeling_action_colour_and_the_cursor_shared_with_the_3d_arm(page) -> None:  # noqa: ANN001
    _open(page, "feeling", shown="#touch-distances", plot="joint-plot")
    _changes(page, _plot(page, "joint-plot"), lambda: page.select_option("#action", "slide"))
    _changes(page, _plot(page, "joint-plot"), lambda: page.select_option("#colour", "blue"))
    assert "colour=blue" in page.url and "action=slide" in page.url
    _changes(page, _plot(page, "joint-plot", "layout.shapes"), lambda: _slide(page, "#time", 1.5))
    viewer = page.evaluate("() => fetch('/api/viewer').then((r) => r.json())")
    if viewer["available"]:  # the 3D arm follows the page's cursor
        page.wait_for_function(f"() => {VIEWED_CURSOR}.then((s) => Math.abs(s.t - 1.5) < 0.06)")
        shown = page.evaluate(f"() => {VIEWED_CURSOR}")["source"]
        assert shown == page.eval_on_selector("#shown", "el => el.value")
        page.select_option("#shown", index=2)
        page.wait_for_function(
            f"(id) => {VIEWED_CURSOR}.then((s) => s.source === id)",
            arg=page.eval_on_selector("#shown", "el => el.value"),
        )
        page.wait_for_function(  # switching the recording keeps the cursor
            f"() => {VIEWED_CURSOR}.then((s) => Math.abs(s.t - 1.5) < 0.06)"
        )
        assert page.input_value("#time") == "1.5"
    _reveal(page, "feeling")


def test_abstracting_runs_the_cosine_experiment_live(page, served: tuple[str, bool]) -> None:  # noqa: ANN001
    _open(page, "abstracting", "&psi=0.0002", shown="#sweep h2")
    _changes(page, _text(page, "#psi-value"), lambda: _slide(page, "#psi", 2))
    page.fill("#seed", "4")
    page.click("#run")
    page.wait_for_function(
        "() => document.getElementById('run-status').textContent.startsWith('done')", timeout=60_000
    )
    assert float(page.inner_text("#d-rel")) > 0
    assert page.evaluate("() => document.getElementById('csc-plot').data.length") >= 6
    assert page.eval_on_selector("#progress > div", "el => el.style.width") == "100%"
    assert len(page.query_selector_all("#run-history tr")) == 1
    if page.query_selector("#sweep-metric"):  # a stored psi_s sweep: pick another measure
        other = page.eval_on_selector_all("#sweep-metric option", "els => els.map((e) => e.value)")[1]
        _changes(page, _plot(page, "sweep-plot"), lambda: page.select_option("#sweep-metric", other))
        assert f"metric={other}" in page.url
    elif served[1]:
        raise AssertionError("the stored sweep was not shown")
    _reveal(page, "abstracting")


def test_associating_mute_and_colour_by(page) -> None:  # noqa: ANN001
    _open(page, "associating", shown="#said-muted", plot="space-a")
    _changes(page, _plot(page, "space-a"), lambda: page.select_option("#mute", "vision"))
    page.wait_for_selector("#moved")
    # the distance the muted point moved is the server's (0 when the other sense alone picks the same words)
    scene = page.url.split("scene=")[1].split("&")[0]
    answer = page.evaluate(
        f"() => fetch('/api/lessons/associating?scene={scene}&mute=vision').then(r => r.json())"
    )
    assert float(page.inner_text("#moved")) == pytest.approx(answer["moved"], abs=1e-4)
    assert page.inner_text("#said-muted").strip()
    _changes(page, _plot(page, "space-a"), lambda: page.select_option("#mute", "proprioception"))
    _changes(page, _plot(page, "space-v"), lambda: page.select_option("#colour-by", "colour"))
    _changes(page, _plot(page, "space-s"), lambda: page.select_option("#scene", index=9))
    assert "mute=proprioception" in page.url
    _reveal(page, "associating")


def test_generalising_two_models_side_by_side(page) -> None:  # noqa: ANN001
    _open(page, "generalising", shown="#summary-0 table")
    page.wait_for_selector("#summary-1 table")
    page.wait_for_function("() => document.getElementById('grid-1').data")
    options = page.eval_on_selector_all("#model-b option", "els => els.map((e) => e.value)")
    if len(options) < 2:
        pytest.skip("the app serves one model: nothing to compare")
    current = page.eval_on_selector("#model-b", "el => el.value")
    other = next(o for o in options if o != current)
    _changes(page, _text(page, "#title-1"), lambda: page.select_option("#model-b", other))
    first = page.eval_on_selector("#model-a", "el => el.value")
    other_a = next(o for o in options if o != first)
    _changes(page, _text(page, "#title-0"), lambda: page.select_option("#model-a", other_a))
    assert other_a in page.inner_text("#title-0") and page.query_selector("#summary-0 table")
    page.select_option("#model-a", first)
    page.wait_for_function("(m) => document.getElementById('title-0').textContent.startsWith(m)", arg=first)
    assert other in page.inner_text("#title-1") and f"b={other}" in page.url
    page.select_option("#model-b", current)  # back to the default pair (faithful vs end-to-end)
    page.wait_for_function("(m) => document.getElementById('title-1').textContent.startsWith(m)", arg=current)
    page.click("#grid-0 .nsewdrag", position={"x": 30, "y": 30})
    page.wait_for_selector("#detail-0 li")
    # the keyboard's way to a cell: its select
    _changes(page, _text(page, "#detail-1"), lambda: page.select_option("#pick-1", index=1))
    _reveal(page, "generalising")


def test_hide_flags_remove_controls_and_survive_navigation(page) -> None:  # noqa: ANN001
    _open(page, "timescales", "&hide=tau,time,answer", shown="#half-life")
    assert page.is_hidden("[data-control=tau]") and page.is_hidden("[data-control=time]")
    assert page.is_visible("[data-control=scene]") and page.is_hidden("button.reveal")
    page.click("nav.lesson-tabs a[data-lesson=speaking]")
    page.wait_for_selector("#lesson-speaking")
    assert "hide=tau%2Ctime%2Canswer" in page.url or "hide=tau,time,answer" in page.url
    assert page.is_hidden("button.reveal")


def test_feeling_shows_the_hand_path_under_the_same_time_cursor(page) -> None:  # noqa: ANN001
    _open(page, "feeling", shown="#touch-distances", plot="hand-plot")
    hand = next(p for p in plot_titles(page) if p["id"] == "hand-plot")
    assert hand["title"].startswith("hand path of") and "cm" in hand["title"]
    ys = [t for k, t in sorted(hand["axes"].items()) if k.startswith("y")]
    assert ys == ["forward x (cm)", "left y (cm)", "up z (cm)"]
    assert hand["traces"] == 3 * page.eval_on_selector_all("#shown option", "els => els.length")
    assert "reads" in page.inner_text("#reads-note")
    assert "hand path RMS (cm)" in page.inner_text("#touch-distances thead")
    moved = _changes(page, _plot(page, "hand-plot", "layout.shapes"), lambda: _slide(page, "#time", 1.5))
    assert [s["x0"] for s in json.loads(moved)] == [1.5, 1.5, 1.5]  # the cursor of the joint plot
