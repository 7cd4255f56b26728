#!/usr/bin/env python3
"""Flight recorder benchmark (loopback only, stops by itself).

Starts the demo cell's whole stack (scripts/stack.js: roscore, the sim, every node of config/demo-cell.yaml, the
BFF) with its own ports and DATA_DIR, runs the process, and watches the recorder node (cell_nodes recorder_node)
with the demo cell's topics at their real rates: its CPU (% of one core) and RSS while the ring fills to the cell
file's before_s + after_s, then a save by hand (/cell/recorder/save): the time from the end of its `after` seconds
to the file on disk, the file's size and what is in it (messages per topic and rate, from its JSON description).
Usage: python bench/recorder_bench.py [--seconds 150]
BENCH_QUICK=1 (npm run bench -- --quick): 25 s, the ring only partly filled (the RSS then reads lower).
"""
from __future__ import annotations

import argparse
import json
import os
import re
import signal
import subprocess
import tempfile
import time
import xmlrpc.client
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PORT = 29380
UR_HOST = "127.0.0.43"
TICK = os.sysconf("SC_CLK_TCK")


def node_pid(master: str, node: str) -> int:
    code, _, uri = xmlrpc.client.ServerProxy(master).lookupNode("/bench", node)
    if code != 1:
        raise RuntimeError(f"no node {node}")
    return int(xmlrpc.client.ServerProxy(uri).getPid("/bench")[2])


def cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK      # utime + stime


def rss_mib(pid: int, key: str = "VmRSS") -> float:
    m = re.search(rf"^{key}:\s+(\d+) kB", Path(f"/proc/{pid}/status").read_text(), re.M)
    return int(m.group(1)) / 1024 if m else float("nan")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=25.0 if os.environ.get("BENCH_QUICK") else 150.0)
    args = ap.parse_args()
    data_dir = tempfile.mkdtemp(prefix="recorder-bench-")
    master = f"http://127.0.0.1:{PORT + 1}"
    env = dict(os.environ, PORT=str(PORT), TLS_PORT=str(PORT + 3), ROS_MASTER_URI=master,
               ROSBRIDGE_PORT=str(PORT + 2), DATA_DIR=data_dir, UR_HOST=UR_HOST)
    log = open(os.path.join(data_dir, "stack.log"), "w")
    stack = subprocess.Popen(["node", "scripts/stack.js"], cwd=ROOT, env=env, stdout=log, stderr=subprocess.STDOUT,
                             start_new_session=True)
    try:
        t0 = time.monotonic()
        while "[stack] ready:" not in Path(log.name).read_text():
            if stack.poll() is not None or time.monotonic() - t0 > 180:
                raise SystemExit(f"the stack did not start:\n{Path(log.name).read_text()[-3000:]}")
            time.sleep(0.2)
        print(f"stack ready in {time.monotonic() - t0:.1f} s (DATA_DIR {data_dir})")
        ready = time.time()
        os.environ.update(ROS_MASTER_URI=master)
        import rospy
        from cell_msgs.msg import RecorderState
        from cell_msgs.srv import ProcessStart
        from std_srvs.srv import Trigger
        rospy.init_node("bench", anonymous=True, disable_signals=True)
        rospy.wait_for_service("/cell/recorder/save", 30)
        rospy.wait_for_service("/cell/process/start", 30)
        states: list = []
        rospy.Subscriber("/cell/recorder/state", RecorderState, lambda m: states.append((time.time(), m)))
        pid = node_pid(master, "/recorder")
        r = rospy.ServiceProxy("/cell/process/start", ProcessStart)(cycles=0)
        print(f"process start: {r.success} {r.message}; recorder pid {pid}, watching for {args.seconds:.0f} s")

        c0, w0 = cpu_s(pid), time.monotonic()
        samples = []
        while time.monotonic() - w0 < args.seconds:
            time.sleep(5)
            samples.append((time.monotonic() - w0, cpu_s(pid), rss_mib(pid)))
            if len(samples) % 6 == 0:
                t, c, m = samples[-1]
                print(f"  {t:5.0f} s: CPU {100 * (c - c0) / t:4.1f} % of one core so far, RSS {m:.1f} MiB")
        c1, w1 = cpu_s(pid), time.monotonic()
        cpu = 100 * (c1 - c0) / (w1 - w0)
        rss_first, rss_last = samples[0][2], samples[-1][2]

        answer = rospy.ServiceProxy("/cell/recorder/save", Trigger)()
        saved_count = states[-1][1].saved_count if states else 0
        deadline = time.time() + 120
        while not (states and states[-1][1].saved_count > saved_count):
            if time.time() > deadline:
                raise SystemExit("no recording saved")
            time.sleep(0.05)
        at, st = states[-1]
        end = next(m.pending_until.to_sec() for _, m in reversed(states) if m.pending)
        path = Path(data_dir) / "recordings" / st.last_saved
        about = json.loads(path.with_suffix(".json").read_text())
        dur = about["duration_s"]
        covered = min(dur, end - ready)     # a window reaching back before the stack was up holds less
        print(f"recorder: CPU {cpu:.1f} % of one core (mean over {w1 - w0:.0f} s, process running), "
              f"RSS {rss_first:.1f} MiB after 5 s -> {rss_last:.1f} MiB at {w1 - w0:.0f} s (peak {rss_mib(pid, 'VmHWM'):.1f})")
        print(f"save by hand ({answer.message}): written {at - end:.2f} s after its window ended; "
              f"{about['size'] / 2**20:.2f} MiB MCAP (zstd), {about['messages']} messages over {dur:.0f} s "
              f"({about['size'] / covered / 1024:.1f} KiB/s on disk over the {covered:.0f} s the stack was up)")
        for t in sorted(about["topics"], key=lambda t: -t["count"]):
            print(f"  {t['topic']:<28} {t['type']:<32} {t['count']:>7}  {t['count'] / covered:7.1f} Hz")
    finally:
        os.killpg(stack.pid, signal.SIGINT)
        try:
            stack.wait(30)
        except subprocess.TimeoutExpired:
            os.killpg(stack.pid, signal.SIGKILL)
        log.close()


if __name__ == "__main__":
    main()
