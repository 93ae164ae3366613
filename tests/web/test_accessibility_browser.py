"""Accessibility in Debian chromium: axe-core (injected from the npm package scripts/ensure-axe
installs) finds no serious or critical violation on any page, every control can be reached with
the keyboard and shows where the focus is, and a Csc point can be opened without a mouse."""

from __future__ import annotations

import re

import httpx
import pytest
from browser_helpers import AXE_JS, axe_violations
from playwright.sync_api import TimeoutError as PlaywrightTimeout

pytestmark = pytest.mark.browser

LESSONS = ["timescales", "speaking", "seeing", "feeling", "abstracting", "associating", "generalising"]
# route -> what shows that the page has drawn what it loads
PAGES = {
    "scenes": "#scene-grid .scene-card img",
    "upload": "#examples li",
    "csc": "#csc-plot .main-svg",
    "latent": "#latent-plot .main-svg",
    "results": ".js-plotly-plot .main-svg",
    "glossary": "dl.glossary",
    "jobs": "main h1",
    **{f"lessons?lesson={name}": f"#lesson-{name} .try" for name in LESSONS},
}


@pytest.fixture(scope="module", autouse=True)
def _axe_installed() -> None:
    if not AXE_JS.is_file():
        pytest.skip("axe-core is not installed (run scripts/ensure-axe)")


def _settle(page, shown: str) -> None:  # noqa: ANN001
    page.locator(shown).first.wait_for()
    try:  # the page's own fetches finish; the embedded viser view may keep loading scripts on a busy machine
        page.wait_for_load_state("networkidle", timeout=10_000)
    except PlaywrightTimeout:
        page.wait_for_function("document.readyState === 'complete'")
    page.wait_for_timeout(300)


@pytest.mark.parametrize("route", list(PAGES))
def test_axe_finds_no_serious_violation_on_each_page(page, route: str) -> None:  # noqa: ANN001
    page.goto(f"/#/{route}")
    _settle(page, PAGES[route])
    assert axe_violations(page) == []
    assert not page.errors  # type: ignore[attr-defined]


def test_axe_finds_no_serious_violation_on_the_scene_view(page, base_url: str) -> None:  # noqa: ANN001
    scene = httpx.get(f"{base_url}/api/scenes", timeout=30).json()["scenes"][0]
    page.goto(f"/#/scene/{scene['id']}")
    _settle(page, "#activity-plot .main-svg")
    assert axe_violations(page) == []


def test_every_control_is_reached_by_tab_and_shows_its_focus(page) -> None:  # noqa: ANN001
    page.goto("/#/scenes")
    _settle(page, PAGES["scenes"])
    controls = page.locator("main select, main input, main button, main a[href]").count()
    seen: set[str] = set()
    outlines = []
    for _ in range(min(controls, 40) + 8):  # header, then the page's controls in order
        page.keyboard.press("Tab")
        info = page.evaluate(
            """() => { const e = document.activeElement; const s = getComputedStyle(e);
            const ring = s.outlineStyle !== 'none' && parseFloat(s.outlineWidth) > 0;
            return { key: e.id || e.name || e.textContent.trim().slice(0, 30), tag: e.tagName,
                     outline: ring || s.boxShadow !== 'none' }; }"""
        )
        seen.add(info["key"])
        outlines.append(info)
    assert {"action", "colour", "shape", "variant", "split", "q"} <= seen
    assert all(o["outline"] for o in outlines if o["tag"] != "BODY"), outlines


def test_a_csc_point_opens_its_scene_from_the_keyboard(page, base_url: str) -> None:  # noqa: ANN001
    page.goto("/#/csc?space=a")
    _settle(page, "#csc-plot .main-svg")
    ids = {p["id"] for p in httpx.get(f"{base_url}/api/csc?space=a", timeout=60).json()["points"]}
    summary = page.locator("#csc-point-list summary")
    summary.focus()
    page.keyboard.press("Enter")  # opens the list of points
    page.keyboard.press("Tab")  # the scrollable list
    page.keyboard.press("Tab")  # its first point
    focused = page.evaluate("() => document.activeElement.getAttribute('href')")
    assert focused.startswith("#/scene/")
    page.wait_for_function(  # the focused point is marked in the plot
        "() => document.getElementById('csc-plot').data.some((t) => t.name === 'focused' && t.x.length === 1)"
    )
    page.keyboard.press("Enter")
    page.wait_for_url(re.compile(r"#/scene/"))
    landed = page.url.split("#/scene/")[1].split("?")[0]
    assert landed in ids and f"#/scene/{landed}" == focused
