"""Helpers of the browser tests: screenshots (into a temp folder unless MTRNN_SCREENSHOTS names one),
axe-core's accessibility check injected into a page, and the titles of a page's Plotly figures."""

from __future__ import annotations

import functools
import os
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
# scripts/ensure-axe installs axe-core here (the Makefile's test target runs it)
AXE_JS = ROOT / ".venv" / "axe" / "node_modules" / "axe-core" / "axe.min.js"
SERIOUS = ("serious", "critical")


@functools.cache
def screenshots_dir() -> Path:
    """MTRNN_SCREENSHOTS (e.g. docs/screenshots, to retake README's pictures), else a temp folder."""
    wanted = os.environ.get("MTRNN_SCREENSHOTS")
    return Path(wanted) if wanted else Path(tempfile.mkdtemp(prefix="mtrnn-screenshots-"))


def shoot(page, name: str, full_page: bool = True) -> Path:  # noqa: ANN001 - a playwright Page
    folder = screenshots_dir()
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.png"
    page.screenshot(path=str(path), full_page=full_page)
    return path


def axe_violations(page, impacts: tuple[str, ...] = SERIOUS) -> list[dict]:  # noqa: ANN001
    """axe-core's violations of `impacts` on the page as it is now (the viser iframe, viser's own
    client, is not ours and left out): [{id, impact, help, nodes: [target...]}]."""
    if not page.evaluate("() => !!window.axe"):
        page.add_script_tag(path=str(AXE_JS))
    found = page.evaluate("() => axe.run(document, { iframes: false, resultTypes: ['violations'] })")
    return [
        {
            "id": v["id"],
            "impact": v["impact"],
            "help": v["help"],
            "nodes": [n["target"] for n in v["nodes"]][:5],
        }
        for v in found["violations"]
        if v["impact"] in impacts
    ]


# Every Plotly figure on the page: its title and axis titles as the page gave them (gd.layout: the
# full layout shows Plotly's "Click to enter ... title" placeholder for a missing one), for every x/y
# axis Plotly drew, and whether a legend is shown.
PLOT_TITLES_JS = """() => [...document.querySelectorAll('.js-plotly-plot')].map((gd) => {
  const full = gd._fullLayout || {};
  const text = (t) => (t && typeof t === 'object' && t.text) || '';
  const axes = Object.keys(full).filter((k) => /^[xy]axis\\d*$/.test(k) && full[k].visible !== false);
  return {
    id: gd.id,
    title: text(gd.layout.title),
    axes: Object.fromEntries(axes.map((k) => [k, text(gd.layout[k] && gd.layout[k].title)])),
    traces: gd.data.length,
    legend: full.showlegend !== false && gd.data.some((t) => t.showlegend !== false),
  };
})"""


def plot_titles(page) -> list[dict]:  # noqa: ANN001
    return page.evaluate(PLOT_TITLES_JS)


def assert_titled(plots: list[dict], allow_none: bool = False) -> None:
    """Every figure has a title, every y axis a title and at least one x axis (shared x: the bottom one)."""
    assert plots or allow_none, "no plot on the page"
    for p in plots:
        assert p["title"].strip(), p
        ys = [t for k, t in p["axes"].items() if k.startswith("y")]
        xs = [t for k, t in p["axes"].items() if k.startswith("x")]
        assert ys and all(t.strip() for t in ys), p
        assert any(t.strip() for t in xs), p
