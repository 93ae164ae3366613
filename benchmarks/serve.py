"""Explorer app latency and throughput (issue 4), against the shipped corpus and model.

    .venv/bin/python benchmarks/serve.py [--url http://127.0.0.1:8000] [--duration 30] [--json]

Without --url the app is started in its own process (`mtrnn serve --no-viewer`) on the settings
of the environment (MTRNN_CORPUS, MTRNN_MODELS_DIR, MTRNN_MODEL; defaults: the shipped ones).
Measures, over HTTP:
  1. POST /api/scenes/{id}/describe on corpus scenes: p50 / p90 latency (goal p50 <= 20 ms);
  2. POST /api/describe of a 100-frame 320x240 recording (.zip, PNG frames, exported from the
     corpus): p50 latency (goal <= 1.0 s on 2 cores);
  3. 8 concurrent clients for `--duration` seconds (describe, scene list, scene detail): requests
     per second and errors (goal 0).
"""

from __future__ import annotations

import argparse
import io
import json
import statistics
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import httpx

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from data.corpus import export_recording  # noqa: E402
from data.recording import Recording, write_zip  # noqa: E402
from tests.app_builder import serve_in_process  # noqa: E402


@contextmanager
def local_app() -> Iterator[str]:
    """`mtrnn serve --no-viewer` in its own process, as `make run` starts it."""
    with serve_in_process(["server.cli", "serve", "--no-viewer"], timeout=120, quiet=True) as (url, _):
        yield url


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q * (len(ordered) - 1)))]


def upload_of_100_frames(rid: str) -> bytes:
    rec = export_recording(rid, 0)
    steps = min(100, len(rec.joints))
    short = Recording(rec.joints[:steps], rec.frames[:steps], rec.fps, rec.utterance)
    with tempfile.TemporaryDirectory() as tmp:
        return write_zip(short, Path(tmp) / "rec.zip").read_bytes()


def concurrent_load(
    url: str, scenes: list[str], clients: int, duration: float
) -> tuple[dict[str, int], float]:
    """`clients` threads asking for describe, scene list and scene detail for `duration` seconds:
    ({"ok": n, "errors": n}, seconds)."""
    counts = {"ok": 0, "errors": 0}
    lock = threading.Lock()
    stop = time.perf_counter() + duration

    def worker(index: int) -> None:
        with httpx.Client(base_url=url, timeout=60) as c:
            k = index
            while time.perf_counter() < stop:
                rid = scenes[k % len(scenes)]
                kind = k % 4
                try:
                    if kind < 2:
                        r = c.post(f"/api/scenes/{rid}/describe")
                    elif kind == 2:
                        r = c.get("/api/scenes", params={"action": "pull"})
                    else:
                        r = c.get(f"/api/scenes/{rid}")
                    ok = r.status_code == 200
                except httpx.HTTPError:
                    ok = False
                with lock:
                    counts["ok" if ok else "errors"] += 1
                k += clients

    threads = [threading.Thread(target=worker, args=(i,)) for i in range(clients)]
    started = time.perf_counter()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    elapsed = time.perf_counter() - started
    return counts, elapsed


def time_describes(client: httpx.Client, scenes: list[str], count: int) -> dict:
    """Latency of POST /api/scenes/{id}/describe over `count` corpus scenes (after a warm-up)."""
    for rid in scenes[:3]:
        client.post(f"/api/scenes/{rid}/describe").raise_for_status()
    describe_ms = []
    for k in range(count):
        t0 = time.perf_counter()
        client.post(f"/api/scenes/{scenes[k % len(scenes)]}/describe").raise_for_status()
        describe_ms.append((time.perf_counter() - t0) * 1e3)
    return {
        "p50": statistics.median(describe_ms),
        "p90": percentile(describe_ms, 0.9),
        "n": len(describe_ms),
        "goal_p50": 20.0,
    }


def time_uploads(client: httpx.Client, rid: str, count: int) -> dict:
    """Latency of POST /api/describe of a 100-frame recording, with the server's own timings."""
    data = upload_of_100_frames(rid)
    upload_s, server_ms = [], {"read_ms": [], "encode_ms": [], "model_ms": []}
    for _ in range(count):
        t0 = time.perf_counter()
        r = client.post("/api/describe", files={"recording": ("rec.zip", io.BytesIO(data))})
        r.raise_for_status()
        upload_s.append(time.perf_counter() - t0)
        for key in server_ms:
            server_ms[key].append(r.json()["timings"][key])
    return {
        "p50": statistics.median(upload_s),
        "max": max(upload_s),
        "n": len(upload_s),
        "bytes": len(data),
        "goal_p50": 1.0,
        **{f"server_{k}_p50": statistics.median(v) for k, v in server_ms.items()},
    }


def print_summary(result: dict) -> None:
    d, u, c = result["describe_scene_ms"], result["upload_100_frames_s"], result["concurrent"]
    print(
        f"describe corpus scene: p50 {d['p50']:.1f} ms, p90 {d['p90']:.1f} ms (n={d['n']}; goal p50 <= 20 ms)"
    )
    print(
        f"upload 100 frames 320x240 ({u['bytes'] / 2**20:.1f} MiB zip): "
        f"p50 {u['p50']:.2f} s, max {u['max']:.2f} s "
        f"(read {u['server_read_ms_p50']:.0f} ms, encode {u['server_encode_ms_p50']:.0f} ms, "
        f"model {u['server_model_ms_p50']:.0f} ms; goal p50 <= 1.0 s)"
    )
    print(
        f"{c['clients']} clients x {c['seconds']} s: {c['requests']} requests, {c['rps']:.1f} req/s, "
        f"{c['errors']} errors (goal 0)"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--url", default=None, help="a running explorer (default: start one here)")
    parser.add_argument("--duration", type=float, default=30.0, help="seconds of the concurrency test")
    parser.add_argument("--clients", type=int, default=8)
    parser.add_argument("--describes", type=int, default=100, help="corpus describes to time")
    parser.add_argument("--uploads", type=int, default=7, help="uploads to time")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()

    with local_app() if args.url is None else contextmanager(lambda: iter([args.url]))() as url:
        client = httpx.Client(base_url=url, timeout=60)
        scenes = [s["id"] for s in client.get("/api/scenes").json()["scenes"]]
        result = {
            "describe_scene_ms": time_describes(client, scenes, args.describes),
            "upload_100_frames_s": time_uploads(client, scenes[0], args.uploads),
        }
        counts, elapsed = concurrent_load(url, scenes, args.clients, args.duration)
    result["concurrent"] = {
        "clients": args.clients,
        "seconds": round(elapsed, 1),
        "requests": counts["ok"] + counts["errors"],
        "errors": counts["errors"],
        "rps": (counts["ok"] + counts["errors"]) / elapsed,
    }
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        print_summary(result)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
