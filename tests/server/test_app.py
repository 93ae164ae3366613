"""The app shell: pages that once had HTML of their own answer with the route of the one web router."""

import pytest
from fastapi.testclient import TestClient

from tests.app_builder import JOBS_ROUTERS, build_app, jobs_settings


@pytest.mark.parametrize(
    ("old", "route"), [("/jobs.html", "jobs"), ("/results.html", "results"), ("/lessons/", "lessons")]
)
def test_a_moved_page_redirects_to_its_route_of_the_app(tmp_path, old: str, route: str) -> None:
    with TestClient(build_app(jobs_settings(tmp_path), routers=JOBS_ROUTERS)) as client:
        r = client.get(old, follow_redirects=False)
    assert r.status_code == 301
    assert r.headers["location"] == f"/#/{route}"


def test_the_recording_format_the_upload_page_links_to_is_served(tmp_path) -> None:
    with TestClient(build_app(jobs_settings(tmp_path), routers=JOBS_ROUTERS)) as client:
        r = client.get("/docs/recording-format.md")
    assert r.status_code == 200
    assert r.headers["content-type"].startswith("text/markdown")
    assert "joints.csv" in r.text
