"""Settings of the explorer app: the one place that reads the environment (prefix ``MTRNN_``).

MTRNN_HOST, MTRNN_PORT        where uvicorn listens (default 127.0.0.1:8000)
MTRNN_MODELS_DIR              folder of shipped models, one sub-folder per model
                              (model.safetensors + meta.json); default data/artefacts/models
MTRNN_MODEL                   the model served first (default: "default", else the first found)
MTRNN_CORPUS                  encoded corpus file (default: data.corpus's own default)
MTRNN_VISER                   "0" starts the app without the 3D viewer (scripts, benchmarks)
MTRNN_FRAME_CACHE             how many corpus recordings keep their re-rendered frames (default 8)
MTRNN_RUN_DIR                 the run store of evaluations and the app's jobs (default runs/)
MTRNN_FIGURES_DIR             where `mtrnn report` wrote its figures (default docs/figures)
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parent.parent
WEB_DIR = REPO_ROOT / "web"
DEFAULT_JOB_DATA = "server.jobs.kinds:corpus_data"


def _env_path(name: str) -> Path | None:
    value = os.environ.get(name)
    return Path(value) if value else None


@dataclass(frozen=True)
class Settings:
    """Everything the app needs to know before it starts; one instance per app."""

    host: str = "127.0.0.1"
    port: int = 8000
    models_dir: Path = REPO_ROOT / "data" / "artefacts" / "models"
    model: str = "default"
    corpus_path: Path | None = None  # None: data.corpus's default location
    viser: bool = True  # start the embedded 3D viewer
    frame_cache: int = 8  # corpus recordings whose rendered frames stay in memory
    upload_cache: int = 16  # uploaded recordings kept for their scene view
    web_dir: Path = field(default=WEB_DIR)
    run_dir: Path = REPO_ROOT / "runs"  # run store (SQLite) of evaluations, and the jobs table
    figures_dir: Path = REPO_ROOT / "docs" / "figures"  # the report's figures (Results page)
    job_data: str = DEFAULT_JOB_DATA  # "module:function" loading a job's SequenceSet
    cosine_epochs: int = 1000  # a live cosine run (lesson 5) stops here if not converged before
    cosine_snapshot_every: int = 10  # epochs between two Csc snapshots of a live cosine run

    @classmethod
    def from_env(cls, **overrides: object) -> Settings:
        """Defaults, then ``MTRNN_*`` variables, then explicit overrides (e.g. CLI flags)."""
        values: dict[str, object] = {}
        if "MTRNN_HOST" in os.environ:
            values["host"] = os.environ["MTRNN_HOST"]
        if "MTRNN_PORT" in os.environ:
            values["port"] = int(os.environ["MTRNN_PORT"])
        if "MTRNN_MODEL" in os.environ:
            values["model"] = os.environ["MTRNN_MODEL"]
        if "MTRNN_VISER" in os.environ:
            values["viser"] = os.environ["MTRNN_VISER"] not in ("0", "false", "no")
        if "MTRNN_FRAME_CACHE" in os.environ:
            values["frame_cache"] = int(os.environ["MTRNN_FRAME_CACHE"])
        for name, key in (
            ("MTRNN_MODELS_DIR", "models_dir"),
            ("MTRNN_CORPUS", "corpus_path"),
            ("MTRNN_RUN_DIR", "run_dir"),
            ("MTRNN_FIGURES_DIR", "figures_dir"),
        ):
            if (p := _env_path(name)) is not None:
                values[key] = p
        values.update({k: v for k, v in overrides.items() if v is not None})
        return cls(**values)  # type: ignore[arg-type]
