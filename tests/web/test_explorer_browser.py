"""The explorer in a real browser (Playwright + Debian chromium): what issue 4's "Done means" lists.

Each test compares what the page shows with what the REST API answers, and saves a screenshot
(into a temp folder; MTRNN_SCREENSHOTS=docs/screenshots retakes README's pictures).
"""

from __future__ import annotations

import io
import re

import httpx
import numpy as np
import pytest
from browser_helpers import assert_titled, plot_titles, shoot
from PIL import Image

from data.corpus import export_recording
from data.recording import write_zip

pytestmark = pytest.mark.browser

PAGES = {
    "scenes": "Scenes",
    "upload": "Upload a recording",
    "csc": "Csc spaces",
    "latent": "Latent explorer",
    "glossary": "Glossary",
}


# the "?" button of a control: inside the same labelled field (or the upload drop zone)
HELP_NEXT_TO_CONTROL = (
    "xpath=ancestor::*[contains(@class,'field') or contains(@class,'dropzone')][1]"
    "//button[contains(@class,'help')]"
)


def first_scene(base_url: str) -> dict:
    return httpx.get(f"{base_url}/api/scenes", timeout=30).json()["scenes"][0]


@pytest.mark.parametrize("route", list(PAGES))
def test_every_page_opens_with_help_on_its_controls(page, route: str) -> None:  # noqa: ANN001
    page.goto(f"/#/{route}")
    page.locator("main h1").filter(has_text=PAGES[route]).wait_for()
    if route in ("csc", "latent"):
        page.locator(".plot .main-svg").first.wait_for()
    if route != "glossary":
        assert page.locator("main button.help").count() >= 1
        for control in page.locator("main select, main input").all():
            assert control.locator(HELP_NEXT_TO_CONTROL).count() >= 1, control.evaluate("e => e.outerHTML")
    assert page.locator("#nav a").count() >= 5
    assert not page.errors  # type: ignore[attr-defined]
    shoot(page, f"page-{route}", full_page=route != "scenes")  # 256 rows: the first screen is enough


def test_help_button_explains_and_links_to_the_glossary(page) -> None:  # noqa: ANN001
    page.goto("/#/csc?space=s")
    page.locator("main .field button.help").first.click()
    pop = page.locator(".popover")
    pop.wait_for()
    assert "Glossary" in pop.inner_text()
    pop.locator("a").click()
    page.wait_for_url(re.compile(r"#/glossary\?term="))
    page.locator("dt.highlight").wait_for()


def test_pick_a_scene_read_its_utterance_and_see_the_arm_in_3d(page, base_url: str) -> None:  # noqa: ANN001
    scene = first_scene(base_url)
    page.goto(f"/#/scenes?action={scene['action']}")
    page.locator(f"a.scene-link:text-is('{scene['id']}')").click()
    page.wait_for_url(re.compile(f"#/scene/{scene['id']}"))
    said = httpx.post(f"{base_url}/api/scenes/{scene['id']}/describe", timeout=60).json()
    generated = page.locator("#generated")
    generated.wait_for()
    assert generated.inner_text() == (said["utterance"] or "(silence)")
    assert page.locator("#expected").inner_text() == scene["utterance"]
    page.locator("#activity-plot .main-svg").first.wait_for()
    page.locator("#target-plot .main-svg").first.wait_for()
    # the 3D view: viser's client through the app's WebSocket proxy, showing this recording
    viser = page.frame_locator("#viser-frame")
    viser.locator("canvas").first.wait_for(state="visible", timeout=90_000)
    viser.get_by_text(scene["id"]).first.wait_for(timeout=90_000)
    page.locator("#time").fill("2")
    page.locator("#time").dispatch_event("input")
    page.wait_for_timeout(4000)  # let the software renderer draw a few frames
    png = page.locator("#viser-frame").screenshot()
    pixels = np.asarray(Image.open(io.BytesIO(png)).convert("L"), dtype=float)
    assert pixels.std() > 8.0, "the 3D canvas is blank"
    assert page.locator("#camera-frame").evaluate("img => img.complete && img.naturalWidth") > 0
    page.wait_for_url(re.compile(r"[?&]t=2"))  # the time is in the URL
    # viser warns that headless chromium renders WebGL in software: close it for the screenshot
    for close in viser.locator(".mantine-Notification-root button").all():
        close.click()
    shoot(page, "scene")


