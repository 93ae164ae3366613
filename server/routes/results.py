"""The results report (`mtrnn report`) for the app's Results page.

GET    /api/results                the report's figure data (docs/figures/results.json)
GET    /api/results/figures/{png}  the report's PNG figures
"""

from __future__ import annotations

import os
from pathlib import Path

from fastapi import APIRouter, HTTPException
from fastapi.responses import FileResponse

from server.settings import REPO_ROOT

router = APIRouter(tags=["results"])


def figures_dir() -> Path:
    """Where `mtrnn report` wrote its figures: $MTRNN_FIGURES_DIR or docs/figures."""
    return Path(os.environ.get("MTRNN_FIGURES_DIR", REPO_ROOT / "docs" / "figures"))


@router.get("/api/results")
def results() -> FileResponse:
    """The numbers behind docs/RESULTS.md's figures (written by `mtrnn report`)."""
    path = figures_dir() / "results.json"
    if not path.is_file():
        raise HTTPException(404, "no results yet: run `mtrnn evaluate`, `mtrnn sweep` and `mtrnn report`")
    return FileResponse(path, media_type="application/json", headers={"Cache-Control": "no-cache"})


@router.get("/api/results/figures/{name}")
def result_figure(name: str) -> FileResponse:
    path = (figures_dir() / name).resolve()
    if path.parent != figures_dir().resolve() or path.suffix != ".png" or not path.is_file():
        raise HTTPException(404, f"no figure {name!r}")
    return FileResponse(path, media_type="image/png")
