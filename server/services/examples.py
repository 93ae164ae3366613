"""The recordings to try (`data.examples`): listed, and each written once as a format-v1 .zip.

A recording is rendered on its first request (a second or two) and kept under
``<settings.user_dir>/examples/`` (atomic write), so the download after that is a file. One is
rendered at a time: the catalogue is fixed, so the folder never holds more than its recordings.
"""

from __future__ import annotations

import logging
import threading
import time
from pathlib import Path

from data.examples import EXAMPLES, VERSION, Example, write_example
from server.services.errors import NotFound

logger = logging.getLogger(__name__)


class ExampleService:
    """The catalogue of recordings to try and their .zip files, made on first use."""

    def __init__(self, user_dir: Path) -> None:
        self.folder = Path(user_dir) / "examples"
        self._lock = threading.Lock()  # one recording rendered at a time

    def catalogue(self) -> list[Example]:
        return list(EXAMPLES.values())

    def example(self, name: str) -> Example:
        try:
            return EXAMPLES[name]
        except KeyError:
            raise NotFound(f"no example {name!r}; GET /api/examples lists them") from None

    def path(self, name: str) -> Path:
        """The example's .zip, rendered and written the first time it is asked for."""
        example = self.example(name)
        path = self.folder / f"{example.name}.v{VERSION}.zip"
        with self._lock:
            if not path.is_file():
                started = time.perf_counter()
                write_example(example.name, path)
                logger.info("example %s written in %.1f s", example.name, time.perf_counter() - started)
        return path
