"""Studies built in code, as OpenSeesPy users build models: a structure, a ground motion, an
integrator, the experimental part, cases with their lag and compensation, and (for distributed
runs) a deployment. A Study writes the same Protobuf text config that ``rths run`` reads, so a
study built here and a config file are one thing: ``Study.text`` shows it, ``Study.write(path)``
keeps it, ``Study.run()`` runs it in process and ``Study.launch(out)`` runs it as separate
processes over Cyclone DDS (the ``rths launch`` command).

Units are SI everywhere: seconds, metres, kilograms, newtons; lags in seconds.
"""

import json
import math
import numbers
import os
import shutil
import subprocess
import tempfile
import warnings

from . import _rths
from .case import Case, Link

_INTEGRATORS = {
    "explicit-newmark": "EXPLICIT_NEWMARK",
    "central-difference": "CENTRAL_DIFFERENCE",
    "chen-ricles": "CHEN_RICLES",
    "newmark-average-acceleration": "NEWMARK_AVERAGE_ACCELERATION",
    "alpha-os": "ALPHA_OS",
    "kr-alpha": "KR_ALPHA",
}
_MOTION_UNITS = {"g": "G", "m/s2": "M_PER_S2", "cm/s2": "CM_PER_S2"}


def _type_name(value):
    kind = type(value)
    return kind.__name__ if kind.__module__ == "builtins" else f"{kind.__module__}.{kind.__name__}"


