"""How `mtrnn serve` bounds its connections: uvicorn's limits and the deadlines it lacks.

uvicorn 0.54 closes an idle keep-alive connection (`timeout_keep_alive`), answers 503 past
`limit_concurrency` and bounds an unfinished header (`h11_max_incomplete_event_size`), but it has
no deadline for a request's header or body: a client sending one byte every few seconds holds
its connection forever. `DeadlineH11Protocol` adds both: a request's header must be complete
`HEADER_TIMEOUT_S` after the connection opened (or the previous answer was sent), its body
`BODY_TIMEOUT_S` after its header; otherwise the connection is closed. A WebSocket, once
upgraded, is no longer an HTTP request and is not concerned.
"""

from __future__ import annotations

import asyncio
from typing import Any

import h11
import uvicorn
from uvicorn.protocols.http.h11_impl import H11Protocol

from server.settings import Settings

HEADER_TIMEOUT_S = 10.0  # a request line and its headers
BODY_TIMEOUT_S = 120.0  # a request body (an upload at the cap over a slow link)
KEEP_ALIVE_S = 5  # an idle keep-alive connection
MAX_CONNECTIONS = 512  # connections and requests at once; beyond: 503
MAX_HEADER_BYTES = 32 * 1024  # an unfinished request line and headers
GRACEFUL_SHUTDOWN_S = 5  # open streams (SSE, WebSockets) at shutdown are closed after this


class DeadlineH11Protocol(H11Protocol):
    """uvicorn's h11 protocol with a deadline for each request's header and body."""

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._deadline: asyncio.TimerHandle | None = None
        self._arm(HEADER_TIMEOUT_S, h11.IDLE)

    def _arm(self, seconds: float, state: type[h11.IDLE] | type[h11.SEND_BODY]) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
        self._deadline = self.loop.call_later(seconds, self._expire, state)

    def _expire(self, state: Any) -> None:
        """Close the connection if the peer is still where it was when the deadline was set."""
        if self.transport.is_closing() or self.transport.get_protocol() is not self:
            return  # closed, or upgraded to a WebSocket
        if self.conn.their_state is state:
            self.transport.close()  # connection_lost tells the request's receive() it is gone

    def handle_events(self) -> None:
        cycle = self.cycle
        super().handle_events()
        if self.cycle is not cycle and self.conn.their_state is h11.SEND_BODY:
            self._arm(BODY_TIMEOUT_S, h11.SEND_BODY)

    def on_response_complete(self) -> None:
        super().on_response_complete()
        self._arm(HEADER_TIMEOUT_S, h11.IDLE)

    def connection_lost(self, exc: Exception | None) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
        super().connection_lost(exc)


def uvicorn_config(app: Any, settings: Settings) -> uvicorn.Config:
    """The uvicorn configuration of `mtrnn serve`, with every limit above."""
    return uvicorn.Config(
        app,
        host=settings.host,
        port=settings.port,
        log_level="info",
        http=DeadlineH11Protocol,
        limit_concurrency=MAX_CONNECTIONS,
        timeout_keep_alive=KEEP_ALIVE_S,
        h11_max_incomplete_event_size=MAX_HEADER_BYTES,
        timeout_graceful_shutdown=GRACEFUL_SHUTDOWN_S,
    )
