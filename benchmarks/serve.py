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
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import httpx

from data.corpus import export_recording
from data.recording import Recording, write_zip
from server.viewer import free_port


@contextmanager
def local_app() -> Iterator[str]:
    """`mtrnn serve --no-viewer` in its own process, as `make run` starts it."""
    port = free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "server.cli", "serve", "--no-viewer", "--port", str(port)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.time() + 120
        while True:
            try:
                if httpx.get(f"{url}/api/health", timeout=2).status_code == 200:
                    break
            except httpx.HTTPError:
                pass
            if time.time() > deadline or proc.poll() is not None:
                raise RuntimeError("the explorer did not start (see `mtrnn serve`)")
            time.sleep(0.2)
        yield url
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q * (len(ordered) - 1)))]


def upload_of_100_frames(rid: str) -> bytes:
    rec = export_recording(rid, 0)
    steps = min(100, len(rec.joints))
    short = Recording(rec.joints[:steps], rec.frames[:steps], rec.fps, rec.utterance)
    with tempfile.TemporaryDirectory() as tmp:
        return write_zip(short, Path(tmp) / "rec.zip").read_bytes()


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
        for rid in scenes[:3]:  # warm-up
            client.post(f"/api/scenes/{rid}/describe").raise_for_status()

        describe_ms = []
        for k in range(args.describes):
            t0 = time.perf_counter()
            client.post(f"/api/scenes/{scenes[k % len(scenes)]}/describe").raise_for_status()
            describe_ms.append((time.perf_counter() - t0) * 1e3)

        data = upload_of_100_frames(scenes[0])
        upload_s, server_ms = [], {"read_ms": [], "encode_ms": [], "model_ms": []}
        for _ in range(args.uploads):
            t0 = time.perf_counter()
            r = client.post("/api/describe", files={"recording": ("rec.zip", io.BytesIO(data))})
            r.raise_for_status()
            upload_s.append(time.perf_counter() - t0)
            for key in server_ms:
                server_ms[key].append(r.json()["timings"][key])

        counts = {"ok": 0, "errors": 0}
        lock = threading.Lock()
        stop = time.perf_counter() + args.duration

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
                    k += args.clients

        threads = [threading.Thread(target=worker, args=(i,)) for i in range(args.clients)]
        started = time.perf_counter()
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        elapsed = time.perf_counter() - started

    result = {
        "describe_scene_ms": {
            "p50": statistics.median(describe_ms),
            "p90": percentile(describe_ms, 0.9),
            "n": len(describe_ms),
            "goal_p50": 20.0,
        },
        "upload_100_frames_s": {
            "p50": statistics.median(upload_s),
            "max": max(upload_s),
            "n": len(upload_s),
            "bytes": len(data),
            "goal_p50": 1.0,
            **{f"server_{k}_p50": statistics.median(v) for k, v in server_ms.items()},
        },
        "concurrent": {
            "clients": args.clients,
            "seconds": round(elapsed, 1),
            "requests": counts["ok"] + counts["errors"],
            "errors": counts["errors"],
            "rps": (counts["ok"] + counts["errors"]) / elapsed,
        },
    }
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        d, u, c = result["describe_scene_ms"], result["upload_100_frames_s"], result["concurrent"]
        print(
            f"describe corpus scene: p50 {d['p50']:.1f} ms, p90 {d['p90']:.1f} ms "
            f"(n={d['n']}; goal p50 <= 20 ms)"
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
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