def test_scene_view_is_addressable_by_time_and_overlay(page, base_url: str) -> None:  # noqa: ANN001
    scene = first_scene(base_url)
    page.goto(f"/#/scene/{scene['id']}?t=1.5&overlay=1")
    page.locator("#generated").wait_for()
    page.wait_for_function("document.querySelector('#time-label').textContent.startsWith('1.5')")
    assert page.locator("#overlay").is_checked()
    src = page.locator("#camera-frame").get_attribute("src")
    assert "overlay=true" in src and "/frames/30.jpg" in src


def test_upload_an_exported_recording_through_the_file_input(page, base_url: str, tmp_path) -> None:  # noqa: ANN001
    scene = first_scene(base_url)
    path = write_zip(export_recording(scene["id"], 0), tmp_path / f"{scene['id']}.zip")
    api = httpx.post(
        f"{base_url}/api/describe", files={"recording": (path.name, path.read_bytes())}, timeout=120
    ).json()
    page.goto("/#/upload")
    page.locator("#recording-file").set_input_files(str(path))
    said = page.locator("#upload-utterance")
    said.wait_for(timeout=120_000)
    assert said.inner_text() == (api["utterance"] or "(silence)")
    assert page.locator("#upload-preview img").count() == 3
    shoot(page, "upload")
    page.locator("#open-upload").click()
    page.wait_for_url(re.compile(r"#/scene/upload-"))
    page.locator("#generated").wait_for()
    assert page.locator("#generated").inner_text() == (api["utterance"] or "(silence)")


def test_upload_of_a_broken_file_shows_the_servers_message(page, tmp_path) -> None:  # noqa: ANN001
    broken = tmp_path / "broken.zip"
    broken.write_bytes(b"definitely not a zip archive")
    page.goto("/#/upload")
    page.locator("#recording-file").set_input_files(str(broken))
    error = page.locator("#upload-status .error")
    error.wait_for()
    assert "corrupt archive" in error.inner_text() and "broken.zip" in error.inner_text()


POINT_JS = """(id) => {
  const gd = document.getElementById(id);
  const fl = gd._fullLayout;
  const area = gd.querySelector('.nsewdrag').getBoundingClientRect();
  const t = gd.data.findIndex((tr) => tr.x.length > 0);
  const k = Math.floor(gd.data[t].x.length / 2);
  return { x: area.left + fl.xaxis.d2p(gd.data[t].x[k]), y: area.top + fl.yaxis.d2p(gd.data[t].y[k]) };
}"""


@pytest.mark.parametrize("space", ["s", "v", "a"])
def test_click_a_point_in_each_csc_space_opens_its_scene(page, base_url: str, space: str) -> None:  # noqa: ANN001
    page.goto(f"/#/csc?space={space}&colour=colour")
    page.locator("#csc-plot .scatterlayer .point").first.wait_for()
    page.locator("#measures").wait_for()
    if space == "a":
        shoot(page, "csc")
    ids = {p["id"] for p in httpx.get(f"{base_url}/api/csc?space={space}", timeout=60).json()["points"]}
    xy = page.evaluate(POINT_JS, "csc-plot")
    page.mouse.move(xy["x"], xy["y"])
    page.wait_for_timeout(300)
    page.mouse.click(xy["x"], xy["y"])
    page.wait_for_url(re.compile(r"#/scene/"))
    landed = page.url.split("#/scene/")[1].split("?")[0]
    assert landed in ids
    page.locator("#generated").wait_for()


