"""The jobs table of the app: its own SQLite file in the app's folder (`<user_dir>/jobs.sqlite`).

One row per training or evaluation job, so that the Jobs page lists them after a server restart;
a job that was running when the server stopped is marked "interrupted" by the next one.

    jobs(id, kind, params, status, created, updated, progress, result, error)
"""

from __future__ import annotations

import json
import sqlite3
import threading
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from server.jobs.events import finite

DB_NAME = "jobs.sqlite"
SCHEMA = """
CREATE TABLE IF NOT EXISTS jobs (
    id TEXT PRIMARY KEY,
    kind TEXT NOT NULL,
    params TEXT NOT NULL,
    status TEXT NOT NULL,
    created REAL NOT NULL,
    updated REAL NOT NULL,
    progress TEXT,
    result TEXT,
    error TEXT
);
"""
INTERRUPTED = "the server stopped while this job was running"


def _json(value: Any) -> str:
    """Strict JSON: numpy values as numbers and lists, NaN and infinities as null."""
    return json.dumps(finite(value), sort_keys=True, separators=(",", ":"), allow_nan=False)


class JobStore:
    """Rows of the jobs table; every write is one transaction."""

    def __init__(self, folder: Path) -> None:
        folder.mkdir(parents=True, exist_ok=True)
        self.path = folder / DB_NAME
        self._lock = threading.Lock()
        with self._db() as db:
            db.executescript(SCHEMA)

    @contextmanager
    def _db(self) -> Iterator[sqlite3.Connection]:
        with self._lock:
            db = sqlite3.connect(self.path, timeout=30)
            db.row_factory = sqlite3.Row
            try:
                with db:
                    yield db
            finally:
                db.close()

    def put(self, job_id: str, kind: str, params: Mapping[str, Any], status: str) -> None:
        now = time.time()
        with self._db() as db:
            db.execute(
                "INSERT INTO jobs(id, kind, params, status, created, updated) VALUES (?, ?, ?, ?, ?, ?)",
                (job_id, kind, _json(params), status, now, now),
            )

    def update(
        self,
        job_id: str,
        status: str | None = None,
        progress: Any | None = None,
        result: Any | None = None,
        error: str | None = None,
    ) -> None:
        sets, args = ["updated = ?"], [time.time()]
        for column, value in (("status", status), ("error", error)):
            if value is not None:
                sets.append(f"{column} = ?")
                args.append(value)
        for column, value in (("progress", progress), ("result", result)):
            if value is not None:
                sets.append(f"{column} = ?")
                args.append(_json(value))
        with self._db() as db:
            db.execute(f"UPDATE jobs SET {', '.join(sets)} WHERE id = ?", [*args, job_id])

    def jobs(self, job_id: str | None = None) -> list[dict[str, Any]]:
        """Every job (newest first), or the one with `job_id`."""
        sql = "SELECT * FROM jobs" + (" WHERE id = ?" if job_id else "") + " ORDER BY created DESC"
        with self._db() as db:
            rows = db.execute(sql, (job_id,) if job_id else ()).fetchall()
        out = []
        for r in rows:
            d = dict(r)
            for column in ("params", "progress", "result"):
                d[column] = json.loads(d[column]) if d[column] else None
            out.append(d)
        return out

    def mark_interrupted(self, active: tuple[str, ...]) -> list[str]:
        """Jobs that were active when the server stopped can never finish: mark them interrupted."""
        with self._db() as db:
            marks = ",".join("?" * len(active))
            ids = [r["id"] for r in db.execute(f"SELECT id FROM jobs WHERE status IN ({marks})", active)]
            for job_id in ids:
                db.execute(
                    "UPDATE jobs SET status = 'interrupted', updated = ?, error = ? WHERE id = ?",
                    (time.time(), INTERRUPTED, job_id),
                )
        return ids
