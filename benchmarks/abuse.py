"""The explorer under attack (issue 14): honest uploads while hostile clients send crafted files and
hold slow connections.

    .venv/bin/python benchmarks/abuse.py [--duration 30] [--clients 8] [--slow 200] [--json]

The app is started in its own process (`mtrnn serve --no-viewer`, the shipped corpus and model).
Two phases of `--duration` seconds each:
  1. alone: `--clients` honest clients uploading corpus recordings (exported in format v1, .zip of
     PNG frames) to POST /api/describe, one after another;
  2. attacked: the same honest load, while a ninth client sends the crafted uploads of
     tests/server/hostile_cases.py round and round, and a tenth holds `--slow` connections open,
     sending a request's headers one byte every few seconds.
Prints per phase: honest requests per second, p50 / p99 latency, errors (anything but 200), the
hostile answers by status, and the server's peak RSS (VmHWM; reset between phases). Goals: 0 honest
errors, attacked p50 within 2x of alone, no 5xx to the hostile client, peak RSS under 3 GB, the app
alive at the end.
"""

from __future__ import annotations

import argparse
import json
import socket
import statistics
import sys
import tempfile
import threading
import time
from collections import Counter
from pathlib import Path

import httpx

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests" / "server")]

import hostile_cases  # noqa: E402  (tests/server/hostile_cases.py: the crafted uploads)

from data.corpus import export_recording, load_corpus  # noqa: E402
from data.recording import write_zip  # noqa: E402
from tests.app_builder import serve_in_process  # noqa: E402


