"""One verdict per question, whatever the entry point.

Divergence: the same two cases (one that diverges, one that does not) through `rths sdof`, `run`,
`sweep`, `joint-lag`, `launch` (lockstep over DDS), `sites` (when namespaces are permitted) and
Python (rths.sdof, rths.Study.run, rths.Study.launch) get the same verdict and exit code.
Pre-run stability: the same lag against the same critical delay through `run`, `sweep`,
`stability`, Python's rths.sdof and rths.stability, with compensation (a linear compensator
analysed, an adaptive one stated as not analysable with the uncompensated margin beside).

A 4 s motion (a 0.5 s pulse at the frame's period, then free vibration) keeps every run short.
Run from ctest (python_verdicts) with PYTHONPATH=build/python, RTHS_EXECUTABLE and
RTHS_SOURCE_DIR set. `launch` and `sites` on the shared DDS domain, each test on topics of its
own (tests/support/dds_scope.py).
"""
import csv
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import rths

RTHS = os.environ["RTHS_EXECUTABLE"]
BIN_DIR = str(Path(RTHS).resolve().parent.parent)
sys.path.insert(0, str(Path(os.environ["RTHS_SOURCE_DIR"]) / "tests" / "support"))
import dds_scope  # noqa: E402
PERIOD, ZETA, DT = 0.5, 0.05, 0.001
# (name, experimental fraction, shift lag in s, diverges): the frame's critical delay is 7.97 ms
# at alpha = 1 and 24.2 ms at alpha = 1/3.
CASES = [("unstable", 1.0, 0.025, True), ("stable", 1 / 3, 0.014, False)]


@pytest.fixture(scope="module")
def motion(tmp_path_factory):
    path = tmp_path_factory.mktemp("motion") / "pulse.txt"
    with open(path, "w", encoding="utf-8") as f:
        for k in range(4001):
            t = k * DT
            f.write(f"{t:.3f} {math.sin(2 * math.pi * t / PERIOD) if t < 0.5 else 0.0:.9f}\n")
    return path


def cli(*args, timeout=240):
    done = subprocess.run([RTHS, *map(str, args)], capture_output=True, text=True, timeout=timeout)
    assert done.returncode in (0, 1), f"rths {args}: exit {done.returncode}\n{done.stderr}"
    return done


def study_text(motion, fraction, lag, extra=""):
    return (f'name: "verdict"\n'
            f"structure {{ sdof {{ period: {PERIOD} mass: 1000 }} damping {{ modal_zeta: {ZETA} }} }}\n"
            f'motion {{ path: "{motion}" column_units: M_PER_S2 }}\n'
            f"integrator {{ kind: EXPLICIT_NEWMARK dt: {DT} }}\n"
            f"substructuring {{ experimental_fraction: {fraction!r} model {{ linear {{}} }} }}\n"
            f'cases {{ name: "reference" }}\n'
            f'cases {{ name: "lagged" delay {{ shift {{ delay: {lag!r} }} }} }}\n' + extra)


def built(motion, fraction, lag):
    return (rths.Study("verdict").sdof(PERIOD, ZETA).motion(str(motion), units="m/s2")
            .integrator("explicit-newmark", DT).experimental(fraction)
            .case("reference").case("lagged", delay=lag))


