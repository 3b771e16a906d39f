"""rths: real-time hybrid simulation with actuator and network lag, from Python.

The C++ library's studies, runs, sweeps, stability analysis, identification and run records,
as NumPy arrays and dicts whose names carry their units:

    import rths
    r = rths.sdof(period=0.5, zeta=0.05, motion="RSN175_IMPVALL.H_H-E12140.AT2", delay=0.014,
                  experimental_fraction=1/3)
    r["verdict"]["status"], r["delayed_m"].max()

    study = rths.Study("frame").sdof(0.5).motion("record.AT2").case("reference").case("lag", delay=0.014)
    study.run()            # in process
    study.launch("out", domain=7)   # coordinator, substructure node and emulator over DDS

Bad input raises rths.BadInputError (a ValueError) with the message the CLI prints; anything
else rths.Error (a RuntimeError). ``rths.data_path("ground_motions", "RSN175_IMPVALL.H_H-E12140.AT2")``
names a record shipped with rths, from any folder.
"""

import os as _os

from ._rths import (BadInputError, Error, identify, load_study, parse_study, read_record, run,
                    stability, sweep)
from ._rths import Study as LoadedStudy
from .case import Case, Link
from .study import Study

__version__ = "@PROJECT_VERSION@"

# The data shipped with rths: installed by `cmake --install`, or the source tree this was built from.
_DATA_DIRS = ("@RTHS_INSTALLED_DATA_DIR@", "@PROJECT_SOURCE_DIR@/data")


def data_path(*parts):
    """The path of a file shipped in rths's data/ folder (ground_motions/, measured/), e.g.
    ``data_path("measured", "mts_mrdamper_chirp_0A.txt")``. Raises FileNotFoundError naming the
    folders searched."""
    for folder in _DATA_DIRS:
        candidate = _os.path.join(folder, *parts)
        if _os.path.exists(candidate):
            return candidate
    raise FileNotFoundError(f"{_os.path.join(*parts)}: not in rths's data ({', '.join(_DATA_DIRS)})")

__all__ = ["BadInputError", "Case", "Error", "Link", "LoadedStudy", "Study", "data_path", "identify", "load_study",
           "parse_study", "read_record", "run", "sdof", "stability", "sweep", "__version__"]


def _floor_series(series, case):
    """The first floor's displacement (m) of `case` in a run's series."""
    name = f"{case}_u_floor1_m"
    if name not in series:
        raise Error(f"sdof: the run gave no series {name}")
    return series[name]


def sdof(period, zeta, motion, delay=0.0, delay_model="shift", dt=0.001, experimental_fraction=1.0,
         motion_units=None, scale=1.0, integrator="explicit-newmark", allow_unstable=False):
    """One SDOF hybrid test, as ``rths sdof``: the lag-free reference against one lag.

    period (s) in (0, 50], zeta in [0, 1], motion a PEER AT2 (g) or columns file (then
    motion_units 'g', 'm/s2' or 'cm/s2'), delay (s) in [0, 1] applied as `delay_model` ('shift',
    'eq1', 'eq1-lag', 'first-order'), dt (s), the specimen's share of the stiffness.

    Returns a dict of NumPy arrays ``time_s``, ``reference_m``, ``delayed_m`` (displacement of the
    floor relative to the ground) and ``verdict``: status ("completed", "diverged", ...),
    diverged, the errors every rths output leads with, peak_error_pct (E_peak) and rms_error_pct
    (E_rms), the paper's nrmse_pct, peak_reference_m, peak_delayed_m, peak_error_m, and the stability
    check made before the run (critical delays and margin, in s and %), the same verdict every
    other entry point gives for the case. ``allow_unstable`` runs a case past its critical delay
    as meant (it still reports diverged).
    """
    study = (Study("sdof", base_dir=_os.getcwd())
             .sdof(period, zeta)
             .motion(motion, units=motion_units, scale=scale)
             .integrator(integrator, dt)
             .experimental(experimental_fraction)
             .case("reference")
             .case("delayed", delay=delay, delay_model=delay_model, expect_unstable=allow_unstable))
    result = study.run()
    summary = {c["name"]: c for c in result["summary"]["cases"]}
    delayed = summary["delayed"]
    verdict = {key: delayed[key] for key in ("status", "status_detail", "diverged", "peak_error_pct",
                                              "rms_error_pct", "nrmse_pct", "peak_error_m",
                                              "stability")}
    verdict["peak_reference_m"] = summary["reference"]["peak_displacement_m"]
    verdict["peak_delayed_m"] = delayed["peak_displacement_m"]
    series = result["series"]
    return {"time_s": series["time_s"], "reference_m": _floor_series(series, "reference"),
            "delayed_m": _floor_series(series, "delayed"), "verdict": verdict}
