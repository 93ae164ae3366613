"""The live description in a real browser: the timeline strip under the shared time cursor.

On the scene view (and the upload view, the same page) the strip lists what the model would say
at each step, highlights the utterance at the cursor and moves with it; for end_to_end models the
slots' word-unit probabilities are drawn as lines with the cursor line.
"""

from __future__ import annotations

import httpx
import pytest
from browser_helpers import axe_violations, plot_titles, shoot

from data.corpus import export_recording
from data.recording import write_zip

pytestmark = pytest.mark.browser

RID = "slide-red-apple-2"  # a sliding action, whose description changes as the recording goes on


def runs(timeline: dict) -> list[tuple[float, str]]:
    """(start in seconds, utterance) of each run of equal utterances, as the strip lists them."""
    u, t = timeline["utterance"], timeline["t"]
    return [(t[k], u[k]) for k in range(len(u)) if k == 0 or u[k] != u[k - 1]]


def highlighted(page) -> str:  # noqa: ANN001 - a playwright Page
    return page.locator("#timeline-strip [aria-current='step']").inner_text()


def move_cursor(page, t: float) -> None:  # noqa: ANN001
    page.locator("#time").fill(f"{t:.2f}")
    page.locator("#time").dispatch_event("input")
    page.wait_for_function(f"document.querySelector('#time-label').textContent === '{t:.2f} s'")


def scene_id(base_url: str) -> str:
    ids = {s["id"] for s in httpx.get(f"{base_url}/api/scenes", timeout=60).json()["scenes"]}
    return RID if RID in ids else sorted(ids)[0]


def test_the_timeline_strip_follows_the_cursor(page, base_url: str) -> None:  # noqa: ANN001
    rid = scene_id(base_url)
    timeline = httpx.get(f"{base_url}/api/scenes/{rid}/timeline", timeout=60).json()
    page.goto(f"/#/scene/{rid}")
    strip = page.locator("#timeline-strip button")
    strip.first.wait_for()
    listed = runs(timeline)
    assert strip.all_inner_texts() == [f"at {t:.2f} s: {u or '(silence)'}" for t, u in listed]
    for k in sorted({0, len(listed) // 2, len(listed) - 1}):
        start, text = listed[k]
        end = listed[k + 1][0] if k + 1 < len(listed) else timeline["t"][-1] + 1 / timeline["fps"]
        fps = timeline["fps"]
        step = (round(start * fps) + round(end * fps) - 1) // 2  # the middle step of the run, even of 2 steps
        t = round(step / fps, 2)
        move_cursor(page, t)
        step = min(step, len(timeline["utterance"]) - 1)
        assert highlighted(page) == f"at {start:.2f} s: {text or '(silence)'}"
        assert page.locator("#timeline-now").inner_text() == (timeline["utterance"][step] or "(silence)")
    assert page.locator("#timeline-strip [aria-current='step']").count() == 1
    # the keyboard moves the cursor to an utterance of the strip
    start, text = listed[-1]
    strip.last.focus()
    strip.last.press("Enter")
    page.wait_for_function(f"document.querySelector('#time-label').textContent === '{start:.2f} s'")
    assert highlighted(page) == f"at {start:.2f} s: {text or '(silence)'}"
    settles = page.locator("#timeline-settles").inner_text()
    for name, s in (timeline["settles"]["slots"] or {}).items():
        assert f"{name} “{s['word']}” at {s['t']:.2f} s" in settles
    if timeline["slots"]:
        plot = next(p for p in plot_titles(page) if p["id"] == "timeline-plot")
        assert plot["title"] and plot["axes"] == {"xaxis": "time (s)", "yaxis": "probability"}
        assert plot["traces"] == sum(len(s["words"]) for s in timeline["slots"].values()) and plot["legend"]
        shapes = page.evaluate("() => document.querySelector('#timeline-plot').layout.shapes")
        assert shapes[0]["x0"] == pytest.approx(start)  # the cursor line moved with the cursor
    ours = [v for v in axe_violations(page) if any("timeline" in str(n) for n in v["nodes"])]
    assert not ours, ours  # no serious or critical accessibility violation in the timeline
    assert not page.errors  # type: ignore[attr-defined]
    shoot(page, "scene-timeline")


def test_the_upload_view_shows_the_uploads_timeline(page, base_url: str, tmp_path) -> None:  # noqa: ANN001
    rid = scene_id(base_url)
    path = write_zip(export_recording(rid, 0), tmp_path / f"{rid}.zip")
    answer = httpx.post(
        f"{base_url}/api/describe", files={"recording": (path.name, path.read_bytes())}, timeout=120
    ).json()
    listed = runs(answer["timeline"])
    page.goto(f"/#/scene/{answer['id']}")
    strip = page.locator("#timeline-strip button")
    strip.first.wait_for()
    assert strip.count() == len(listed)
    assert strip.last.inner_text() == f"at {listed[-1][0]:.2f} s: {answer['utterance'] or '(silence)'}"
    move_cursor(page, answer["timeline"]["t"][-1])
    assert page.locator("#timeline-now").inner_text() == (answer["utterance"] or "(silence)")
    assert not page.errors  # type: ignore[attr-defined]