def test_click_the_latent_plane_and_read_the_generated_text(page, base_url: str) -> None:  # noqa: ANN001
    page.goto("/#/latent")
    page.locator("#latent-plot .scatterlayer .point").first.wait_for()
    box = page.locator("#latent-plot .nsewdrag").bounding_box()
    page.mouse.click(box["x"] + 0.3 * box["width"], box["y"] + 0.4 * box["height"])
    page.wait_for_url(re.compile(r"#/latent\?x="))
    said = page.locator("#latent-utterance")
    page.wait_for_function(
        "!['click the plane', '…'].includes(document.querySelector('#latent-utterance').textContent)"
    )
    params = dict(p.split("=") for p in page.url.split("?")[1].split("&"))
    api = httpx.post(
        f"{base_url}/api/csc/generate", json={"point": [float(params["x"]), float(params["y"])]}, timeout=60
    ).json()
    assert said.inner_text() == (api["utterance"] or "(silence)")
    assert page.locator("#latent-history li").count() == 1
    shoot(page, "latent")


def test_the_header_switches_the_served_model(page, base_url: str) -> None:  # noqa: ANN001
    models = httpx.get(f"{base_url}/api/models", timeout=30).json()
    if len(models["models"]) < 2:
        pytest.skip("only one model is shipped")
    other = next(m["name"] for m in models["models"] if not m["selected"])
    page.goto("/#/scenes")
    try:
        with page.expect_response(lambda r: r.url.endswith("/api/models/selected") and r.ok):
            page.locator("#model").select_option(other)
        assert httpx.get(f"{base_url}/api/health", timeout=30).json()["model"] == other
        page.locator("#scene-count").wait_for()  # the page was rendered again
    finally:
        httpx.put(f"{base_url}/api/models/selected", json={"name": models["selected"]}, timeout=60)


@pytest.mark.parametrize("route", ["results", "csc?space=a", "csc?space=s", "latent"])
def test_every_plot_says_what_it_shows(page, route: str) -> None:  # noqa: ANN001
    page.goto(f"/#/{route}")
    page.locator(".js-plotly-plot .main-svg").first.wait_for()
    page.wait_for_load_state("networkidle")
    plots = plot_titles(page)
    assert_titled(plots)
    by_id = {p["id"]: p for p in plots}
    for coloured in ("csc-plot", "latent-plot", "modes-f1"):  # colours that mean something have a legend
        if coloured in by_id:
            assert by_id[coloured]["legend"], by_id[coloured]
    if route == "results":
        for metric, words in (("sentence_exact", "exact"), ("f1", "F1"), ("edit_distance", "edit distance")):
            assert words in by_id[f"modes-{metric}"]["title"] and by_id[f"modes-{metric}"]["axes"]["yaxis"]
    # every chart offers its numbers as a table
    assert page.locator("figure.chart button.table-toggle").count() == len(plots)


def test_show_as_table_lists_the_numbers_the_chart_draws(page, base_url: str) -> None:  # noqa: ANN001
    page.goto("/#/csc?space=v")
    page.locator("#ev-plot .main-svg").first.wait_for()
    ev = httpx.get(f"{base_url}/api/csc?space=v", timeout=60).json()["explained_variance_ratio"]
    button = page.locator("#ev-plot").locator("xpath=..").locator("button.table-toggle")
    button.press("Enter")  # the keyboard opens it
    rows = page.locator("#ev-plot-table tbody tr")
    rows.first.wait_for()
    assert rows.count() == len(ev)
    assert button.get_attribute("aria-expanded") == "true"
    first = rows.first.locator("td").all_inner_texts()
    assert first[0] == "PC1" and float(first[1]) == pytest.approx(100 * ev[0], rel=1e-3)
    assert "principal component" in page.locator("#ev-plot-table caption").inner_text()


