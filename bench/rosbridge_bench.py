#!/usr/bin/env python3
"""rosbridge server benchmark (loopback only, stops by itself).

Scenarios (as in TOOLCHAIN.md's reference figures for rosbridge_suite):
- 100 Hz std_msgs/Float64MultiArray (6 values), JSON, to 1 / 10 / 25 clients
- 30 Hz 640x480 JPEG sensor_msgs/CompressedImage, JSON and CBOR, to 1 / 5 clients
Latency = receipt time at the client minus the publish time carried in the message.
Server RSS (max) and CPU (% of one core) are sampled from /proc during each scenario.

Run: cd /work/main && source scripts/ros-env.sh && python bench/rosbridge_bench.py [--duration 5]
(or with scripts/ros2-env.sh: the same server and scenarios on ROS 2 Jazzy; bench/run.sh runs both, one after the
other). BENCH_QUICK=1 (npm run bench -- --quick) makes the default 1.5 s per scenario.
It starts its own roscore (ROS 1; on ROS 2 a domain of its own) and rosbridge_server on free loopback ports and
stops both at the end; the publisher is this process, through the nodes' wiring.
"""
from __future__ import annotations

import argparse
import asyncio
import base64
import io
import json
import multiprocessing as mp
import os
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from typing import Any, Dict, List, Optional, Tuple

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SERVER = os.path.join(ROOT, "ros_backend", "src", "cell_rosbridge", "scripts", "rosbridge_server")
CLK_TCK = os.sysconf("SC_CLK_TCK")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_port(port: int, timeout: float) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.05)
    raise RuntimeError(f"port {port} did not open")


# ------------------------------------------------------------------ clients (separate process)

async def _client(port: int, sub: Dict[str, Any], kind: str, stop_at: float, start_at: float,
                  lat: List[float], counts: List[int], ready: asyncio.Event, n_ready: List[int], n: int) -> None:
    import cbor2
    import websockets
    async with websockets.connect(f"ws://127.0.0.1:{port}", max_size=None, compression=None) as ws:
        await ws.send(json.dumps(sub))
        n_ready[0] += 1
        if n_ready[0] == n:
            ready.set()
        while True:
            left = stop_at - time.time()
            if left <= 0:
                return
            try:
                frame = await asyncio.wait_for(ws.recv(), left)
            except asyncio.TimeoutError:
                return
            now = time.time()
            msg = cbor2.loads(frame) if isinstance(frame, bytes) else json.loads(frame)
            if msg.get("op") != "publish":
                continue
            body = msg["msg"]
            if kind == "array":
                sent = body["data"][0]
            else:
                st = body["header"]["stamp"]  # ROS 1 {secs, nsecs}; ROS 2 {sec, nanosec}
                sent = st.get("secs", st.get("sec", 0)) + st.get("nsecs", st.get("nanosec", 0)) * 1e-9
            if sent >= start_at:  # ignore warm-up messages
                lat.append((now - sent) * 1000.0)
                counts[0] += 1


def client_process(port: int, n: int, sub: Dict[str, Any], kind: str, start_at: float, stop_at: float,
                   conn: Any) -> None:
    async def main() -> Tuple[List[List[float]], List[int]]:
        ready = asyncio.Event()
        n_ready = [0]
        lats: List[List[float]] = [[] for _ in range(n)]
        counts = [[0] for _ in range(n)]
        tasks = [asyncio.create_task(_client(port, sub, kind, stop_at, start_at, lats[i], counts[i], ready,
                                             n_ready, n)) for i in range(n)]
        await asyncio.gather(*tasks)
        return lats, [c[0] for c in counts]

    lats, counts = asyncio.run(main())
    conn.send((lats, counts))
    conn.close()


# ------------------------------------------------------------------ server sampling

