"""The MATLAB and HDF5 files rths writes, read back by independent readers (scipy.io.loadmat and
h5py) and compared value for value with the CSV the same command writes. Run from ctest
(tables_readback) with RTHS_EXECUTABLE, RTHS_SOURCE_DIR and RTHS_DATA_DIR set."""
import csv
import hashlib
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io

RTHS = os.environ["RTHS_EXECUTABLE"]
SOURCE = Path(os.environ["RTHS_SOURCE_DIR"])
MOTION = SOURCE / "data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2"
# The launch below: on the shared DDS domain, on topics of its own.
sys.path.insert(0, str(SOURCE / "tests" / "support"))
import dds_scope  # noqa: E402


def rths(*args, expect=0):
    done = subprocess.run([RTHS, *map(str, args)], capture_output=True, text=True, timeout=240)
    assert done.returncode == expect, f"rths {' '.join(map(str, args))}: exit {done.returncode}\n{done.stdout}\n{done.stderr}"
    return done


def read_csv(path, skip_comment=False):
    """Columns of a CSV as {name: list of text}."""
    with open(path, newline="") as f:
        if skip_comment:
            assert f.readline().startswith("#")
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    return header, {name: [r[i] for r in body] for i, name in enumerate(header)}


def as_numbers(texts):
    return np.array([float(t) if t != "" else math.nan for t in texts])


def assert_same_as_csv(header, columns, mat_path, h5_path, text_columns=()):
    """Every CSV column is a variable of the .mat and a dataset of the .h5 with equal values."""
    mat = scipy.io.loadmat(mat_path, simplify_cells=True)
    with h5py.File(h5_path, "r") as h5:
        assert h5.attrs["columns"].split(",") == header
        assert sorted(h5.keys()) == sorted(header)
        for name in header:
            stored = h5[name]
            if name in text_columns:
                assert [s.decode() for s in stored[()]] == columns[name]
                assert list(np.atleast_1d(mat[name])) == columns[name]
                continue
            expected = as_numbers(columns[name])
            np.testing.assert_array_equal(stored[()], expected, err_msg=f"h5 {name}")
            np.testing.assert_array_equal(np.atleast_1d(mat[name]), expected, err_msg=f"mat {name}")
            assert isinstance(stored.attrs["units"], str)
            mat_unit = mat["units"][name]  # '' (1x0 char) comes back as an empty array
            assert (mat_unit if np.size(mat_unit) else "") == stored.attrs["units"], name
    assert set(header) <= set(mat)
    return mat


@pytest.fixture
def study(tmp_path):
    config = tmp_path / "frame.textproto"
    config.write_text(
        'name: "frame"\n'
        "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }\n"
        f'motion {{ path: "{MOTION}" duration: 2 }}\n'
        "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
        "substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }\n"
        'cases { name: "reference" }\n'
        'cases { name: "lag_shift_14ms" delay { shift { delay: 0.014 } } }\n'
        "sweep { periods: [0.3, 0.6] delays: [0.004, 0.014] "
        "models { linear {} } models { bilinear { yield_displacement: 0.005 post_yield_ratio: 0.1 } } }\n")
    return config


def motion_file_sha256():
    return hashlib.sha256(MOTION.read_bytes()).hexdigest()


def assert_carries_the_run(mat, h5, study, ok=1.0):
    """The .mat's `attributes` struct and the .h5's root attributes name the study, dt (s), the
    motion (name and checksums) and the verdict, alike; returns the motion-as-run checksum."""
    attributes = mat["attributes"]
    for key in ("study", "motion_name", "motion_sha256", "motion_file_sha256", "status"):
        assert attributes[key] == h5.attrs[key], key
    assert attributes["study"] == study
    assert attributes["dt_s"] == h5.attrs["dt_s"] == 0.001
    assert isinstance(attributes["dt_s"], float) and isinstance(h5.attrs["dt_s"], np.float64)
    assert attributes["motion_name"] == "RSN175_IMPVALL.H_H-E12140"
    assert attributes["motion_file_sha256"] == motion_file_sha256()
    assert len(attributes["motion_sha256"]) == 64 and attributes["motion_sha256"] != motion_file_sha256()
    assert attributes["status"] == "completed"
    assert attributes["ok"] == h5.attrs["ok"] == ok
    return attributes["motion_sha256"]


