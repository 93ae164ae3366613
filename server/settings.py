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
MTRNN_USER_DIR                the app's own data: models trained in the app (models/), its jobs table
                              and its evaluations' run store (runs/); default runs/app
MTRNN_MAX_JOBS                training / evaluation jobs running at once (default: 1 per 2 cores)
MTRNN_DECODE_SLOTS            uploads read and encoded at once (default: one per core)
MTRNN_ALLOWED_HOSTS           comma-separated Host names the app answers (default: loopback names)
MTRNN_TOKEN                   access token; required when the app listens on a non-loopback address
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parent.parent
WEB_DIR = REPO_ROOT / "web"
DEFAULT_JOB_DATA = "server.jobs.kinds:corpus_data"
LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1", "[::1]")
CORES = os.cpu_count() or 1


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
    # A live cosine run (lesson 5) learns by the paper's rule at the calibrated zeta_gain, which takes
    # 12,000-16,000 epochs at small psi to converge (docs/experiments/faithful.md); live, it stops here
    # (about 10 s on one idle core), and the lesson shows the converged numbers beside it.
    cosine_epochs: int = 2500
    cosine_snapshot_every: int = 10  # epochs between two Csc snapshots of a live cosine run
    user_dir: Path = REPO_ROOT / "runs" / "app"  # models trained in the app, its jobs and evaluations
    max_jobs: int = max(1, CORES // 2)  # training / evaluation jobs running at once
    decode_slots: int = CORES  # uploads read and encoded at once; the others wait or get 503
    max_json_bytes: int = 1024**2  # largest JSON request body
    allowed_hosts: tuple[str, ...] = LOOPBACK_HOSTS  # Host names the app answers
    token: str | None = None  # access token (required on a non-loopback address)

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
        for name, key in (
            ("MTRNN_FRAME_CACHE", "frame_cache"),
            ("MTRNN_MAX_JOBS", "max_jobs"),
            ("MTRNN_DECODE_SLOTS", "decode_slots"),
        ):
            if name in os.environ:
                values[key] = int(os.environ[name])
        if "MTRNN_ALLOWED_HOSTS" in os.environ:
            values["allowed_hosts"] = tuple(
                h.strip() for h in os.environ["MTRNN_ALLOWED_HOSTS"].split(",") if h.strip()
            )
        if os.environ.get("MTRNN_TOKEN"):
            values["token"] = os.environ["MTRNN_TOKEN"]
        for name, key in (
            ("MTRNN_MODELS_DIR", "models_dir"),
            ("MTRNN_CORPUS", "corpus_path"),
            ("MTRNN_RUN_DIR", "run_dir"),
            ("MTRNN_FIGURES_DIR", "figures_dir"),
            ("MTRNN_USER_DIR", "user_dir"),
        ):
            if (p := _env_path(name)) is not None:
                values[key] = p
        values.update({k: v for k, v in overrides.items() if v is not None})
        return cls(**values)  # type: ignore[arg-type]
