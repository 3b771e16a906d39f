"""The `rths` Python module against the `rths` command line: same numbers, same names, same
error messages. Run from ctest (python_module) with PYTHONPATH=build/python and RTHS_EXECUTABLE,
RTHS_SOURCE_DIR set. Its launch on the shared DDS domain, on topics of its own
(tests/support/dds_scope.py)."""
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import rths

RTHS = os.environ["RTHS_EXECUTABLE"]
SOURCE = Path(os.environ["RTHS_SOURCE_DIR"])
MOTION = SOURCE / "data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2"
sys.path.insert(0, str(SOURCE / "tests" / "support"))
import dds_scope  # noqa: E402

STUDY_TEXT = (
    'name: "frame"\n'
    "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }\n"
    f'motion {{ path: "{MOTION}" duration: 3 }}\n'
    "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
    "substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }\n"
    'cases { name: "reference" }\n'
    'cases { name: "lag_shift_14ms" delay { shift { delay: 0.014 } } }\n'
    'cases { name: "eq1_as_printed_14ms" delay { eq1 { delay: 0.014 } } }\n'
    "sweep { periods: [0.2, 0.4, 0.8, 1.6] delays: [0.005, 0.014] }\n")


def cli(*args, expect=0):
    done = subprocess.run([RTHS, *map(str, args)], capture_output=True, text=True, timeout=240)
    assert done.returncode == expect, f"rths {args}: exit {done.returncode}\n{done.stdout}\n{done.stderr}"
    return done


def csv_columns(path, skip_comment=False):
    with open(path, newline="") as f:
        if skip_comment:
            f.readline()
        rows = list(csv.reader(f))
    return {name: [r[i] for r in rows[1:]] for i, name in enumerate(rows[0])}


def numbers(texts):
    return np.array([float(t) if t else math.nan for t in texts])


@pytest.fixture
def config(tmp_path):
    path = tmp_path / "frame.textproto"
    path.write_text(STUDY_TEXT)
    return path


def test_a_shipped_study_loads_with_its_cases():
    study = rths.load_study(SOURCE / "configs/paper_frame.textproto")
    assert study.name == "paper_frame"
    assert study.cases == ["reference", "lag_shift_14ms", "eq1_lag_14ms", "eq1_as_printed_14ms"]
    assert study.base_dir == SOURCE / "configs"
    assert 'name: "paper_frame"' in study.text


def test_run_gives_the_cli_numbers_as_arrays_with_units_in_the_names(config, tmp_path):
    result = rths.run(rths.load_study(config))
    cli("run", config, "--no-plots", "--out", tmp_path / "cli")
    expected = csv_columns(tmp_path / "cli/results.csv")
    assert list(result["series"]) == list(expected)  # the CSV's names, which carry their units
    for name, values in expected.items():
        assert isinstance(result["series"][name], np.ndarray)
        np.testing.assert_array_equal(result["series"][name], numbers(values), err_msg=name)
    assert result["units"]["lag_shift_14ms_force_act1_N"] == "N"
    summary = json.loads((tmp_path / "cli/summary.json").read_text())
    assert result["summary"] == summary
    peaks = {c["name"]: c["peak_displacement_m"] for c in result["summary"]["cases"]}
    assert peaks["lag_shift_14ms"] > peaks["reference"] > peaks["eq1_as_printed_14ms"]


def test_run_of_named_cases_keeps_the_reference(config):
    result = rths.run(rths.parse_study(STUDY_TEXT), cases=["lag_shift_14ms"])
    assert [c["name"] for c in result["summary"]["cases"]] == ["reference", "lag_shift_14ms"]
    with pytest.raises(rths.BadInputError, match="no case 'nope'"):
        rths.run(rths.parse_study(STUDY_TEXT), cases=["nope"])


