"""The zip container both layouts share: opening it and reading a member (whole or as a stream)
with errors that name it. `data.recording.read` checks the members before any is read."""

from __future__ import annotations

import contextlib
import io
import zipfile
import zlib
from collections.abc import Iterator
from typing import IO

from data.recording.format import RecordingError

# What zipfile raises for a damaged, encrypted or oddly compressed member.
ZIP_ERRORS = (zipfile.BadZipFile, zlib.error, EOFError, OSError, NotImplementedError, RuntimeError)


def open_archive(data: bytes, name: str) -> zipfile.ZipFile:
    try:
        return zipfile.ZipFile(io.BytesIO(data))
    except ZIP_ERRORS as exc:
        raise RecordingError(f"corrupt archive: {name} cannot be opened as a zip/npz ({exc})") from exc


def _corrupt(info: zipfile.ZipInfo, name: str, exc: BaseException) -> RecordingError:
    return RecordingError(f"corrupt archive: {info.filename!r} in {name} cannot be read ({exc})")


def read_member(archive: zipfile.ZipFile, info: zipfile.ZipInfo, name: str) -> bytes:
    try:
        return archive.read(info)
    except ZIP_ERRORS as exc:
        raise _corrupt(info, name, exc) from exc


@contextlib.contextmanager
def open_member(archive: zipfile.ZipFile, info: zipfile.ZipInfo, name: str) -> Iterator[IO[bytes]]:
    """A member as a stream (decompressed as it is read); zip errors while reading name it."""
    try:
        with archive.open(info) as stream:
            yield stream
    except ZIP_ERRORS as exc:
        raise _corrupt(info, name, exc) from exc
