"""rths.sdof and rths.Study built in code against the command line: the same study gives the same
numbers and the same verdict however it is entered. Run from ctest (python_study_builder) with
PYTHONPATH=build/python, RTHS_EXECUTABLE and RTHS_SOURCE_DIR set. Its launch on the shared DDS
domain, on topics of its own (tests/support/dds_scope.py)."""
import json
import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import rths

RTHS = os.environ["RTHS_EXECUTABLE"]
SOURCE = Path(os.environ["RTHS_SOURCE_DIR"])
MOTION = str(SOURCE / "data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2")
sys.path.insert(0, str(SOURCE / "tests" / "support"))
import dds_scope  # noqa: E402


def cli_json(*args, expect=0):
    done = subprocess.run([RTHS, *map(str, args)], capture_output=True, text=True, timeout=240)
    assert done.returncode == expect, f"rths {args}: exit {done.returncode}\n{done.stderr}"
    return json.loads(done.stdout)


def frame(name="frame"):
    return (rths.Study(name)
            .sdof(period=0.5, zeta=0.05)
            .motion(MOTION)
            .integrator("explicit-newmark", dt=0.001)
            .experimental(fraction=1 / 3)
            .case("reference")
            .case("lag_shift_14ms", delay=0.014))


def test_version_is_the_projects():
    cmake = (SOURCE / "CMakeLists.txt").read_text()
    assert rths.__version__ == re.search(r"project\(rths VERSION ([0-9.]+)", cmake).group(1)


def test_sdof_gives_the_clis_numbers_and_verdict():
    got = rths.sdof(period=0.5, zeta=0.05, motion=MOTION, delay=0.014, experimental_fraction=1 / 3)
    want = cli_json("sdof", "--period", 0.5, "--zeta", 0.05, "--motion", MOTION, "--dt", 0.001,
                    "--delay", "14ms", "--exp-fraction", 1 / 3, "--json")
    assert isinstance(got["delayed_m"], np.ndarray) and got["delayed_m"].dtype == np.float64
    assert len(got["time_s"]) == len(got["reference_m"]) == len(got["delayed_m"])
    verdict = got["verdict"]
    assert verdict["status"] == want["status"] == "completed"
    assert verdict["nrmse_pct"] == pytest.approx(want["nrmse_pct"], rel=1e-12)
    assert verdict["peak_delayed_m"] == pytest.approx(want["peak_delayed_m"], rel=1e-12)
    assert np.max(np.abs(got["delayed_m"])) == pytest.approx(verdict["peak_delayed_m"], rel=1e-12)
    assert verdict["stability"]["past_critical_delay"] is False
    assert verdict["stability"]["margin_pct"] > 0


def test_sdof_past_the_critical_delay_is_judged_diverged_as_on_the_command_line():
    got = rths.sdof(period=0.5, zeta=0.05, motion=MOTION, delay=0.03, allow_unstable=True)
    want = cli_json("sdof", "--period", 0.5, "--zeta", 0.05, "--motion", MOTION, "--dt", 0.001,
                    "--delay", "30ms", "--json", "--allow-unstable")
    assert got["verdict"]["diverged"] is True
    assert got["verdict"]["status"] == want["status"]
    assert got["verdict"]["stability"]["past_critical_delay"] is True


def test_a_study_built_in_code_equals_its_written_config_run_by_the_cli(tmp_path):
    study = frame()
    assert study.cases == ["reference", "lag_shift_14ms"]
    in_python = study.run()
    config = study.write(tmp_path / "frame.textproto")
    subprocess.run([RTHS, "run", config, "--out", tmp_path / "out", "--no-plots"], check=True,
                   capture_output=True, timeout=240)
    on_cli = json.loads((tmp_path / "out" / "summary.json").read_text())
    for mine, theirs in zip(in_python["summary"]["cases"], on_cli["cases"]):
        assert mine["name"] == theirs["name"]
        assert mine["peak_displacement_m"] == theirs["peak_displacement_m"]
        assert mine["status"] == theirs["status"]


def test_a_study_built_in_code_runs_distributed_and_equals_its_in_process_run(tmp_path, monkeypatch):
    study = frame("frame_distributed")
    study.deployment("nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR }")
    in_process = study.run()
    summary = study.launch(tmp_path / "launch", domain=dds_scope.scope_dds_to_this_test(monkeypatch),
                           cases=["lag_shift_14ms"], timeout=240)
    assert summary["exit_code"] == 0
    launched = {c["name"]: c for c in summary["cases"]}["lag_shift_14ms"]
    wanted = {c["name"]: c for c in in_process["summary"]["cases"]}["lag_shift_14ms"]
    assert launched["peak_displacement_m"] == wanted["peak_displacement_m"]


def test_bad_input_is_named_before_anything_runs():
    with pytest.raises(rths.BadInputError, match="period"):
        rths.Study("x").sdof(period=0)
    with pytest.raises(rths.BadInputError, match="dt"):
        rths.Study("x").integrator(dt=1e-9)
    with pytest.raises(rths.BadInputError, match="delay"):
        rths.Study("x").case("late", delay=7)
    with pytest.raises(rths.BadInputError, match="already a case"):
        rths.Study("x").case("a").case("a")
    with pytest.raises(rths.BadInputError, match="no ground motion"):
        rths.Study("x").sdof(0.5).case("a").text
    with pytest.raises(rths.BadInputError):
        rths.Study("x").sdof(0.5).motion("/nonexistent.AT2").case("a").run()


