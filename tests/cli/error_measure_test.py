"""One reading everywhere: in every output of the shipped studies, E_peak and E_rms lead.

Runs, as a user would, `rths run`, `sdof`, `sweep`, `joint-lag` and `identify --predict` on the
shipped configs and reads what each writes: its text, its CSV headers, its JSON keys and its
figures' labels (SVG). The paper's median-normalised NRMSE may appear only labelled as the
paper's (in text), after E_peak and E_rms (CSV columns, figure panels), beside them (JSON) and in
the paper's own Fig. 4 panel. Run from ctest (cli_error_measure) with RTHS_SOURCE_DIR and
RTHS_BINARY_DIR set.
"""
import csv
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

SOURCE = Path(os.environ["RTHS_SOURCE_DIR"])
RTHS = Path(os.environ["RTHS_BINARY_DIR"]) / "cli" / "rths"
FAILURES = []


def check(condition, what):
    if not condition:
        FAILURES.append(what)


def rths(*args, allowed=(0,)):
    done = subprocess.run([str(RTHS), *map(str, args)], cwd=SOURCE, capture_output=True, text=True,
                          timeout=600)
    if done.returncode not in allowed:
        sys.exit(f"rths {' '.join(map(str, args))}: exit {done.returncode}\n{done.stdout}{done.stderr}")
    return done.stdout


def check_text(name, text):
    """Every line naming NRMSE names it the paper's; E_peak or E_rms come before any NRMSE."""
    for line in text.splitlines():
        if "NRMSE" in line:
            check("paper" in line, f"{name}: NRMSE without the paper's label: {line.strip()}")
    first_nrmse = text.find("NRMSE")
    first_ours = min((i for i in (text.find("E_peak"), text.find("E_rms")) if i >= 0), default=-1)
    check(first_ours >= 0, f"{name}: neither E_peak nor E_rms in the output")
    if first_nrmse >= 0:
        check(first_ours < first_nrmse, f"{name}: NRMSE is read before E_peak / E_rms")


def check_csv_header(name, path):
    header = next(csv.reader(path.open()))
    errors = [column for column in header if column.endswith("_pct")]
    check(errors[:2] == ["peak_error_pct", "rms_error_pct"],
          f"{name}: the error columns lead with {errors[:2]}, not peak_error_pct, rms_error_pct")


def walk_json(name, node, where="$"):
    """Every object that carries the paper's NRMSE carries E_peak and E_rms beside it."""
    if isinstance(node, dict):
        for key in node:
            if "nrmse" in key and key.endswith("pct") and not key.startswith("in_process"):
                check({"peak_error_pct", "rms_error_pct"} <= set(node) or where.endswith("measures"),
                      f"{name}: {where}.{key} without peak_error_pct and rms_error_pct beside it")
        for key, value in node.items():
            walk_json(name, value, f"{where}.{key}")
    elif isinstance(node, list):
        for i, value in enumerate(node):
            walk_json(name, value, f"{where}[{i}]")


def check_svg(name, path, paper_panel=False):
    """The figure's text: E_rms or E_peak before any NRMSE, which is the paper's panel's alone."""
    text = re.sub(r"<[^>]+>", " ", path.read_text())
    ours = min((i for i in (text.find("E_rms"), text.find("E_peak")) if i >= 0), default=-1)
    check(ours >= 0, f"{name}: no E_rms / E_peak label")
    nrmse = text.find("NRMSE")
    if paper_panel:
        check("the paper's Fig. 4" in text, f"{name}: the paper's Fig. 4 panel is not named so")
    if nrmse >= 0:
        check(paper_panel and 0 <= ours < nrmse, f"{name}: NRMSE on a figure that is not the paper's")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        check_text("rths run", rths("run", "configs/paper_frame.textproto", "--out", out / "run"))
        check_text("summary.txt", (out / "run" / "summary.txt").read_text())
        walk_json("rths run --json", json.loads(rths("run", "configs/paper_frame.textproto",
                                                         "--out", out / "run_json", "--json")))
        walk_json("summary.json", json.loads((out / "run" / "summary.json").read_text()))
        motion = SOURCE / "data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2"
        sdof = ["sdof", "--period", "0.5", "--zeta", "0.05", "--motion", motion, "--delay", "14ms",
                "--exp-fraction", "0.3333333333333333"]
        check_text("rths sdof", rths(*sdof))
        walk_json("rths sdof --json", json.loads(rths(*sdof, "--json")))

        sweep = out / "sweep"
        check_text("rths sweep", rths("sweep", "configs/paper_sweep.textproto", "--out", sweep))
        check_csv_header("sweep.csv", sweep / "sweep.csv")
        summary = json.loads(rths("sweep", "configs/paper_sweep.textproto", "--out", out / "sweep_json",
                                  "--json", "--no-plots"))
        check(summary["trends"]["measure"] == "E_rms (%)", "rths sweep --json: trends not in E_rms")
        check("paper" in summary["paper_trends"]["measure"], "rths sweep --json: paper_trends unlabelled")
        check_svg("sweep.svg", sweep / "sweep.svg", paper_panel=True)
        check_svg("sweep_vs_delay.svg", sweep / "sweep_vs_delay.svg")

        joint = out / "joint"
        check_text("rths joint-lag", rths("joint-lag", "configs/joint_lag_study.textproto", "--no-measure",
                                          "--out", joint))
        check_csv_header("joint-lag grid.csv", joint / "grid.csv")
        walk_json("joint-lag summary.json", json.loads((joint / "summary.json").read_text()))
        check_svg("error_map.svg", joint / "error_map.svg")

        predict = rths("identify", "data/measured/mts_mrdamper_chirp_0A.txt", "--channels", "measured",
                       "--trim-idle", "--predict", "configs/paper_frame.textproto")
        check_text("rths identify --predict", predict[predict.find("prediction with"):])
    for failure in FAILURES:
        print("FAIL:", failure)
    sys.exit(1 if FAILURES else 0)


if __name__ == "__main__":
    main()