def test_run_writes_the_same_table_as_csv_mat_and_h5(study, tmp_path):
    for fmt in ("csv", "mat", "h5"):
        out = rths("run", study, "--no-plots", "--format", fmt, "--out", tmp_path / fmt).stdout
        assert str(tmp_path / fmt / f"results.{fmt}") in out
    header, columns = read_csv(tmp_path / "csv/results.csv")
    assert header[:3] == ["step", "time_s", "reference_u_floor1_m"]
    mat = assert_same_as_csv(header, columns, tmp_path / "mat/results.mat", tmp_path / "h5/results.h5")
    assert mat["units"]["time_s"] == "s" and mat["units"]["lag_shift_14ms_force_act1_N"] == "N"
    assert mat["attributes"]["reference_case"] == "reference"
    assert len(columns["time_s"]) == 2000  # 2 s at 1 ms
    with h5py.File(tmp_path / "h5/results.h5", "r") as h5:
        lag, ref = h5["lag_shift_14ms_u_floor1_m"][()], h5["reference_u_floor1_m"][()]
        assert np.max(np.abs(lag)) > np.max(np.abs(ref))  # the lag enlarges the response
        assert_carries_the_run(mat, h5, "frame")
        assert h5["lag_shift_14ms_measured_act1_m"].attrs["units"] == "m"


def test_sweep_mat_and_h5_hold_the_sweep_csv_with_text_columns(study, tmp_path):
    for fmt in ("csv", "mat", "h5"):
        rths("sweep", study, "--no-plots", "--threads", 1, "--format", fmt, "--out", tmp_path / fmt)
    header, columns = read_csv(tmp_path / "csv/sweep.csv")
    mat = assert_same_as_csv(header, columns, tmp_path / "mat/sweep.mat", tmp_path / "h5/sweep.h5",
                             text_columns=("motion", "model"))
    assert len(columns["index"]) == 8
    assert mat["units"]["period_s"] == "s" and mat["units"]["stiffness_N_per_m"] == "N/m"
    grid = json.loads((tmp_path / "csv/sweep.meta.json").read_text())["grid"]
    with h5py.File(tmp_path / "h5/sweep.h5", "r") as h5:
        assert h5.attrs["grid_hash"] == grid
    rths("sweep", study, "--shard", "0/2", "--format", "mat", "--out", tmp_path / "shard", expect=2)


