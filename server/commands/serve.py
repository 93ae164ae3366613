"""`mtrnn serve`: the explorer app (REST, web pages and the 3D view) on one origin.

On a loopback address (the default, 127.0.0.1) the app is open to this machine's users. On any
other address (``--host 0.0.0.0``) it needs an access token (``--token`` or MTRNN_TOKEN) and
refuses to start without one; the one URL it prints carries the token once (``?token=...``), which
the app swaps for a cookie (`server.guard`). uvicorn runs with the limits of `server.connections`.
"""

from __future__ import annotations

import argparse
import sys


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("serve", help="start the explorer web app")
    parser.add_argument("--host", default=None, help="interface to listen on (default 127.0.0.1)")
    parser.add_argument("--port", type=int, default=None, help="port (default 8000)")
    parser.add_argument("--model", default=None, help="model folder name under data/artefacts/models")
    parser.add_argument("--no-viewer", action="store_true", help="do not start the 3D viewer")
    parser.add_argument(
        "--token",
        default=None,
        help="access token (default MTRNN_TOKEN); required when --host is not a loopback address",
    )
    parser.set_defaults(func=run)


def url_of(host: str, port: int, token: str | None) -> str:
    """The one URL a person opens (with the token, once, when there is one)."""
    shown = "localhost" if host in ("127.0.0.1", "0.0.0.0", "::", "") else host
    shown = f"[{shown}]" if ":" in shown else shown
    return f"http://{shown}:{port}/" + (f"?token={token}" if token else "")


def run(args: argparse.Namespace) -> int:
    from server.guard import is_loopback
    from server.settings import Settings

    settings = Settings.from_env(
        host=args.host,
        port=args.port,
        model=args.model,
        viser=False if args.no_viewer else None,
        token=args.token,
    )
    if not is_loopback(settings.host) and not settings.token:
        print(
            f"mtrnn serve: listening on {settings.host} opens the app to other machines, so it needs "
            "an access token: pass --token <secret> or set MTRNN_TOKEN (e.g. "
            "MTRNN_TOKEN=$(python -c 'import secrets; print(secrets.token_urlsafe(24))')).",
            file=sys.stderr,
        )
        return 2
    import torch
    import uvicorn

    from server.app import create_app
    from server.connections import uvicorn_config

    torch.set_num_threads(1)  # small nets: one thread per request beats two fighting over 2 cores
    server = uvicorn.Server(uvicorn_config(create_app(settings), settings))
    print(f"MultiMTRNN explorer: {url_of(settings.host, settings.port, settings.token)}", flush=True)
    server.run()
    return 0