def test_sweep_equals_the_cli_sweep_and_its_shards_join(config, tmp_path):
    study = rths.load_study(config)
    whole = rths.sweep(study, threads=1)
    cli("sweep", config, "--no-plots", "--threads", 1, "--out", tmp_path)
    expected = csv_columns(tmp_path / "sweep.csv")
    assert whole["grid_points"] == 8 and whole["shard"] == "0/1"
    assert whole["grid_hash"] == json.loads((tmp_path / "sweep.meta.json").read_text())["grid"]
    rename = {"period": "period_s", "delay": "delay_s", "dt": "dt_s", "stiffness": "stiffness_N_per_m",
              "peak_ref": "peak_ref_m", "peak_delayed": "peak_delayed_m", "peak_error": "peak_error_m"}
    for name, values in expected.items():
        key = rename.get(name, name)
        if name in ("motion", "model"):
            assert whole["series"][key] == values
        else:
            np.testing.assert_array_equal(whole["series"][key], numbers(values), err_msg=name)
    halves = [rths.sweep(study, shard=f"{i}/2", threads=1) for i in range(2)]
    np.testing.assert_array_equal(np.concatenate([h["series"]["nrmse_pct"] for h in halves]), whole["series"]["nrmse_pct"])
    assert whole["trends"]["period_falling_pair_fraction"] == 1.0  # error falls with period (Fig. 4)
    with pytest.raises(rths.BadInputError):
        rths.sweep(study, shard="2/2")


def test_numbers_follow_the_same_range_rules_as_the_flags():
    with pytest.raises(rths.BadInputError, match=r"period_s = 0 s is outside \(0, 50\] s"):
        rths.stability(0.0, 0.05)
    with pytest.raises(rths.BadInputError, match=r"dt_s = 1e-09 s is outside \[1e-06, 1\] s"):
        rths.stability(0.5, 0.05, dt_s=1e-9)
    with pytest.raises(rths.BadInputError, match="zeta"):
        rths.stability(0.5, 5.0)


def test_stability_is_the_cli_json(tmp_path):
    got = rths.stability(0.5, 0.05, experimental_fraction=1.0, dt_s=0.001)
    expected = json.loads(cli("stability", "--period", 0.5, "--zeta", 0.05, "--exp-fraction", 1, "--dt", 0.001,
                              "--json").stdout)
    assert got == expected
    assert 0.007 < got["continuous"]["critical_delay_s"] < 0.009  # ~8 ms for the paper's frame


def test_identify_finds_a_known_delay_in_synthetic_data(tmp_path):
    dt, delay, stiffness = 0.001, 0.012, 50.0  # s, s, N/mm
    t = np.arange(0, 20, dt)
    command = 5 * np.sin(2 * np.pi * (0.2 + 0.4 * t) * t)  # mm, a chirp
    measured = np.interp(t - delay, t, command, left=0.0)
    force = stiffness * measured
    data = tmp_path / "lab.csv"
    np.savetxt(data, np.column_stack([t, command, measured, force]), delimiter=",", header="time,command,measured,force",
               comments="")
    result = rths.identify(data, candidates=[], max_steps=0)
    measured_channel = [c for c in result["report"]["channels"] if c["channel"] == "measured"][0]
    fitted = measured_channel["declared"]["params"]
    found = [p for name, p in fitted.items() if "delay" in name][0]
    assert abs(found["value"] - delay) < 5e-4, fitted
    assert result["units"]["force_target_N"] == "N"
    np.testing.assert_allclose(result["series"]["measured_target_m"], measured * 1e-3)
    expected = json.loads(cli("identify", data, "--candidates", "none", "--max-steps", 0, "--json").stdout)
    # The CLI adds what only it knows: the units it read the file in and its k-fold validation.
    for cli_only in ("input_units", "validation"):
        expected.pop(cli_only, None)
    assert result["report"] == expected


def test_identify_reads_a_record_without_force_for_the_actuator_alone(tmp_path):
    dt, delay = 0.001, 0.012  # s
    t = np.arange(0, 10, dt)
    command = 5 * np.sin(2 * np.pi * (0.2 + 0.4 * t) * t)  # mm
    data = tmp_path / "actuator.csv"
    np.savetxt(data, np.column_stack([t, command, np.interp(t - delay, t, command, left=0.0)]),
               delimiter=",", header="time,command,measured", comments="")
    result = rths.identify(data, channels=["measured"], candidates=[], max_steps=0)
    assert [c["channel"] for c in result["report"]["channels"]] == ["measured"]
    with pytest.raises(ValueError, match="missing column 'force'"):
        rths.identify(data, candidates=[], max_steps=0)


