"""The results report (`mtrnn report`) for the app's Results page.

GET    /api/results                the report's figure data (<figures_dir>/results.json)
GET    /api/results/figures/{png}  the report's PNG figures
"""

from __future__ import annotations

from fastapi import APIRouter, HTTPException
from fastapi.responses import FileResponse

from server.deps import SettingsDep

router = APIRouter(tags=["results"])


@router.get("/api/results")
def results(settings: SettingsDep) -> FileResponse:
    """The numbers behind docs/RESULTS.md's figures (written by `mtrnn report`)."""
    path = settings.figures_dir / "results.json"
    if not path.is_file():
        raise HTTPException(404, "no results yet: run `mtrnn evaluate`, `mtrnn sweep` and `mtrnn report`")
    return FileResponse(path, media_type="application/json", headers={"Cache-Control": "no-cache"})


@router.get("/api/results/figures/{name}")
def result_figure(settings: SettingsDep, name: str) -> FileResponse:
    path = (settings.figures_dir / name).resolve()
    if path.parent != settings.figures_dir.resolve() or path.suffix != ".png" or not path.is_file():
        raise HTTPException(404, f"no figure {name!r}")
    return FileResponse(path, media_type="image/png")