def test_the_csc_page_says_why_d_rel_is_zero(page, base_url: str) -> None:  # noqa: ANN001
    space = httpx.get(f"{base_url}/api/csc?space=a", timeout=60).json()
    page.goto("/#/csc?space=a")
    page.locator("#measures").wait_for()
    distinct = len({(f"{p['x']:.5g}", f"{p['y']:.5g}") for p in space["points"]})
    if space["measures"]["d_rel"] >= 5e-5:
        assert page.locator("#d-rel-note").count() == 0
        pytest.skip("the served model's c_a,0 patterns are all distinct: nothing to explain")
    note = page.locator("#d-rel-note").inner_text()
    assert "64 values" in note and f"only {distinct} distinct points" in note


def test_the_scenes_grid_shows_thumbnails_and_right_wrong_badges(page, base_url: str) -> None:  # noqa: ANN001
    def answers() -> dict:
        return {s["id"]: s for s in httpx.get(f"{base_url}/api/scenes", timeout=60).json()["scenes"]}

    scenes = answers()
    for _ in range(60):  # the survey warms up with the server
        if all(s["said"] is not None for s in scenes.values()):
            break
        page.wait_for_timeout(1000)
        scenes = answers()
    page.goto("/#/scenes?action=push&colour=red")
    cards = page.locator("#scene-grid .scene-card:visible")
    cards.first.wait_for()
    wanted = [s for s in scenes.values() if s["action"] == "push" and s["colour"] == "red"]
    assert cards.count() == len(wanted) == 16
    first = cards.first
    page.wait_for_function(  # the camera's first and last frame, both loaded
        "() => { const imgs = document.querySelectorAll('#scene-grid .scene-card:not([hidden]) img');"
        " return imgs.length >= 2 && imgs[0].naturalWidth > 0 && imgs[1].naturalWidth > 0; }",
        timeout=90_000,
    )
    sources = first.locator("img").evaluate_all("imgs => imgs.map((i) => i.src)")
    rid = first.get_attribute("data-id")
    assert sources[0].endswith(f"/api/scenes/{rid}/frames/0.jpg?width=128")
    assert f"/frames/{scenes[rid]['frames'] - 1}.jpg" in sources[1]
    for card in cards.all():
        s = scenes[card.get_attribute("data-id")]
        assert card.locator(".card-said q").inner_text() == (s["said"] or "(silence)")
        assert card.locator(".verdict").inner_text() == ("✓ right" if s["correct"] else "✗ wrong")
        assert card.locator(".badge").inner_text() == s["split"]
    assert page.locator("#scene-grid .verdict.wrong:visible").count() == sum(not s["correct"] for s in wanted)
    shoot(page, "scenes-grid", full_page=False)
    page.locator("button[data-view=table]").click()  # the table, kept as a second view
    page.wait_for_url(re.compile(r"view=table"))
    assert page.locator("#scene-table tbody tr").count() == 16 and page.locator("#scene-grid").is_hidden()


def test_an_example_uploads_and_is_described(page, base_url: str) -> None:  # noqa: ANN001
    examples = httpx.get(f"{base_url}/api/examples", timeout=30).json()["examples"]
    assert len(examples) >= 6
    example = next(e for e in examples if e["kind"] == "unlike")
    page.goto("/#/upload")
    item = page.locator(f"#examples li[data-example='{example['name']}']")
    item.wait_for()
    assert page.locator("#examples li").count() == len(examples)
    assert item.locator("a.download").get_attribute("href") == example["url"]
    assert page.locator("#format-link").get_attribute("href").endswith("recording-format.md")
    item.locator("button.try-example").click()
    said = page.locator("#upload-utterance")
    said.wait_for(timeout=120_000)
    zipped = httpx.get(f"{base_url}{example['url']}", timeout=120).content
    api = httpx.post(
        f"{base_url}/api/describe", files={"recording": (f"{example['name']}.zip", zipped)}, timeout=120
    ).json()
    assert said.inner_text() == (api["utterance"] or "(silence)")
    assert page.locator("#upload-preview h2").inner_text() == f"{example['name']}.zip"
    shoot(page, "upload-example")
