#!/usr/bin/env python3
"""A UDP flood beside a real-time controller run (not a test): what a flood on a shared host
still does to the loop, with and without the settings that protect it.

For each setting, --runs real-time runs of the shipped dry run (configs/paper_frame_controller
.textproto made real time at 1024 Hz, --seconds of motion, its controller on 127.0.0.1 answered
by rths-controller-emulator), alternating a quiet run with one beside a flood: --flooders
processes sending 64 KiB datagrams as fast as they can from other ports to the node's UDP port
(the node's socket never reads them: it is connected and filtered to its controller). Prints per
setting and condition: runs completed, runs stopped and by what (a HOLD of the link, the answer
window, deadline misses), the median overruns, and the datagrams the node judged from a wrong
source (0 expected: the flood never reaches the judge). Exit 0 when no flood run was stopped by
anything judged on the link (a wrong source, an ICMP error), 1 otherwise.

    controller_flood.py [--runs N] [--seconds S] [--flooders F] [--bin DIR] [--settings a,b]

settings: bare (the shipped deployment), priority (realtime_priority: 50), pinned (priority and
pin_loop on the last CPU). Needs the build's rths, rths-controller-emulator and node programs.
"""
import argparse
import os
import re
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time

SOURCE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SETTINGS = {
    "bare": "",
    "priority": "realtime_priority: 50",
    "pinned": "realtime_priority: 50 pin_loop: true loop_cpu: %d" % (os.cpu_count() - 1),
}


def study(seconds, deployment_extra, domain, port):
    text = open(os.path.join(SOURCE, "configs", "paper_frame_controller.textproto")).read()
    text = text.replace('path: "../data/', 'path: "%s/data/' % SOURCE)
    text = text.replace("dt: 0.001 }", "dt: 0.0009765625 }")
    text = text.replace("motion { path:", "motion { duration: %g path:" % seconds)
    text = text.replace("deployment {\n", "deployment {\n  clock: REAL_TIME domain_id: %d "
                        "answer_window_ms: 20 %s\n" % (domain, deployment_extra), 1)
    text = text.replace("local_port: 47210", "local_port: %d" % port)
    text = text.replace("peer_port: 47211", "peer_port: %d" % (port + 1))
    text = text.replace("reply_timeout_ms: 500", "reply_timeout_ms: 0")
    return text


def flooder(port):
    """A process that floods 127.0.0.1:port with 64 KiB datagrams from its own port."""
    code = ("import socket\ns=socket.socket(socket.AF_INET,socket.SOCK_DGRAM)\nb=bytes(65000)\n"
            "while True:\n  try: s.sendto(b,('127.0.0.1',%d))\n  except OSError: pass\n" % port)
    return subprocess.Popen([sys.executable, "-c", code])


def one_run(args, workdir, text, flood, index):
    path = os.path.join(workdir, "study_%d.textproto" % index)
    with open(path, "w") as f:
        f.write(text)
    port = int(re.search(r"local_port: (\d+)", text).group(1))
    emulator = subprocess.Popen([os.path.join(args.bin, "controller_emulator",
                                              "rths-controller-emulator"), "--config", path,
                                 "--node-id", "2", "--case", "lag_shift_14ms"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    floods = [flooder(port) for _ in range(args.flooders)] if flood else []
    time.sleep(0.5)
    out = os.path.join(workdir, "out_%d" % index)
    launch = subprocess.run([os.path.join(args.bin, "cli", "rths"), "launch", path, "--case",
                             "lag_shift_14ms", "--no-plots", "--accept-platform", "--out", out],
                            capture_output=True, text=True, timeout=args.seconds * 4 + 60)
    for p in floods + [emulator]:
        p.send_signal(signal.SIGKILL)
        p.wait()
    return launch.returncode, launch.stdout + launch.stderr


def hold_line(output):
    """The summary's line naming the controller's HOLD."""
    for line in output.splitlines():
        if "controller:" in line:
            return line.strip()[:400]
    return "?"


def judge(output):
    """(stopped by, overruns, wrong-source datagrams) from a launch's summary."""
    overruns = re.search(r"overruns (\d+)", output)
    wrong = re.search(r"wrong source (\d+)", output)
    stopped = "completed"
    for what, pattern in (("deadline misses", "completed with deadline misses"),
                          ("link HOLD", "controller:"), ("answer window", "never applied"),
                          ("node silent", "silent")):
        if pattern in output:
            stopped = what
            break
    return stopped, int(overruns.group(1)) if overruns else -1, int(wrong.group(1)) if wrong else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--flooders", type=int, default=2)
    parser.add_argument("--bin", default=os.path.join(SOURCE, "build"))
    parser.add_argument("--settings", default="bare,priority")
    parser.add_argument("--domain", type=int, default=99)
    args = parser.parse_args()
    ok = True
    with tempfile.TemporaryDirectory() as workdir:
        index = 0
        for name in args.settings.split(","):
            tally = {False: [], True: []}
            for run in range(args.runs):
                for flood in (False, True):
                    index += 1
                    text = study(args.seconds, SETTINGS[name], args.domain, 47360)
                    code, output = one_run(args, workdir, text, flood, index)
                    tally[flood].append((code,) + judge(output))
                    if tally[flood][-1][1] == "link HOLD":
                        print("  %s run %d: %s" % ("flood" if flood else "quiet", index,
                                                 hold_line(output)))
            for flood in (False, True):
                runs = tally[flood]
                stops = [r[1] for r in runs if r[1] != "completed"]
                wrong = sum(r[3] for r in runs)
                overruns = statistics.median([r[2] for r in runs]) if runs else 0
                print("%-9s %-6s %d runs: %d completed, stopped: %s; median overruns %g; "
                      "wrong-source datagrams judged %d" %
                      (name, "flood" if flood else "quiet", len(runs), len(runs) - len(stops),
                       ", ".join(sorted(set(stops))) or "none", overruns, wrong))
                ok = ok and wrong == 0 and not any(s == "link HOLD" for s in stops if flood)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