def test_read_record_gives_the_exported_columns(config, tmp_path, monkeypatch):
    cli("launch", config, "--case", "lag_shift_14ms", "--domain", dds_scope.scope_dds_to_this_test(monkeypatch),
        "--no-plots", "--out", tmp_path)
    record = tmp_path / "lag_shift_14ms.rthsrec"
    got = rths.read_record(record)
    cli("export", record, "--csv", tmp_path / "lag_shift_14ms.csv")
    expected = csv_columns(tmp_path / "lag_shift_14ms.csv")
    assert not got["truncated"] and got["attributes"]["case_name"] == "lag_shift_14ms"
    # One naming rule: Python's names are the CSV's (results/table.h).
    assert list(got["series"]) == list(expected)
    np.testing.assert_array_equal(got["series"]["u_floor1_m"], numbers(expected["u_floor1_m"]))
    np.testing.assert_array_equal(got["series"]["time_s"], numbers(expected["time_s"]))
    np.testing.assert_array_equal(got["series"]["a_floor1_m_per_s2"], numbers(expected["a_floor1_m_per_s2"]))
    # The record names its study, step and motion as the run's table does, numbers as floats.
    assert got["attributes"]["dt_s"] == 0.001 and got["attributes"]["ok"] == 1.0
    assert got["attributes"]["study"] == rths.load_study(config).name
    assert len(got["attributes"]["motion_sha256"]) == 64
    round_trip = [k for k in got["series"] if k.endswith("_round_trip_s")][0]
    assert math.isnan(got["series"][round_trip][0]) and np.all(got["series"][round_trip][1:] > 0)
    cut = tmp_path / "cut.rthsrec"
    shutil.copy(record, cut)
    os.truncate(cut, cut.stat().st_size - 5)
    truncated = rths.read_record(cut)
    assert truncated["truncated"] and truncated["warning"]
    assert len(truncated["series"]["step"]) == len(got["series"]["step"])  # only the footer was cut
    assert got["checksummed"] and got["losses"] == [] and got["attributes"]["lost_steps"] == ""
    # A flipped byte in the middle: the reader's checksums catch it; Python gets the intact rows
    # only when it asks for them, with what was lost.
    damaged = tmp_path / "damaged.rthsrec"
    data = bytearray(record.read_bytes())
    data[len(data) // 2] ^= 0x01
    damaged.write_bytes(bytes(data))
    with pytest.raises(rths.Error, match="lost"):
        rths.read_record(damaged)
    salvaged = rths.read_record(damaged, allow_loss=True)
    lost = int(salvaged["attributes"]["lost_steps"])
    assert len(salvaged["losses"]) == 1 and f"step {lost} lost" in salvaged["losses"][0]
    kept = got["series"]["step"] != lost
    np.testing.assert_array_equal(salvaged["series"]["step"], got["series"]["step"][kept])
    np.testing.assert_array_equal(salvaged["series"]["u_floor1_m"], got["series"]["u_floor1_m"][kept])


def test_errors_carry_the_cli_messages(tmp_path):
    bad = tmp_path / "bad.textproto"
    bad.write_text('name: "x"\nstructure { sdof { period: -1 } }\nnot_a_field: 3\n')
    message = cli("run", bad, expect=2).stderr.strip()
    with pytest.raises(rths.BadInputError) as raised:
        rths.load_study(bad)
    assert isinstance(raised.value, ValueError)
    assert message == "rths: " + str(raised.value)
    missing = tmp_path / "missing.rthsrec"
    message = cli("export", missing, "--csv", tmp_path / "x.csv", expect=2).stderr.strip()
    with pytest.raises(rths.BadInputError) as raised:
        rths.read_record(missing)
    assert message == "rths: " + str(raised.value)
    with pytest.raises(rths.BadInputError, match="unknown effect"):
        rths.identify(missing, candidates=["warp_drive"])


def test_long_work_releases_the_gil():
    study = rths.parse_study(STUDY_TEXT.replace("duration: 3", "duration: 30"))
    done = threading.Event()
    sweeps = []

    def work():  # sweeps back to back for at least 0.5 s
        start = time.monotonic()
        while time.monotonic() - start < 0.5:
            sweeps.append(rths.sweep(study, threads=1, general=True)["grid_points"])
        done.set()

    worker = threading.Thread(target=work)
    start = time.monotonic()
    worker.start()
    ticks = 0
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    worker.join()
    seconds = time.monotonic() - start
    print(f"{len(sweeps)} sweeps in {seconds:.2f} s; the main thread ran {ticks} times meanwhile")
    # With the GIL held during a sweep the main thread would run about once per sweep.
    assert ticks > max(10 * len(sweeps), 0.1 * seconds / 0.0011)
