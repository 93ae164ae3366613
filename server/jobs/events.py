"""What a job's events may carry to a client: finite JSON (NaN and infinities become null, so the
page's JSON.parse reads every event) and errors a person can read (the exception's type and
message, absolute paths cut to their last part; the traceback goes to the server log only).
And, for the Server-Sent Events stream, whether the server is stopping."""

from __future__ import annotations

import json
import math
import re
import signal
from collections.abc import Mapping
from typing import Any

ABSOLUTE_PATH = re.compile(r"(?<![\w.])/(?:[^\s/'\"():,]+/)+([^\s/'\"():,]*)")
MAX_ERROR = 500  # characters of an error message shown to the user


def finite(value: Any) -> Any:
    """`value` with every NaN or infinite float (also inside dicts, lists and numpy values) as None."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [finite(v) for v in value]
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        return finite(value.tolist())
    return value


def to_json(value: Any) -> str:
    """Strict JSON (no NaN, no Infinity) of `finite(value)`."""
    return json.dumps(finite(value), allow_nan=False, separators=(",", ":"))


def sse(event: Mapping[str, Any]) -> str:
    """One Server-Sent Event (its type as the event name, the event as finite JSON)."""
    return f"event: {event.get('type', 'message')}\ndata: {to_json(event)}\n\n"


def public_error(err: BaseException) -> str:
    """ "ValueError: ..." without absolute paths (".../name" stays "name") and at most MAX_ERROR long."""
    text = ABSOLUTE_PATH.sub(lambda m: m.group(1) or "/", f"{type(err).__name__}: {err}")
    return text if len(text) <= MAX_ERROR else text[: MAX_ERROR - 3] + "..."


def server_stopping() -> bool:
    """True once uvicorn has been asked to stop (Ctrl-C, SIGTERM). uvicorn waits for every open
    response before it runs the app's shutdown, so a stream that never ends would hold it: the
    stream asks this instead. uvicorn's signal handler is its `Server.handle_exit`, whose server
    says `should_exit`; anything else (a test client, no signal handler) is never stopping here."""
    server = getattr(signal.getsignal(signal.SIGTERM), "__self__", None)
    return bool(getattr(server, "should_exit", False))