def test_launch_and_export_write_the_record_in_every_format(study, tmp_path, monkeypatch):
    rths("launch", study, "--case", "lag_shift_14ms", "--domain", dds_scope.scope_dds_to_this_test(monkeypatch),
         "--no-plots", "--format", "h5", "--out", tmp_path / "launch")
    record = tmp_path / "launch/lag_shift_14ms.rthsrec"
    out = tmp_path / "export"
    out.mkdir()
    rths("export", record, "--csv", out / "r.csv", "--mat", out / "r.mat", "--h5", out / "r.h5")
    header, columns = read_csv(out / "r.csv")
    assert header[:4] == ["step", "time_s", "ground_acceleration_m_per_s2", "u_floor1_m"]
    mat = assert_same_as_csv(header, columns, out / "r.mat", out / "r.h5")
    assert mat["units"]["node2_round_trip_s"] == "s" and mat["units"]["force_act1_N"] == "N"
    assert mat["units"]["a_floor1_m_per_s2"] == "m/s^2"
    # launch writes run's results table beside the record: each case's columns named as the
    # record's, with the case in front.
    launched_table = tmp_path / "launch/results.h5"
    with h5py.File(out / "r.h5", "r") as exported, h5py.File(launched_table, "r") as launched:
        for name in ("u_floor1_m", "command_act1_m", "measured_act1_m", "force_act1_N",
                     "node2_round_trip_s", "node2_injected_lag_s"):
            launched_column = launched["lag_shift_14ms_" + name][()]
            assert exported[name].attrs["units"] == launched["lag_shift_14ms_" + name].attrs["units"]
            if name.startswith("node2_"):  # NaN where a step reused an older answer
                launched_column = launched_column[~np.isnan(launched_column)]
                assert set(launched_column) <= set(exported[name][()])
                continue
            np.testing.assert_array_equal(exported[name][()], launched_column, err_msg=name)
        assert math.isnan(exported["node2_round_trip_s"][0])  # step 0 has no exchange
        assert np.all(exported["node2_round_trip_s"][1:] > 0)
        # The record's export and the launch's table name the same run: study, dt, motion.
        assert assert_carries_the_run(mat, exported, "frame") == launched.attrs["motion_sha256"]
        assert exported.attrs["motion_file_sha256"] == launched.attrs["motion_file_sha256"]
        assert exported.attrs["dt_s"] == launched.attrs["dt_s"] and launched.attrs["ok"] == 1.0
        assert exported.attrs["case_name"] == "lag_shift_14ms"
        assert exported.attrs["integrity"] == "verified (CRC-32C per entry)"
        assert exported.attrs["lost_steps"] == ""
    rths("export", record, expect=2)  # no output named

    # One flipped byte in the middle of the record: that step's entry fails its checksum; every
    # other row is exported, every format says which step was lost, and the exit is 1.
    damaged = tmp_path / "damaged.rthsrec"
    data = bytearray(record.read_bytes())
    data[len(data) // 2] ^= 0x40
    damaged.write_bytes(bytes(data))
    done = rths("export", damaged, "--csv", out / "d.csv", "--mat", out / "d.mat", "--h5", out / "d.h5", expect=1)
    with h5py.File(out / "d.h5", "r") as h5:
        lost = h5.attrs["lost_steps"]
        assert h5.attrs["integrity"].startswith("damaged: ")
    assert lost.isdigit(), lost  # exactly one step
    assert f"step {lost} lost" in done.stderr
    mat = scipy.io.loadmat(out / "d.mat", simplify_cells=True)
    assert mat["attributes"]["lost_steps"] == lost
    _, kept = read_csv(out / "d.csv")
    assert kept["step"] == [s for s in columns["step"] if s != lost]
    assert kept["u_floor1_m"] == [u for s, u in zip(columns["step"], columns["u_floor1_m"]) if s != lost]


def test_identify_writes_the_record_and_both_models_predictions(tmp_path):
    dt, delay = 0.001, 0.012  # s
    t = np.arange(0, 10, dt)
    command = 5 * np.sin(2 * np.pi * (0.2 + 0.4 * t) * t)  # mm
    measured = np.interp(t - delay, t, command, left=0.0)
    data = tmp_path / "lab.csv"
    np.savetxt(data, np.column_stack([t, command, measured, 40 * measured]), delimiter=",",
               header="time,command,measured,force", comments="")
    for fmt in ("csv", "mat", "h5"):
        rths("identify", data, "--candidates", "none", "--max-steps", 0, "--out", tmp_path / fmt, "--format", fmt)
    header, columns = read_csv(tmp_path / "csv/identify.csv")
    assert header == ["time_s", "measured_input_m", "measured_target_m", "measured_declared_m", "measured_final_m",
                      "force_input_m", "force_target_N", "force_declared_N", "force_final_N"]
    assert_same_as_csv(header, columns, tmp_path / "mat/identify.mat", tmp_path / "h5/identify.h5")
    np.testing.assert_allclose(as_numbers(columns["measured_target_m"]), measured * 1e-3)
    # The declared model (a delay) reproduces the measured displacement.
    residual = as_numbers(columns["measured_declared_m"]) - measured * 1e-3
    assert np.sqrt(np.mean(residual ** 2)) < 0.05 * np.std(measured * 1e-3)


def test_bad_format_is_bad_input(study, tmp_path):
    done = rths("run", study, "--format", "xlsx", "--out", tmp_path, expect=2)
    assert "xlsx" in done.stderr
