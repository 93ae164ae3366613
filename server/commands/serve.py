"""`mtrnn serve`: the explorer app (REST, web pages and the 3D view) on one origin."""

from __future__ import annotations

import argparse


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("serve", help="start the explorer web app")
    parser.add_argument("--host", default=None, help="interface to listen on (default 127.0.0.1)")
    parser.add_argument("--port", type=int, default=None, help="port (default 8000)")
    parser.add_argument("--model", default=None, help="model folder name under data/artefacts/models")
    parser.add_argument("--no-viewer", action="store_true", help="do not start the 3D viewer")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import torch
    import uvicorn

    from server.app import create_app
    from server.settings import Settings

    torch.set_num_threads(1)  # small nets: one thread per request beats two fighting over 2 cores
    settings = Settings.from_env(
        host=args.host, port=args.port, model=args.model, viser=False if args.no_viewer else None
    )
    app = create_app(settings)
    config = uvicorn.Config(app, host=settings.host, port=settings.port, log_level="info")
    server = uvicorn.Server(config)
    shown = "localhost" if settings.host in ("127.0.0.1", "0.0.0.0") else settings.host
    print(f"MultiMTRNN explorer: http://{shown}:{settings.port}/", flush=True)
    server.run()
    return 0