# Issue 39's 3-DOF frame (SI), given as NumPy arrays with its experimental DOF.
M3 = np.diag([1000.0, 1000.0, 800.0])
K3 = np.array([[4e6, -2e6, 0], [-2e6, 3.5e6, -1.5e6], [0, -1.5e6, 1.5e6]])
C3 = np.array([[2275.816349, -809.9103853, 0], [-809.9103853, 2073.338753, -607.432789],
               [0, -607.432789, 1132.229252]])


def frame3(name, *cases):
    study = (rths.Study(name)
             .matrices(M3, C3, K3)
             .motion(MOTION)
             .integrator("explicit-newmark", dt=0.001)
             .experimental_dof(1, stiffness=0.5e6)
             .case("reference"))
    for case, delay in cases:
        study.case(case, delay=delay)
    return study


def test_matrices_and_experimental_dofs_from_numpy_run_as_their_written_config(tmp_path):
    study = frame3("frame3_matrices", ("lag_7ms", 0.007)).benchmark(experimental_dof=1)
    assert "experimental_dofs { dof: 1" in study.text and "rows: 3" in study.text
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a stable study warns of nothing
        in_python = study.run()
    config = study.write(tmp_path / "frame3.textproto")
    subprocess.run([RTHS, "run", config, "--out", tmp_path / "out", "--no-plots"], check=True,
                   capture_output=True, timeout=240)
    on_cli = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert [c["peak_displacement_m"] for c in in_python["summary"]["cases"]] == \
        [c["peak_displacement_m"] for c in on_cli["cases"]]
    # J from Python, named: a 7 ms shift tracks 7 ms late (J1 within one step of 1 ms).
    benchmark = in_python["benchmark"]
    assert benchmark == json.loads((tmp_path / "out" / "benchmark.json").read_text())
    j = {c["name"]: c["value"] for c in benchmark["cases"][0]["criteria"]}
    assert benchmark["cases"][0]["name"] == "lag_7ms"
    assert j["J1"] == pytest.approx(7.0, abs=1.0)
    assert [c["unit"] for c in benchmark["cases"][0]["criteria"]] == ["ms"] + ["%"] * 8
    assert [c["name"] for c in rths.Study.criteria()] == [f"J{i}" for i in range(1, 10)]
    assert frame("no_benchmark").run()["benchmark"] is None


def test_a_storey_specimen_between_two_floors_is_the_whole_frame_without_lag():
    storey = (rths.Study("frame3_storey")
              .matrices(M3, C3, K3)
              .motion(MOTION)
              .integrator("explicit-newmark", dt=0.001)
              .experimental_dof(2, stiffness=2e6, from_dof=1)
              .case("reference"))
    assert "experimental_dofs { dof: 2 mass: 0.0 stiffness: 2000000.0 from_dof: 1" in storey.text
    hybrid = storey.run()["summary"]["cases"][0]["peak_displacement_m"]
    whole = frame3("frame3_whole").run()["summary"]["cases"][0]["peak_displacement_m"]
    assert hybrid == pytest.approx(whole, rel=1e-9)
    with pytest.raises(rths.BadInputError, match="from_dof 2 must be another DOF"):
        rths.Study("x").experimental_dof(2, stiffness=1e6, from_dof=2)


def test_a_diverging_case_is_warned_with_its_verdict():
    with pytest.warns(RuntimeWarning, match=r"case 'lag_10ms': diverging: .*doubling every"):
        result = frame3("frame3_diverging", ("lag_10ms", 0.010)).run()
    assert result["summary"]["cases"][1]["status"] == "diverging"
    assert result["summary"]["cases"][1]["envelope_growth"]["rate_per_s"] > 0


def test_a_wrong_type_is_a_type_error_naming_the_argument():
    with pytest.raises(TypeError, match="structure_text: text must be a str.*numpy.ndarray"):
        rths.Study("x").structure_text(np.eye(2))
    with pytest.raises(TypeError, match=r"sdof: period \(s\): expected a number, got str"):
        rths.Study("x").sdof(period="0.5")
    with pytest.raises(TypeError, match=r"matrices: M \(kg\): expected a 2-D array"):
        rths.Study("x").matrices("M", C3, K3)
    with pytest.raises(TypeError, match=r"matrices: K \(N/m\)"):
        rths.Study("x").matrices(M3, C3, [["a", "b", "c"]] * 3)
    with pytest.raises(TypeError, match="experimental_dof: dof must be an int"):
        rths.Study("x").experimental_dof(1.5, stiffness=1e6)
    with pytest.raises(rths.BadInputError, match=r"matrices: C \(N s/m\): 2 x 2, the structure has 3"):
        rths.Study("x").matrices(M3, np.eye(2), K3)


def test_every_public_function_has_a_docstring():
    for name in rths.__all__:
        if name in ("__version__", "Error", "BadInputError"):
            continue
        assert getattr(rths, name).__doc__, name
