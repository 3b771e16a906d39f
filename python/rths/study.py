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
import os
import shutil
import subprocess
import tempfile

from . import _rths

_DELAY_MODELS = {
    # name: (stage, field): u_r(t) = u(t - tau) and the paper's Eq. 1 forms; see the README.
    "shift": ("shift", "delay"),
    "eq1": ("eq1", "delay"),
    "eq1-lag": ("eq1_lag", "delay"),
    "first-order": ("first_order", "time_constant"),
}
_INTEGRATORS = {
    "explicit-newmark": "EXPLICIT_NEWMARK",
    "central-difference": "CENTRAL_DIFFERENCE",
    "chen-ricles": "CHEN_RICLES",
    "newmark-average-acceleration": "NEWMARK_AVERAGE_ACCELERATION",
    "alpha-os": "ALPHA_OS",
    "kr-alpha": "KR_ALPHA",
}
_MOTION_UNITS = {"g": "G", "m/s2": "M_PER_S2", "cm/s2": "CM_PER_S2"}


def _number(value, what, low=None, high=None, low_open=False):
    """A finite float within [low, high] (low excluded when low_open), else BadInputError naming
    `what`, the value and the range."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise _rths.BadInputError(f"{what}: '{value}' is not a number") from None
    below = low is not None and (x <= low if low_open else x < low)
    if not math.isfinite(x) or below or (high is not None and x > high):
        bracket = "(" if low_open else "["
        raise _rths.BadInputError(f"{what}: {value} is outside {bracket}{low}, {high}]")
    return x


def _quoted(text):
    return '"' + str(text).replace("\\", "\\\\").replace('"', '\\"') + '"'


class Case:
    """One case of a study: a name, the actuator's delay stages (``shift``, ``eq1``, ``eq1-lag``,
    ``first-order``; a lag in s) and optional compensation given as Protobuf text (the body of a
    ``compensation { ... }`` block, e.g. ``"polynomial { order: 2 lead: 0.014 spacing: 0.001 }"``)."""

    def __init__(self, name, delay=None, delay_model="shift", compensation=None, expect_unstable=False):
        if not name:
            raise _rths.BadInputError("case: the name is empty")
        if delay_model not in _DELAY_MODELS:
            raise _rths.BadInputError(f"case {name}: unknown delay_model '{delay_model}' "
                                      f"({', '.join(_DELAY_MODELS)})")
        self.name = name
        self.delay = None if delay is None else _number(delay, f"case {name}: delay (s)", 0.0, 1.0)
        self.delay_model = delay_model
        self.compensation = compensation
        self.expect_unstable = bool(expect_unstable)

    def text(self):
        body = [f"name: {_quoted(self.name)}"]
        if self.delay is not None:
            stage, field = _DELAY_MODELS[self.delay_model]
            body.append(f"delay {{ {stage} {{ {field}: {self.delay!r} }} }}")
        if self.compensation:
            body.append(f"compensation {{ {self.compensation} }}")
        if self.expect_unstable:
            body.append("expect_unstable: true")
        return "cases { " + " ".join(body) + " }"


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
        """Any structure the config format holds, as the text of its ``structure { ... }`` block."""
        self._structure = f"structure {{ {text} }}"
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
        self._substructuring = f"substructuring {{ experimental_fraction: {fraction!r} model {{ {model} }} }}"
        return self

    # --- cases and deployment ----------------------------------------------------------------
    def case(self, name, delay=None, delay_model="shift", compensation=None, expect_unstable=False):
        """Adds a case; the first is the reference. See ``Case``."""
        if any(c.name == name for c in self._cases):
            raise _rths.BadInputError(f"case: '{name}' is already a case of the study")
        self._cases.append(Case(name, delay, delay_model, compensation, expect_unstable))
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
        """Every case in process, as ``rths.run(study)``: {"summary", "series", "units", ...}."""
        return _rths.run(self.compile(), cases)

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
        return summary

    def __repr__(self):
        return f"<rths.Study '{self.name}' built in code, cases {self.cases}>"