def honest_uploads(count: int) -> list[bytes]:
    """`count` corpus recordings as .zip files, as a user exports them."""
    ids = [e.id for e in load_corpus().entries][:: max(1, 256 // count)][:count]
    with tempfile.TemporaryDirectory() as tmp:
        return [write_zip(export_recording(rid, 0), Path(tmp) / f"{rid}.zip").read_bytes() for rid in ids]


def peak_rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def reset_peak_rss(pid: int) -> None:
    Path(f"/proc/{pid}/clear_refs").write_text("5")  # resets VmHWM to the current RSS


def honest_load(url: str, uploads: list[bytes], clients: int, stop: float) -> tuple[list[float], Counter]:
    """Each client uploads recordings one after another until `stop`: (latencies in s of the 200s,
    the other answers by status)."""
    latencies: list[float] = []
    errors: Counter = Counter()
    lock = threading.Lock()

    def client(index: int) -> None:
        with httpx.Client(base_url=url, timeout=120) as c:
            k = index
            while time.perf_counter() < stop:
                data = uploads[k % len(uploads)]
                t0 = time.perf_counter()
                try:
                    status: int | str = c.post(
                        "/api/describe", files={"recording": ("rec.zip", data)}
                    ).status_code
                except httpx.HTTPError as exc:
                    status = type(exc).__name__
                with lock:
                    if status == 200:
                        latencies.append(time.perf_counter() - t0)
                    else:
                        errors[str(status)] += 1
                k += clients

    threads = [threading.Thread(target=client, args=(i,)) for i in range(clients)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return latencies, errors


def hostile_client(url: str, cases: list[hostile_cases.Case], stop: float, statuses: Counter) -> None:
    """The crafted uploads, round and round until `stop`."""
    with httpx.Client(base_url=url, timeout=120) as c:
        k = 0
        while time.perf_counter() < stop:
            case = cases[k % len(cases)]
            try:
                statuses[c.post(case.endpoint, files=case.files()).status_code] += 1
            except httpx.HTTPError as exc:
                statuses[type(exc).__name__] += 1
            k += 1


def slow_connections(port: int, count: int, stop: float, held: list[int]) -> None:
    """`count` connections sending a request's headers a byte every 2 s; reopened when closed."""
    head = b"POST /api/describe HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: " + b"a" * 10_000
    socks: list[tuple[socket.socket, int] | None] = [None] * count
    closed = 0
    while time.perf_counter() < stop:
        for i in range(count):
            try:
                if socks[i] is None:
                    socks[i] = (socket.create_connection(("127.0.0.1", port), timeout=2), 0)
                sock, sent = socks[i]  # type: ignore[misc]
                sock.sendall(head[sent : sent + 1])
                socks[i] = (sock, sent + 1)
            except OSError:
                closed += 1
                socks[i] = None
        held.append(sum(s is not None for s in socks))
        time.sleep(2)
    for s in socks:
        if s is not None:
            s[0].close()
    held.append(-closed)


def summary(latencies: list[float], errors: Counter, seconds: float) -> dict:
    ordered = sorted(latencies) or [float("nan")]
    requests = len(latencies) + sum(errors.values())
    return {
        "requests": requests,
        "rps": requests / seconds,
        "p50_s": statistics.median(ordered),
        "p99_s": ordered[min(len(ordered) - 1, round(0.99 * (len(ordered) - 1)))],
        "errors": sum(errors.values()),
        "error_statuses": dict(errors),
    }


def attacked(url: str, port: int, uploads: list[bytes], args: argparse.Namespace) -> dict:
    """Phase 2: the honest load with the hostile client and the slow connections."""
    cases = [build() for build in hostile_cases.CASES.values()]
    stop = time.perf_counter() + args.duration
    statuses: Counter = Counter()
    held: list[int] = []
    threads = [
        threading.Thread(target=hostile_client, args=(url, cases, stop, statuses)),
        threading.Thread(target=slow_connections, args=(port, args.slow, stop, held)),
    ]
    for t in threads:
        t.start()
    t0 = time.perf_counter()
    latencies, errors = honest_load(url, uploads, args.clients, stop)
    result = summary(latencies, errors, time.perf_counter() - t0)
    for t in threads:
        t.join()
    result["hostile"] = {str(k): v for k, v in sorted(statuses.items(), key=str)}
    result["slow_held_min"] = min(held[:-1], default=0)
    result["slow_closed_by_server"] = -held[-1]
    return result


def run(args: argparse.Namespace) -> dict:
    uploads = honest_uploads(4)
    with serve_in_process(["server.cli", "serve", "--no-viewer"], timeout=180, quiet=True) as (url, proc):
        port = int(url.rsplit(":", 1)[1])
        httpx.post(f"{url}/api/describe", files={"recording": ("w.zip", uploads[0])}, timeout=120)  # warm-up
        reset_peak_rss(proc.pid)
        t0 = time.perf_counter()
        alone = summary(
            *honest_load(url, uploads, args.clients, t0 + args.duration), time.perf_counter() - t0
        )
        alone["peak_rss_mb"] = peak_rss_mb(proc.pid)
        reset_peak_rss(proc.pid)
        under_attack = attacked(url, port, uploads, args)
        under_attack["peak_rss_mb"] = peak_rss_mb(proc.pid)
        alive = httpx.get(f"{url}/api/health", timeout=10).status_code == 200 and proc.poll() is None
    return {
        "upload_bytes": [len(u) for u in uploads],
        "alone": alone,
        "attacked": under_attack,
        "alive": alive,
    }


def print_summary(result: dict, args: argparse.Namespace) -> None:
    for phase in ("alone", "attacked"):
        r = result[phase]
        print(
            f"{phase:8s}: {args.clients} honest clients x {args.duration:g} s: {r['requests']} uploads, "
            f"{r['rps']:.2f} req/s, p50 {r['p50_s']:.2f} s, p99 {r['p99_s']:.2f} s, "
            f"{r['errors']} errors {r['error_statuses'] or ''}; "
            f"server peak RSS {r['peak_rss_mb']:.0f} MB"
        )
    a = result["attacked"]
    print(f"hostile answers by status: {a['hostile']}")
    print(
        f"slow connections held (min over the phase): {a['slow_held_min']} of {args.slow}, "
        f"closed by the server: {a['slow_closed_by_server']}"
    )
    ratio = a["p50_s"] / result["alone"]["p50_s"]
    print(f"attacked p50 / alone p50: {ratio:.2f} (goal <= 2); app alive at the end: {result['alive']}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--duration", type=float, default=30.0, help="seconds of each phase")
    parser.add_argument("--clients", type=int, default=8, help="honest clients")
    parser.add_argument("--slow", type=int, default=200, help="slow connections held")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    result = run(args)
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        print_summary(result, args)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