def _number(value, what, low=None, high=None, low_open=False):
    """A finite float within [low, high] (low excluded when low_open): a value of another type
    (a str, a list, an array) raises TypeError naming `what` and the type it got; a number out of
    range BadInputError naming `what`, the value and the range."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{what}: expected a number, got {_type_name(value)} ({value!r:.60})")
    x = float(value)
    below = low is not None and (x <= low if low_open else x < low)
    if not math.isfinite(x) or below or (high is not None and x > high):
        bracket = "(" if low_open else "["
        raise _rths.BadInputError(f"{what}: {value} is outside {bracket}{low}, {high}]")
    return x


def _quoted(text):
    return '"' + str(text).replace("\\", "\\\\").replace('"', '\\"') + '"'


def _matrix(value, what, n=None):
    """`value` as an n x n float64 array (square of any size when n is None): TypeError naming
    `what` when it is not an array of numbers, BadInputError for a wrong shape or a value that is
    not finite."""
    import numpy as np
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__"):
        raise TypeError(f"{what}: expected a 2-D array of numbers (NumPy array or nested lists), "
                        f"got {_type_name(value)}")
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"{what}: expected a 2-D array of numbers, got {_type_name(value)} "
                        "holding something else") from None
    if array.ndim != 2 or array.shape[0] != array.shape[1] or array.shape[0] == 0:
        raise _rths.BadInputError(f"{what}: shape {array.shape}, expected a square n x n matrix")
    if n is not None and array.shape[0] != n:
        raise _rths.BadInputError(f"{what}: {array.shape[0]} x {array.shape[0]}, the structure has "
                                  f"{n} DOFs (M is {n} x {n})")
    if not np.all(np.isfinite(array)):
        raise _rths.BadInputError(f"{what}: holds a value that is not finite")
    return array


def _vector(value, what, n):
    import numpy as np
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__"):
        raise TypeError(f"{what}: expected a 1-D array of numbers, got {_type_name(value)}")
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"{what}: expected a 1-D array of numbers, got {_type_name(value)}") from None
    if array.shape != (n,) or not np.all(np.isfinite(array)):
        raise _rths.BadInputError(f"{what}: shape {array.shape}, expected {n} finite values")
    return array


def _matrix_text(array):
    """The body of a config Matrix: rows and the values row by row, each as Python's repr keeps it
    (a float's repr reads back to the same double)."""
    values = ", ".join(repr(float(x)) for x in array.ravel(order="C"))
    return f"rows: {array.shape[0]} values: [{values}]"


def _warn_unexpected_divergence(study, summary):
    """warnings.warn for every case of a summary that diverged or is diverging unexpectedly."""
    for case in summary.get("cases", []):
        if case.get("diverged") and not case.get("expect_unstable"):
            warnings.warn(f"study '{study}', case '{case['name']}': {case['status']}: "
                          f"{case.get('status_detail', '')}", RuntimeWarning, stacklevel=3)


class Study:
    """A study built in code. Every setter returns the study, so calls chain::

        study = (rths.Study("frame")
                 .sdof(period=0.5, zeta=0.05)
                 .motion("data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2")
                 .integrator("explicit-newmark", dt=0.001)
                 .experimental(fraction=1/3)
                 .case("reference")
                 .case("lag_14ms", delay=0.014))
        result = study.run()

    Relative paths (the motion) resolve against ``base_dir`` (default: the working directory)."""

    def __init__(self, name, base_dir="."):
        self.name = str(name)
        self.base_dir = os.path.abspath(base_dir)
        self._structure = None
        self._motion = None
        self._integrator = 'integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }'
        self._substructuring = "substructuring { experimental_fraction: 1 model { linear {} } }"
        self._cases = []
        self._deployment = None
        self._servo_rate = None
        self._experimental_dofs = []
        self._benchmark = None

    # --- the structure --------------------------------------------------------------------------
    def sdof(self, period, zeta=0.05, mass=1000.0):
        """One storey: period (s) in (0, 50], damping ratio in [0, 1], mass (kg) > 0."""
        period = _number(period, "sdof: period (s)", 0.0, 50.0, low_open=True)
        zeta = _number(zeta, "sdof: zeta", 0.0, 1.0)
        mass = _number(mass, "sdof: mass (kg)", 0.0, None, low_open=True)
        self._structure = (f"structure {{ sdof {{ period: {period!r} mass: {mass!r} }} "
                           f"damping {{ modal_zeta: {zeta!r} }} }}")
        return self

    def shear_building(self, storey_mass, storey_stiffness, zeta=0.05):
        """Storeys from the ground up: masses (kg) and storey stiffnesses (N/m), modal damping."""
        if len(storey_mass) != len(storey_stiffness) or not storey_mass:
            raise _rths.BadInputError("shear_building: give one mass and one stiffness per storey")
        masses = " ".join(f"storey_mass: {_number(m, 'shear_building: storey mass (kg)', 0, None, True)!r}"
                          for m in storey_mass)
        stiffnesses = " ".join(
            f"storey_stiffness: {_number(k, 'shear_building: storey stiffness (N/m)', 0, None, True)!r}"
            for k in storey_stiffness)
        zeta = _number(zeta, "shear_building: zeta", 0.0, 1.0)
        self._structure = (f"structure {{ shear_building {{ {masses} {stiffnesses} }} "
                           f"damping {{ modal_zeta: {zeta!r} }} }}")
        return self

    def structure_text(self, text):
        """Any structure the config format holds, as the text of its ``structure { ... }`` block.
        Matrices as arrays go to ``matrices(M, C, K)``."""
        if not isinstance(text, str):
            raise TypeError(f"structure_text: text must be a str (the body of a structure {{ ... }} "
                            f"block), got {_type_name(text)}; give matrices to Study.matrices(M, C, K)")
        self._structure = f"structure {{ {text} }}"
        return self

    def matrices(self, M, C=None, K=None, influence=None, zeta=None):
        """A structure by its matrices, SI units, as NumPy arrays (or nested lists): mass M (kg),
        damping C (N s/m) and stiffness K (N/m), each n x n, and the influence vector (n, default
        all ones). Without C, give ``zeta``: modal damping of that ratio. The library checks that
        M is symmetric positive definite and K positive semi-definite when the study compiles.
        A wrong type raises TypeError naming the argument; a wrong shape or a value that is not
        finite, BadInputError."""
        if K is None:
            raise TypeError("matrices: K (the stiffness, N/m) is required")
        mass = _matrix(M, "matrices: M (kg)")
        n = mass.shape[0]
        blocks = [f"mass {{ {_matrix_text(mass)} }}",
                  f"stiffness {{ {_matrix_text(_matrix(K, 'matrices: K (N/m)', n))} }}"]
        if C is not None:
            if zeta is not None:
                raise _rths.BadInputError("matrices: give C or zeta, not both")
            blocks.append(f"damping {{ {_matrix_text(_matrix(C, 'matrices: C (N s/m)', n))} }}")
        if influence is not None:
            iota = _vector(influence, "matrices: influence", n)
            blocks.append(f"influence {{ rows: {n} values: [{', '.join(repr(float(x)) for x in iota)}] }}")
        damping = ""
        if C is None:
            if zeta is None:
                raise _rths.BadInputError("matrices: give C (N s/m) or zeta (modal damping ratio)")
            damping = f" damping {{ modal_zeta: {_number(zeta, 'matrices: zeta', 0.0, 1.0)!r} }}"
        self._structure = f"structure {{ matrices {{ {' '.join(blocks)} }}{damping} }}"
        return self

    # --- the motion, the integrator, the experimental part -----------------------------------------
    def motion(self, path, units=None, scale=1.0):
        """A ground motion file: PEER AT2 (in g) or columns, whose units ('g', 'm/s2', 'cm/s2')
        must then be given."""
        fields = [f"path: {_quoted(path)}"]
        if units is not None:
            if units not in _MOTION_UNITS:
                raise _rths.BadInputError(f"motion: unknown units '{units}' ({', '.join(_MOTION_UNITS)})")
            fields.append(f"column_units: {_MOTION_UNITS[units]}")
        if scale != 1.0:
            fields.append(f"scale: {_number(scale, 'motion: scale', 0.0, None, True)!r}")
        self._motion = "motion { " + " ".join(fields) + " }"
        return self

    def integrator(self, kind="explicit-newmark", dt=0.001):
        """The integrator (``explicit-newmark``, ``central-difference``, ``chen-ricles``,
        ``alpha-os``, ``kr-alpha``, ``newmark-average-acceleration``) and its step dt (s) in
        [1 us, 1 s]."""
        if kind not in _INTEGRATORS:
            raise _rths.BadInputError(f"integrator: unknown kind '{kind}' ({', '.join(_INTEGRATORS)})")
        dt = _number(dt, "integrator: dt (s)", 1e-6, 1.0)
        self._integrator = f"integrator {{ kind: {_INTEGRATORS[kind]} dt: {dt!r} }}"
        return self

    def experimental(self, fraction=1.0, model="linear {}"):
        """The share of every storey's stiffness that the specimen carries, in (0, 1], and the
        storey model as config text (``linear {}``, ``bilinear { yield_displacement: 0.01
        post_yield_ratio: 0.1 }``, ...)."""
        fraction = _number(fraction, "experimental: fraction", 0.0, 1.0, low_open=True)
        if not isinstance(model, str):
            raise TypeError(f"experimental: model must be config text (str), got {_type_name(model)}")
        self._experimental_dofs = []
        self._substructuring = f"substructuring {{ experimental_fraction: {fraction!r} model {{ {model} }} }}"
        return self

    def experimental_dof(self, dof, stiffness, mass=0.0, damping=None, zeta=None, model="linear {}",
                         from_dof=None, angle_degrees=None):
        """Adds a specimen to a structure given by matrices (or a shear building, taken as its
        matrices): between DOF `dof` (1-based) and the ground, or with `from_dof` an element
        between the two DOFs (a storey's specimen: deformation u[dof] - u[from_dof]), with
        `angle_degrees` a brace at that angle (deformation cos(angle) times that). Stiffness
        (N/m), mass (kg) and damping (N s/m) or damping ratio zeta along the element, the
        restoring-force model as config text. The numerical part is the rest (M - m b b^T,
        C - c b b^T, K - k b b^T). Call once per specimen; each has its own actuator."""
        if isinstance(dof, bool) or not isinstance(dof, numbers.Integral):
            raise TypeError(f"experimental_dof: dof must be an int (1-based), got {_type_name(dof)}")
        if dof < 1:
            raise _rths.BadInputError(f"experimental_dof: dof {dof} is not 1-based (>= 1)")
        fields = [f"dof: {int(dof)}",
                  f"mass: {_number(mass, 'experimental_dof: mass (kg)', 0.0, None)!r}",
                  f"stiffness: {_number(stiffness, 'experimental_dof: stiffness (N/m)', 0.0, None, True)!r}"]
        if from_dof is not None:
            if isinstance(from_dof, bool) or not isinstance(from_dof, numbers.Integral):
                raise TypeError(f"experimental_dof: from_dof must be an int (1-based), got {_type_name(from_dof)}")
            if from_dof < 1 or from_dof == dof:
                raise _rths.BadInputError(
                    f"experimental_dof: from_dof {from_dof} must be another DOF (1-based) than dof {dof}")
            fields.append(f"from_dof: {int(from_dof)}")
        if angle_degrees is not None:
            angle = _number(angle_degrees, "experimental_dof: angle_degrees", -90.0, 90.0)
            if abs(angle) >= 90.0:
                raise _rths.BadInputError("experimental_dof: angle_degrees must be in (-90, 90)")
            fields.append(f"angle_degrees: {angle!r}")
        if damping is not None and zeta is not None:
            raise _rths.BadInputError("experimental_dof: give damping or zeta, not both")
        if damping is not None:
            fields.append(f"damping: {_number(damping, 'experimental_dof: damping (N s/m)', 0.0, None)!r}")
        if zeta is not None:
            fields.append(f"zeta: {_number(zeta, 'experimental_dof: zeta', 0.0, 1.0)!r}")
        if not isinstance(model, str):
            raise TypeError(f"experimental_dof: model must be config text (str), got {_type_name(model)}")
        fields.append(f"model {{ {model} }}")
        self._experimental_dofs.append("experimental_dofs { " + " ".join(fields) + " }")
        self._substructuring = "substructuring { " + " ".join(self._experimental_dofs) + " }"
        return self

    def benchmark(self, experimental_dof=1, j1_search=None):
        """Judge every case but the reference by the RTHS benchmark's criteria J1-J9
        (``Study.criteria()`` defines them): ``run()["benchmark"]`` then holds each
        case's J as {name, value, unit, definition}. experimental_dof (1-based) is where x_t and
        x_m are read; j1_search (s) J1's lag range (default 49 steps)."""
        if isinstance(experimental_dof, bool) or not isinstance(experimental_dof, numbers.Integral):
            raise TypeError(f"benchmark: experimental_dof must be an int, got {_type_name(experimental_dof)}")
        fields = [f"experimental_dof: {int(experimental_dof)}"]
        if j1_search is not None:
            fields.append(f"j1_search: {_number(j1_search, 'benchmark: j1_search (s)', 0.0, 1.0, True)!r}")
        self._benchmark = "benchmark { " + " ".join(fields) + " }"
        return self

    @staticmethod
    def criteria():
        """The RTHS benchmark's criteria J1-J9 as [{name, unit, definition}] (J1 in ms, J2-J9 in
        %), as every report names them."""
        return _rths.benchmark_criteria()

    # --- cases and deployment ----------------------------------------------------------------
    def case(self, name, delay=None, delay_model="shift", compensation=None, expect_unstable=False,
             stages=None, force_predictor=None, link=None, text=None):
        """Adds a case; the first is the reference. Stacked delays (``delay=[0.060, 0.014]``),
        any delay stage as text (``stages``), compensation, a force predictor and the network
        link in process (``link=rths.Link(0.030, jitter=0.0025, loss=0.01)``): see ``Case``
        and ``Link``."""
        if any(c.name == name for c in self._cases):
            raise _rths.BadInputError(f"case: '{name}' is already a case of the study")
        self._cases.append(Case(name, delay, delay_model, compensation, expect_unstable, stages,
                                force_predictor, link, text))
        return self

    def deployment(self, text):
        """The deployment for distributed runs, as the text of its ``deployment { ... }`` block
        (nodes, links, clock, limits; see configs/paper_frame_distributed.textproto)."""
        self._deployment = f"deployment {{ {text} }}"
        return self

    def servo(self, rate_hz):
        """The actuator emulator's servo loop rate (Hz), an integer multiple of the integrator's."""
        self._servo_rate = _number(rate_hz, "servo: rate (Hz)", 0.0, None, True)
        return self

    @property
    def cases(self):
        return [c.name for c in self._cases]

    @property
    def text(self):
        """The study as a Protobuf text config, the format ``rths run`` reads."""
        if self._structure is None:
            raise _rths.BadInputError(f"study {self.name}: no structure (call sdof, shear_building or structure_text)")
        if self._motion is None:
            raise _rths.BadInputError(f"study {self.name}: no ground motion (call motion)")
        if not self._cases:
            raise _rths.BadInputError(f"study {self.name}: no case (call case)")
        lines = [f"name: {_quoted(self.name)}", self._structure, self._motion, self._integrator,
                 self._substructuring]
        lines += [c.text() for c in self._cases]
        if self._servo_rate is not None:
            lines.append(f"servo {{ rate: {self._servo_rate!r} }}")
        if self._benchmark:
            lines.append(self._benchmark)
        if self._deployment:
            lines.append(self._deployment)
        return "\n".join(lines) + "\n"

    def compile(self):
        """The study checked by the library (every field and range), as ``rths.load_study`` gives."""
        return _rths.parse_study(self.text, self.base_dir, f"<study {self.name}>")

    def write(self, path):
        """Writes the config; ``rths run PATH`` then runs the same study. Relative paths inside
        (the motion) are written as given: write it where they resolve, or give absolute ones."""
        with open(path, "w", encoding="utf-8") as f:
            f.write(self.text)
        return path

    def run(self, cases=None):
        """Every case in process, as ``rths.run(study)``: {"summary", "series", "units",
        "benchmark", ...}; "benchmark" holds J1-J9 per case ({name, value, unit, definition})
        when the study has a benchmark section (``benchmark()``), else None. A case that diverged
        or is diverging, and was not expected to (``expect_unstable``), is announced with
        ``warnings.warn`` (RuntimeWarning) naming the case and the verdict; the result is returned
        as it is."""
        result = _rths.run(self.compile(), cases)
        _warn_unexpected_divergence(self.name, result["summary"])
        return result

    def launch(self, out, domain, cases=None, executable=None, timeout=None):
        """Every case (or the named ones) as separate processes over Cyclone DDS, as ``rths
        launch``: writes results, plots and records under `out` and returns its summary.json as a
        dict, with "exit_code" added (0 ok, 1 the run failed its purpose). The DDS domain id
        (0-232) keeps concurrent runs apart. Raises rths.Error when the command cannot start or
        reports bad input (exit 2) or an environment problem (exit 3)."""
        self.compile()  # bad input is named here, before any process starts
        program = executable or os.environ.get("RTHS_EXECUTABLE") or shutil.which("rths")
        if not program:
            raise _rths.Error("launch: the rths program is neither on PATH nor in RTHS_EXECUTABLE")
        with tempfile.NamedTemporaryFile("w", suffix=".textproto", dir=self.base_dir, delete=False) as f:
            f.write(self.text)
            config = f.name
        try:
            command = [program, "launch", config, "--out", str(out), "--domain", str(int(domain))]
            for name in cases or []:
                command += ["--case", name]
            done = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
        finally:
            os.unlink(config)
        if done.returncode not in (0, 1):
            raise _rths.Error(f"launch exited {done.returncode}: {done.stderr.strip()}")
        with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
            summary = json.load(f)
        summary["exit_code"] = done.returncode
        _warn_unexpected_divergence(self.name, summary)
        return summary

    def __repr__(self):
        return f"<rths.Study '{self.name}' built in code, cases {self.cases}>"
