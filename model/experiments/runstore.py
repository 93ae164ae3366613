"""SQLite store of evaluation runs: their configs, metrics per split, artifacts and checkpoints.

One store lives in a run directory (`<run_dir>/runs.sqlite`, checkpoints under
`<run_dir>/checkpoints/<run key>/`). Only the driver process writes to it (workers return their
results), every write is one transaction, and a run counts as done only once its metrics row and
status are committed together, so a killed evaluation loses at most the runs in flight and a
restart with the same command skips every finished run.

Tables
    configs(hash, json)                          each distinct configuration once
    runs(key, experiment, mode, fold, init, seed, config_hash, params, data_digest,
         status, attempts, seconds, checkpoint, host, created, finished, error,
         split, train_scenes)                   the protocol split (model.experiments.splits)
    metrics(run_key, split, name, value)         split in train / test / mixed (or a sweep's own)
    artifacts(run_key, name, json)               larger per-run results (Csc points for PCA panels)
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import socket
import sqlite3
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

SCHEMA = """
CREATE TABLE IF NOT EXISTS configs (
    hash TEXT PRIMARY KEY,
    json TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS runs (
    key TEXT PRIMARY KEY,
    experiment TEXT NOT NULL,
    mode TEXT NOT NULL,
    fold INTEGER NOT NULL,
    init INTEGER NOT NULL,
    seed INTEGER NOT NULL,
    config_hash TEXT NOT NULL REFERENCES configs(hash),
    params TEXT NOT NULL,
    data_digest TEXT NOT NULL,
    status TEXT NOT NULL CHECK (status IN ('pending', 'running', 'done', 'failed')),
    attempts INTEGER NOT NULL DEFAULT 0,
    seconds REAL,
    checkpoint TEXT,
    host TEXT,
    created REAL NOT NULL,
    finished REAL,
    error TEXT,
    split TEXT NOT NULL DEFAULT 'scenes',
    train_scenes INTEGER
);
CREATE INDEX IF NOT EXISTS runs_experiment ON runs(experiment, status);
CREATE TABLE IF NOT EXISTS metrics (
    run_key TEXT NOT NULL REFERENCES runs(key) ON DELETE CASCADE,
    split TEXT NOT NULL,
    name TEXT NOT NULL,
    value REAL,
    PRIMARY KEY (run_key, split, name)
);
CREATE TABLE IF NOT EXISTS artifacts (
    run_key TEXT NOT NULL REFERENCES runs(key) ON DELETE CASCADE,
    name TEXT NOT NULL,
    json TEXT NOT NULL,
    PRIMARY KEY (run_key, name)
);
"""

DB_NAME = "runs.sqlite"
# columns added after the first stores were written: (name, declaration) added to an older store
ADDED_COLUMNS = (("split", "TEXT NOT NULL DEFAULT 'scenes'"), ("train_scenes", "INTEGER"))


def canonical_json(value: Any) -> str:
    """JSON with sorted keys and no whitespace: equal values give equal strings (and hashes)."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), default=_json_default)


def _json_default(value: Any) -> Any:
    if hasattr(value, "tolist"):
        return value.tolist()
    if hasattr(value, "item"):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def digest(value: Any, length: int = 16) -> str:
    return hashlib.sha256(canonical_json(value).encode()).hexdigest()[:length]


@dataclass(frozen=True)
class RunSpec:
    """One training + evaluation: everything that determines its numbers, and nothing else."""

    experiment: str  # e.g. "evaluate", "psi_s", "cosine"
    mode: str  # training mode: faithful, end_to_end, peer (or "cosine")
    fold: int
    init: int
    seed: int
    config: Mapping[str, Any] = field(default_factory=dict)  # full config as a dict (or {} = defaults)
    params: Mapping[str, Any] = field(default_factory=dict)  # sweep coordinates, e.g. {"psi_s": 5e-4}
    data_digest: str = ""
    split: str = "scenes"  # model.experiments.splits.SPLITS; the paper's 50:50 by scene by default
    train_scenes: int | None = None  # the size split's training scenes

    @property
    def config_hash(self) -> str:
        return digest(self.config)

    @property
    def key(self) -> str:
        """Stable identity of the run: equal specs give equal keys across processes and machines.
        The split joins the identity only when it is not the paper's, so the keys of the runs
        stored before there were other splits stay theirs."""
        identity: dict[str, Any] = {
            "experiment": self.experiment,
            "mode": self.mode,
            "fold": self.fold,
            "init": self.init,
            "seed": self.seed,
            "config": self.config_hash,
            "params": dict(self.params),
            "data": self.data_digest,
        }
        if self.split != "scenes":
            identity.update({"split": self.split, "train_scenes": self.train_scenes})
        return digest(identity, length=20)


@dataclass
class RunRecord:
    key: str
    experiment: str
    mode: str
    fold: int
    init: int
    seed: int
    config: dict
    params: dict
    status: str
    attempts: int
    seconds: float | None
    checkpoint: str | None
    finished: float | None
    metrics: dict[str, dict[str, float]]
    split: str = "scenes"
    train_scenes: int | None = None


def _add_column(db: sqlite3.Connection, name: str, declaration: str) -> None:
    """Add a column to an older store's runs table (another process may have just added it)."""
    try:
        db.execute(f"ALTER TABLE runs ADD COLUMN {name} {declaration}")
    except sqlite3.OperationalError as err:
        if "duplicate column" not in str(err):
            raise


class RunStore:
    """The run directory's SQLite database. Safe to open from several processes (WAL, busy timeout);
    writes are single transactions."""

    def __init__(self, run_dir: str | os.PathLike) -> None:
        self.run_dir = Path(run_dir)
        self.run_dir.mkdir(parents=True, exist_ok=True)
        self.path = self.run_dir / DB_NAME
        self.checkpoint_dir = self.run_dir / "checkpoints"
        with self._connect() as db:
            db.executescript(SCHEMA)
            present = {row["name"] for row in db.execute("PRAGMA table_info(runs)")}
            for name, declaration in ADDED_COLUMNS:
                if name not in present:
                    _add_column(db, name, declaration)

    # --- plumbing -------------------------------------------------------------------------------

    def _connect(self) -> sqlite3.Connection:
        db = sqlite3.connect(self.path, timeout=30.0, isolation_level=None)
        db.row_factory = sqlite3.Row
        db.execute("PRAGMA journal_mode=WAL")
        db.execute("PRAGMA synchronous=FULL")
        db.execute("PRAGMA foreign_keys=ON")
        return db

    @contextmanager
    def _transaction(self) -> Iterator[sqlite3.Connection]:
        db = self._connect()
        try:
            db.execute("BEGIN IMMEDIATE")
            yield db
            db.execute("COMMIT")
        except BaseException:
            db.execute("ROLLBACK")
            raise
        finally:
            db.close()

    @contextmanager
    def _read(self) -> Iterator[sqlite3.Connection]:
        db = self._connect()
        try:
            yield db
        finally:
            db.close()

    # --- runs -----------------------------------------------------------------------------------

    def register(self, specs: list[RunSpec]) -> None:
        """Record the planned runs (pending) unless already known; finished runs stay untouched."""
        now = time.time()
        with self._transaction() as db:
            for spec in specs:
                db.execute(
                    "INSERT OR IGNORE INTO configs(hash, json) VALUES (?, ?)",
                    (spec.config_hash, canonical_json(spec.config)),
                )
                db.execute(
                    "INSERT OR IGNORE INTO runs(key, experiment, mode, fold, init, seed, config_hash, params,"
                    " data_digest, status, created, split, train_scenes)"
                    " VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, 'pending', ?, ?, ?)",
                    (
                        spec.key,
                        spec.experiment,
                        spec.mode,
                        spec.fold,
                        spec.init,
                        spec.seed,
                        spec.config_hash,
                        canonical_json(spec.params),
                        spec.data_digest,
                        now,
                        spec.split,
                        spec.train_scenes,
                    ),
                )

    def done_keys(self, keys: list[str] | None = None) -> set[str]:
        with self._read() as db:
            rows = db.execute("SELECT key FROM runs WHERE status = 'done'").fetchall()
        done = {r["key"] for r in rows}
        return done if keys is None else done & set(keys)

    def mark_running(self, key: str) -> None:
        with self._transaction() as db:
            db.execute(
                "UPDATE runs SET status = 'running', attempts = attempts + 1, host = ? "
                "WHERE key = ? AND status != 'done'",
                (socket.gethostname(), key),
            )

    def write_checkpoint(self, key: str, files: Mapping[str, bytes]) -> Path:
        """Write a run's checkpoint files atomically: into a temporary folder, then one rename."""
        final = self.checkpoint_dir / key
        tmp = self.checkpoint_dir / f".{key}.tmp-{os.getpid()}"
        if tmp.exists():
            shutil.rmtree(tmp)
        tmp.mkdir(parents=True)
        for name, data in files.items():
            (tmp / name).write_bytes(data)
        if final.exists():
            shutil.rmtree(final)
        os.replace(tmp, final)
        return final

    def finish(
        self,
        key: str,
        metrics: Mapping[str, Mapping[str, float]],
        seconds: float,
        checkpoint: str | None = None,
        artifacts: Mapping[str, Any] | None = None,
    ) -> None:
        """Commit one finished run: metrics per split, artifacts and status in one transaction."""
        with self._transaction() as db:
            cur = db.execute(
                "UPDATE runs SET status = 'done', seconds = ?, checkpoint = ?, finished = ?, error = NULL "
                "WHERE key = ?",
                (seconds, checkpoint, time.time(), key),
            )
            if cur.rowcount != 1:
                raise KeyError(f"run {key} was never registered")
            db.execute("DELETE FROM metrics WHERE run_key = ?", (key,))
            db.execute("DELETE FROM artifacts WHERE run_key = ?", (key,))
            for split, values in metrics.items():
                for name, value in values.items():
                    if isinstance(value, bool | int | float):
                        db.execute(
                            "INSERT INTO metrics(run_key, split, name, value) VALUES (?, ?, ?, ?)",
                            (key, split, name, float(value)),
                        )
            for name, value in (artifacts or {}).items():
                db.execute(
                    "INSERT INTO artifacts(run_key, name, json) VALUES (?, ?, ?)",
                    (key, name, canonical_json(value)),
                )

    def fail(self, key: str, error: str) -> None:
        with self._transaction() as db:
            db.execute("UPDATE runs SET status = 'failed', error = ? WHERE key = ?", (error[-4000:], key))

    def runs(
        self,
        experiment: str | None = None,
        mode: str | None = None,
        status: str | None = "done",
        keys: list[str] | None = None,
        split: str | None = None,
    ) -> list[RunRecord]:
        """Runs with configs and metrics ({split: {name: value}}), by mode, params, fold, init
        (`split`: only the runs of that protocol split)."""
        where, args = [], []
        filters = (("r.experiment", experiment), ("r.mode", mode), ("r.status", status), ("r.split", split))
        for column, value in filters:
            if value is not None:
                where.append(f"{column} = ?")
                args.append(value)
        if keys is not None:
            where.append(f"r.key IN ({','.join('?' * len(keys))})")
            args.extend(keys)
        sql = (
            "SELECT r.*, c.json AS config_json FROM runs r JOIN configs c ON c.hash = r.config_hash"
            + (" WHERE " + " AND ".join(where) if where else "")
            + " ORDER BY r.mode, r.params, r.train_scenes, r.fold, r.init"
        )
        with self._read() as db:
            rows = db.execute(sql, args).fetchall()
            metric_rows = db.execute("SELECT run_key, split, name, value FROM metrics").fetchall()
        metrics: dict[str, dict[str, dict[str, float]]] = {}
        for m in metric_rows:
            metrics.setdefault(m["run_key"], {}).setdefault(m["split"], {})[m["name"]] = m["value"]
        return [
            RunRecord(
                key=r["key"],
                experiment=r["experiment"],
                mode=r["mode"],
                fold=r["fold"],
                init=r["init"],
                seed=r["seed"],
                config=json.loads(r["config_json"]),
                params=json.loads(r["params"]),
                status=r["status"],
                attempts=r["attempts"],
                seconds=r["seconds"],
                checkpoint=r["checkpoint"],
                finished=r["finished"],
                metrics=metrics.get(r["key"], {}),
                split=r["split"],
                train_scenes=r["train_scenes"],
            )
            for r in rows
        ]

    def artifact(self, key: str, name: str) -> Any | None:
        with self._read() as db:
            row = db.execute(
                "SELECT json FROM artifacts WHERE run_key = ? AND name = ?", (key, name)
            ).fetchone()
        return None if row is None else json.loads(row["json"])

    def experiments(self) -> list[str]:
        with self._read() as db:
            return [r[0] for r in db.execute("SELECT DISTINCT experiment FROM runs ORDER BY experiment")]