@pytest.mark.parametrize("name,fraction,lag,diverges", CASES)
def test_one_divergence_verdict_and_exit_code_everywhere(name, fraction, lag, diverges, motion,
                                                         tmp_path, monkeypatch):
    want_exit = 1 if diverges else 0
    config = tmp_path / "study.textproto"
    config.write_text(study_text(motion, fraction, lag))
    verdicts = {}

    done = cli("sdof", "--period", PERIOD, "--zeta", ZETA, "--motion", motion, "--motion-units",
               "m/s2", "--dt", DT, "--delay", lag, "--exp-fraction", fraction, "--json")
    verdicts["sdof"] = (json.loads(done.stdout)["status"] == "diverged", done.returncode)

    done = cli("run", config, "--out", tmp_path / "run", "--no-plots")
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    verdicts["run"] = (summary["cases"][1]["diverged"], done.returncode)

    sweep = tmp_path / "sweep.textproto"
    sweep.write_text(study_text(motion, fraction, lag).split("cases {")[0] +
                     f"sweep {{ periods: [{PERIOD}] delays: [{lag!r}] experimental_fractions: "
                     f"[{fraction!r}] dts: [{DT}] motions {{ path: \"{motion}\" column_units: "
                     f"M_PER_S2 }} delay_model: SHIFT models {{ linear {{}} }} }}\n")
    done = cli("sweep", sweep, "--out", tmp_path / "sweep", "--no-plots")
    with open(tmp_path / "sweep" / "sweep.csv", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 1
    verdicts["sweep"] = (rows[0]["diverged"] in ("1", "true"), done.returncode)

    joint = tmp_path / "joint.textproto"
    joint.write_text(f'study: "{config}"\nnetwork_round_trips: [0]\nactuator_lags: [{lag!r}]\n'
                     f'output_directory: "{tmp_path / "joint"}"\n')
    done = cli("joint-lag", joint, "--no-plots", "--json")
    verdicts["joint-lag"] = (json.loads(done.stdout)["grid"][0]["diverged"], done.returncode)

    python = rths.sdof(period=PERIOD, zeta=ZETA, motion=str(motion), motion_units="m/s2",
                       delay=lag, experimental_fraction=fraction, allow_unstable=True)
    verdicts["rths.sdof"] = (python["verdict"]["diverged"], want_exit)
    in_process = built(motion, fraction, lag).run()["summary"]["cases"][1]
    verdicts["rths.Study.run"] = (in_process["diverged"], want_exit)

    study = built(motion, fraction, lag).deployment(
        "nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR }")
    launched = study.launch(tmp_path / "launch", domain=dds_scope.scope_dds_to_this_test(monkeypatch),
                            cases=["lagged"], timeout=240)
    case = {c["name"]: c for c in launched["cases"]}["lagged"]
    verdicts["launch (lockstep, via Python)"] = (case["diverged"], launched["exit_code"])

    assert verdicts == {entry: (diverges, want_exit) for entry in verdicts}, verdicts


@pytest.mark.parametrize("name,fraction,lag,diverges", CASES)
def test_sites_gives_the_same_verdict(name, fraction, lag, diverges, motion, tmp_path,
                                      monkeypatch):
    config = tmp_path / "study.textproto"
    config.write_text(study_text(motion, fraction, lag))
    sites = tmp_path / "sites.textproto"
    sites.write_text(f'study: "{config}"\ncase_name: "lagged"\nclock: LOCKSTEP\ntimeout: 120\n'
                     'sites { name: "integrator" node_ids: 0 }\n'
                     'sites { name: "lab" node_ids: [1, 2] }\n'
                     "deployment { nodes { id: 1 kind: SUBSTRUCTURE } "
                     "nodes { id: 2 kind: ACTUATOR_EMULATOR } start_timeout: 20 }\n")
    domain = dds_scope.scope_dds_to_this_test(monkeypatch)
    done = subprocess.run([RTHS, "sites", sites, "--domain", str(domain), "--bin-dir",
                           BIN_DIR, "--out", tmp_path / "sites", "--no-plots"],
                          capture_output=True, text=True, timeout=240)
    if done.returncode == 3:
        pytest.skip(f"namespaces not permitted here: {done.stderr.strip()[-200:]}")
    summary = json.loads((tmp_path / "sites" / "summary.json").read_text())
    assert (summary["cases"][0]["diverged"], done.returncode) == (diverges, 1 if diverges else 0)


def stability_of_case(summary, name):
    return {c["name"]: c for c in summary["cases"]}[name]


def test_one_pre_run_stability_judgement_everywhere(motion, tmp_path):
    # alpha = 1, 9 ms: past the frame's critical delay (bounded over these 4 s).
    fraction, lag = 1.0, 0.009
    done = cli("stability", "--period", PERIOD, "--zeta", ZETA, "--exp-fraction", fraction,
               "--dt", DT, "--json")
    analysis = json.loads(done.stdout)
    assert analysis == rths.stability(PERIOD, ZETA, experimental_fraction=fraction, dt_s=DT)
    continuous = analysis["continuous"]["critical_delay_s"]
    critical = min(continuous, analysis["discrete"]["first_unstable_delay_s"])
    margin = 100.0 * (critical - lag) / critical
    assert margin < 0

    config = tmp_path / "study.textproto"
    config.write_text(study_text(motion, fraction, lag))
    done = cli("run", config, "--out", tmp_path / "run", "--no-plots")
    run = stability_of_case(json.loads((tmp_path / "run" / "summary.json").read_text()), "lagged")
    assert run["stability"]["continuous_critical_delay_s"] == pytest.approx(continuous, rel=1e-9)
    assert run["stability"]["critical_delay_s"] == pytest.approx(critical, rel=1e-9)
    assert run["stability"]["margin_pct"] == pytest.approx(margin, rel=1e-9)
    assert run["stability"]["past_critical_delay"] is True
    said = re.search(r"lag 9 ms against a critical delay of .*?PAST it by [0-9.]+ %", done.stderr)
    assert said, done.stderr

    python = rths.sdof(period=PERIOD, zeta=ZETA, motion=str(motion), motion_units="m/s2",
                       delay=lag, experimental_fraction=fraction, allow_unstable=True)
    assert python["verdict"]["stability"] == run["stability"]

    sweep = tmp_path / "sweep.textproto"
    sweep.write_text(study_text(motion, fraction, lag).split("cases {")[0] +
                     f"sweep {{ periods: [{PERIOD}] delays: [{lag!r}] experimental_fractions: "
                     f"[{fraction!r}] dts: [{DT}] motions {{ path: \"{motion}\" column_units: "
                     f"M_PER_S2 }} delay_model: SHIFT models {{ linear {{}} }} }}\n")
    done = cli("sweep", sweep, "--out", tmp_path / "sweep", "--no-plots")
    assert said.group(0) in done.stderr, done.stderr


def test_compensation_is_judged_the_same_in_run_and_python(motion, tmp_path):
    # alpha = 1, 9 ms: a polynomial compensator's loop analysed, an ATS one not analysable;
    # both with the uncompensated margin beside.
    extra = ('cases { name: "polynomial" delay { shift { delay: 0.009 } } '
             "compensation { polynomial { order: 2 lead: 0.009 } } }\n"
             'cases { name: "ats" delay { shift { delay: 0.009 } } '
             "compensation { adaptive_time_series { window: 1 initial_a1: 0.009 } } }\n")
    config = tmp_path / "study.textproto"
    config.write_text(study_text(motion, 1.0, 0.009, extra))
    done = cli("run", config, "--out", tmp_path / "run", "--no-plots", "--allow-unstable")
    on_cli = json.loads((tmp_path / "run" / "summary.json").read_text())
    in_python = rths.run(rths.load_study(str(config)))["summary"]
    for name in ("polynomial", "ats"):
        mine, theirs = stability_of_case(in_python, name), stability_of_case(on_cli, name)
        assert mine["compensated_loop"] == theirs["compensated_loop"], name
        assert mine["stability"] == theirs["stability"], name
    poly = stability_of_case(on_cli, "polynomial")["compensated_loop"]
    ats = stability_of_case(on_cli, "ats")["compensated_loop"]
    assert poly["analysed"] is True and poly["stable"] is True
    assert ats["analysed"] is False and ats["stable"] is None
    for verdict in (poly["verdict"], ats["verdict"]):
        assert "uncompensated, lag 9 ms against a critical delay" in verdict, verdict
    assert "cannot be judged before it" in ats["verdict"]
    assert "case 'ats': adaptive compensation" in done.stderr
    assert "case 'polynomial'" not in done.stderr