class Sampler:
    def __init__(self, pid: int) -> None:
        self.pid = pid

    def cpu_ticks(self) -> int:
        with open(f"/proc/{self.pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return int(fields[11]) + int(fields[12])

    def rss_mb(self) -> float:
        with open(f"/proc/{self.pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
        return 0.0


# ------------------------------------------------------------------ publisher (this process)

def make_jpeg() -> bytes:
    try:
        from PIL import Image
        import random
        rnd = random.Random(1)
        img = Image.new("RGB", (640, 480))
        px = img.load()
        for y in range(0, 480, 4):  # a textured image so JPEG lands near the usual ~30 KB
            for x in range(0, 640, 4):
                c = ((x * 3 + rnd.randrange(40)) % 256, (y * 2 + rnd.randrange(40)) % 256, (x + y) % 256)
                for dy in range(4):
                    for dx in range(4):
                        px[x + dx, y + dy] = c
        buf = io.BytesIO()
        img.save(buf, "JPEG", quality=60)
        return buf.getvalue()
    except ImportError:  # content does not matter to the bridge: random bytes of the same size
        return os.urandom(30_000)


def run_scenario(ros: Any, name: str, port: int, server_pid: int, n_clients: int, rate: float, kind: str,
                 compression: str, duration: float, jpeg: bytes) -> Dict[str, Any]:
    import std_msgs.msg as std
    import sensor_msgs.msg as sensor

    topic = f"/bench_{kind}"
    msg_type = "std_msgs/Float64MultiArray" if kind == "array" else "sensor_msgs/CompressedImage"
    sub = {"op": "subscribe", "id": name, "topic": topic, "type": msg_type, "compression": compression}
    warmup = 1.5
    start_at = time.time() + warmup
    stop_at = start_at + duration + 0.5
    ctx = mp.get_context("spawn")  # not fork: this process already runs the ROS client library's threads
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=client_process, args=(port, n_clients, sub, kind, start_at, stop_at, child),
                      daemon=True)
    proc.start()
    pub = ros.publisher(topic, std.Float64MultiArray if kind == "array" else sensor.CompressedImage, queue_size=100)
    sampler = Sampler(server_pid)
    period = 1.0 / rate
    sent = 0
    rss_max = 0.0
    cpu0: Optional[int] = None
    t_cpu0 = 0.0
    next_t = time.time()
    end_pub = start_at + duration
    while True:
        now = time.time()
        if now >= end_pub:
            break
        if cpu0 is None and now >= start_at:
            cpu0, t_cpu0 = sampler.cpu_ticks(), time.monotonic()
        if kind == "array":
            m = std.Float64MultiArray(data=[time.time(), 1.0, 2.0, 3.0, 4.0, 5.0])
        else:
            m = sensor.CompressedImage(format="jpeg", data=jpeg)
            m.header.stamp = ros.stamp(time.time())
        pub.publish(m)
        if now >= start_at:
            sent += 1
        if sent % 10 == 0:
            rss_max = max(rss_max, sampler.rss_mb())
        next_t += period
        delay = next_t - time.time()
        if delay > 0:
            time.sleep(delay)
    cpu = (sampler.cpu_ticks() - (cpu0 or 0)) / CLK_TCK / max(1e-6, time.monotonic() - t_cpu0) * 100.0
    rss_max = max(rss_max, sampler.rss_mb())
    lats, counts = parent.recv()
    proc.join(10)
    pub.close()
    all_lat = sorted(x for per in lats for x in per)
    q = statistics.quantiles(all_lat, n=100) if len(all_lat) >= 2 else [float("nan")] * 99
    return {
        "scenario": name, "clients": n_clients, "sent": sent,
        "delivered": sum(counts) / max(1, sent * n_clients) * 100.0,
        "rate_per_client": statistics.mean(counts) / duration if counts else 0.0,
        "p50": q[49], "p95": q[94], "cpu": cpu, "rss": rss_max,
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    quick = os.environ.get("BENCH_QUICK") == "1"
    ap.add_argument("--duration", type=float, default=1.5 if quick else 5.0,
                    help="measured seconds per scenario (5; 1.5 with BENCH_QUICK=1)")
    args = ap.parse_args()

    master_port, port = free_port(), free_port()
    home = tempfile.mkdtemp(prefix="rosbridge-bench-")
    ros2 = os.environ.get("ROS_VERSION") == "2"
    core: Optional[subprocess.Popen] = None
    if ros2:  # no master: a domain of its own, discovery on loopback
        os.environ.update(ROS_DOMAIN_ID=str(200 + os.getpid() % 30), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
                          ROS_HOME=home, ROS_LOG_DIR=home)
        server_args = ["--ros-args", "-r", "__node:=rosbridge_bench_server", "-p", f"port:={port}"]
    else:
        os.environ.update(ROS_MASTER_URI=f"http://127.0.0.1:{master_port}", ROS_HOSTNAME="127.0.0.1",
                          ROS_HOME=home, ROS_LOG_DIR=home)
        core = subprocess.Popen(["roscore", "-p", str(master_port)], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, start_new_session=True)
        server_args = [f"_port:={port}", "__name:=rosbridge_bench_server"]
    server: Optional[subprocess.Popen] = None
    try:
        if core is not None:
            import rosgraph
            deadline = time.monotonic() + 20
            while not rosgraph.is_master_online(os.environ["ROS_MASTER_URI"]):
                if time.monotonic() > deadline:
                    raise RuntimeError("roscore did not start")
                time.sleep(0.1)
        server = subprocess.Popen([sys.executable, SERVER, *server_args],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        wait_port(port, 20)
        from cell_nodes import wiring
        ros = wiring.connect("rosbridge_bench", anonymous=True, disable_signals=True)
        jpeg = make_jpeg()
        print(f"rosbridge bench (ROS {2 if ros2 else 1}): loopback, {os.cpu_count()} cores, {args.duration:g} s per "
              f"scenario{' (quick)' if quick else ''}, JPEG {len(jpeg) / 1024:.0f} KB", flush=True)
        scenarios = [
            ("array100Hz-json", 1, 100.0, "array", "none"),
            ("array100Hz-json", 10, 100.0, "array", "none"),
            ("array100Hz-json", 25, 100.0, "array", "none"),
            ("jpeg30Hz-json", 1, 30.0, "image", "none"),
            ("jpeg30Hz-json", 5, 30.0, "image", "none"),
            ("jpeg30Hz-cbor", 1, 30.0, "image", "cbor"),
            ("jpeg30Hz-cbor", 5, 30.0, "image", "cbor"),
        ]
        rows = []
        for name, n, rate, kind, comp in scenarios:
            rows.append(run_scenario(ros, name, port, server.pid, n, rate, kind, comp, args.duration, jpeg))
            r = rows[-1]
            print(f"  done {name} x{n}: p95 {r['p95']:.2f} ms", flush=True)
        print()
        hdr = f"{'scenario':<17}{'clients':>8}{'msgs/s/client':>15}{'delivered':>11}{'p50 ms':>9}{'p95 ms':>9}" \
              f"{'srv CPU %':>11}{'srv RSS MB':>12}"
        print(hdr)
        print("-" * len(hdr))
        for r in rows:
            print(f"{r['scenario']:<17}{r['clients']:>8}{r['rate_per_client']:>15.1f}{r['delivered']:>10.1f}%"
                  f"{r['p50']:>9.2f}{r['p95']:>9.2f}{r['cpu']:>11.1f}{r['rss']:>12.1f}")
        return 0
    finally:
        if server is not None:
            server.send_signal(signal.SIGINT)
            try:
                server.wait(10)
            except subprocess.TimeoutExpired:
                server.kill()
        if core is not None:
            core.send_signal(signal.SIGTERM)
            try:
                core.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(core.pid, signal.SIGKILL)


if __name__ == "__main__":
    sys.exit(main())
