"""The upload view shows how familiar the recording is to the model (a labelled meter per sense
with its percentage as text) and the answer's warnings beside the utterance; axe stays clean."""

from __future__ import annotations

import sys
from pathlib import Path

import httpx
import pytest
from browser_helpers import axe_violations

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "server"))
from hostile_cases import recording_members, zip_of  # noqa: E402

pytestmark = pytest.mark.browser


def test_a_far_off_upload_shows_its_familiarity_and_warnings(page, base_url: str, tmp_path: Path) -> None:  # noqa: ANN001
    path = tmp_path / "still-arm.zip"
    path.write_bytes(zip_of(recording_members(steps=400)))  # 20 s, the arm still, a red block
    api = httpx.post(
        f"{base_url}/api/describe", files={"recording": (path.name, path.read_bytes())}, timeout=120
    ).json()
    page.goto("/#/upload")
    page.locator("#recording-file").set_input_files(str(path))
    page.locator("#upload-familiarity").wait_for(timeout=120_000)
    for sense in ("proprioception", "vision"):
        meter = page.locator(f"#familiarity-{sense}")
        assert float(meter.get_attribute("value")) == pytest.approx(api["familiarity"][sense])
        label = page.locator(f"label[for='familiarity-{sense}']").inner_text()
        assert ("arm" if sense == "proprioception" else "camera") in label
        text = page.locator(f".familiarity-value[data-sense='{sense}']").inner_text()
        assert text.strip() == f"{round(100 * api['familiarity'][sense])} %"
    shown = page.locator("#upload-warnings li").all_inner_texts()
    assert [w.removeprefix("⚠ ").strip() for w in shown] == api["warnings"]
    assert any("much longer than any the model learned from" in w for w in shown)
    assert axe_violations(page) == []
    assert page.errors == []
