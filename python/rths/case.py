"""A study's cases built in code: each case's actuator lag (one delay or stacked ones, any config
stage), its compensation, its force predictor and, in process, the network link to each lab. A
Case writes the ``cases { ... }`` block of the Protobuf text config ``rths run`` reads, so
whatever a config file's case can say, a Case can (``Case.text()`` shows it).

Units are SI: lags in seconds, drift in seconds per second, loss a probability.
"""

import math
import numbers

from . import _rths

_DELAY_MODELS = {
    # name: (stage, field): u_r(t) = u(t - tau) and the paper's Eq. 1 forms; see the README.
    "shift": ("shift", "delay"),
    "eq1": ("eq1", "delay"),
    "eq1-lag": ("eq1_lag", "delay"),
    "first-order": ("first_order", "time_constant"),
}


def _type_name(value):
    kind = type(value)
    return kind.__name__ if kind.__module__ == "builtins" else f"{kind.__module__}.{kind.__name__}"


def _quoted(text):
    return '"' + str(text).replace("\\", "\\\\").replace('"', '\\"') + '"'


def _finite(value, what):
    """A finite float: TypeError naming `what` for another type, BadInputError for inf or nan.
    Ranges are the library's (one rule per quantity, named with the config field)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{what}: expected a number, got {_type_name(value)} ({value!r:.60})")
    if not math.isfinite(float(value)):
        raise _rths.BadInputError(f"{what}: {value} is not finite")
    return float(value)


def _count(value, what):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{what}: expected an int, got {_type_name(value)}")
    return int(value)


def _text(value, what):
    if not isinstance(value, str):
        raise TypeError(f"{what}: expected config text (str), got {_type_name(value)}")
    return value


def fields_text(fields, what):
    """A dict as the body of a config message: numbers and bools as they read, a str quoted
    unless it is an enum name (UPPER_CASE), a list as the field repeated, a dict as a nested
    message. ``{"stiffness_factor": 0.7, "actuators": [1, 2]}`` gives
    ``stiffness_factor: 0.7 actuators: 1 actuators: 2``."""
    if not isinstance(fields, dict):
        raise TypeError(f"{what}: expected a dict of fields, got {_type_name(fields)}")
    parts = []
    for name, value in fields.items():
        for item in value if isinstance(value, (list, tuple)) else [value]:
            if isinstance(item, dict):
                parts.append(f"{name} {{ {fields_text(item, f'{what}.{name}')} }}")
            elif isinstance(item, bool):
                parts.append(f"{name}: {'true' if item else 'false'}")
            elif isinstance(item, numbers.Integral):
                parts.append(f"{name}: {int(item)}")
            elif isinstance(item, numbers.Real):
                parts.append(f"{name}: {_finite(item, f'{what}.{name}')!r}")
            elif isinstance(item, str):
                enum = item.isupper() and item.replace("_", "").isalnum()
                parts.append(f"{name}: {item if enum else _quoted(item)}")
            else:
                raise TypeError(f"{what}.{name}: a {_type_name(item)} has no config text")
    return " ".join(parts)


class Link:
    """The network between the integrator and one lab, for a case run in process (config
    ``CaseLink``): each way adds ``one_way_delay`` (s), a normal ``jitter`` (s, its standard
    deviation), loses a message with probability ``loss`` and drifts by ``drift_rate`` (s per s
    of the run); ``spike_delay`` (s) on ``spike_steps`` of every ``spike_every`` steps, and the
    steps ``drop_first_step`` + ``drop_steps`` lost, as ``rths sites`` injects them. The draws
    of the command's way use ``seed``, the answer's ``seed + 1``; ``back`` (a dict of the same
    names) gives the answer's way its own values. Each step uses the newest answer that has
    arrived: answers come late, in bursts or never, and the actuator's command is never
    jittered. The ranges are checked when the study compiles, naming the config field."""

    _NETWORK = ("drift_rate", "spike_delay", "spike_every", "spike_steps", "drop_first_step",
                "drop_steps")

    def __init__(self, one_way_delay=0.0, jitter=0.0, loss=0.0, drift_rate=0.0, seed=0,
                 spike_delay=0.0, spike_every=0, spike_steps=0, drop_first_step=0, drop_steps=0,
                 back=None):
        self.to_node = {"one_way_delay": one_way_delay, "jitter": jitter, "loss": loss,
                        "seed": seed, "drift_rate": drift_rate, "spike_delay": spike_delay,
                        "spike_every": spike_every, "spike_steps": spike_steps,
                        "drop_first_step": drop_first_step, "drop_steps": drop_steps}
        self.from_node = dict(self.to_node, seed=_count(seed, "Link: seed") + 1)
        if back is not None:
            if not isinstance(back, dict):
                raise TypeError(f"Link: back must be a dict of the answer's way, got {_type_name(back)}")
            unknown = set(back) - set(self.to_node)
            if unknown:
                raise _rths.BadInputError(f"Link: back names unknown fields {sorted(unknown)} "
                                          f"(known: {', '.join(self.to_node)})")
            self.from_node.update(back)
        for way in (self.to_node, self.from_node):
            for name, value in way.items():
                counted = name == "seed" or name.startswith(("spike_every", "spike_steps", "drop_"))
                way[name] = (_count if counted else _finite)(value, f"Link: {name}")

    @staticmethod
    def _way(way):
        lag = [f"{name}: {way[name]!r}" for name in ("one_way_delay", "jitter", "loss", "seed")
               if way[name]]
        network = [f"{name}: {way[name]!r}" for name in Link._NETWORK if way[name]]
        if network:
            lag.append("network { " + " ".join(network) + " }")
        return " ".join(lag)

    def text(self):
        """The ``link { ... }`` block."""
        return (f"link {{ to_node {{ {self._way(self.to_node)} }} "
                f"from_node {{ {self._way(self.from_node)} }} }}")

    def __repr__(self):
        return f"<rths.Link {self.text()}>"


class Case:
    """One case of a study.

    ``delay``: a lag (s) as ``delay_model`` (``shift``, ``eq1``, ``eq1-lag``, ``first-order``),
    or a list of lags stacked in that order (``[0.060, 0.014]``: the network's round trip, then the
    actuator's). ``stages``: further delay stages as config text, each the body of a ``delay {
    ... }`` block (``"first_order { time_constant: 0.01 }"``, ``"jitter { mean_delay: 0.01
    std_dev: 0.002 }"``, any stage), after those. ``compensation``: the body of a
    ``compensation { ... }`` block, or a list of them (one per actuator). ``force_predictor``:
    True (its defaults), a dict of its fields (``{"stiffness_factor": 0.7,
    "max_relative_error": 0.5}``) or the body of its block as text. ``link``: a Link, or a list
    of them (one per actuator), the network in process. ``text`` adds any other fields of the
    case as config text."""

    def __init__(self, name, delay=None, delay_model="shift", compensation=None,
                 expect_unstable=False, stages=None, force_predictor=None, link=None, text=None):
        if not name:
            raise _rths.BadInputError("case: the name is empty")
        if delay_model not in _DELAY_MODELS:
            raise _rths.BadInputError(f"case {name}: unknown delay_model '{delay_model}' "
                                      f"({', '.join(_DELAY_MODELS)})")
        self.name = name
        lags = [] if delay is None else list(delay) if isinstance(delay, (list, tuple)) else [delay]
        self.delays = [_finite(d, f"case {name}: delay (s)") for d in lags]
        for d in self.delays:
            if not 0.0 <= d <= 1.0:
                raise _rths.BadInputError(f"case {name}: delay (s): {d} is outside [0.0, 1.0]")
        self.delay = self.delays[0] if len(self.delays) == 1 else None
        self.delay_model = delay_model
        self.stages = [_text(s, f"case {name}: stages") for s in self._listed(stages)]
        self.compensation = [_text(c, f"case {name}: compensation") for c in self._listed(compensation)]
        for block in self.compensation:
            if block.lstrip().startswith("force_predictor"):
                raise _rths.BadInputError(
                    f"case {name}: force_predictor is not a compensation block (it predicts the "
                    "returning force, after the link): give force_predictor=True, a dict of its "
                    "fields or its text to case()")
        self.force_predictor = self._predictor_text(force_predictor)
        self.links = self._listed(link)
        for item in self.links:
            if not isinstance(item, Link):
                raise TypeError(f"case {name}: link must be an rths.Link or a list of them, got "
                                f"{_type_name(item)}")
        self.expect_unstable = bool(expect_unstable)
        self.extra = None if text is None else _text(text, f"case {name}: text")

    @staticmethod
    def _listed(value):
        if value is None:
            return []
        return list(value) if isinstance(value, (list, tuple)) else [value]

    def _predictor_text(self, value):
        if value is None or value is False:
            return None
        if value is True:
            return ""
        if isinstance(value, dict):
            return fields_text(value, f"case {self.name}: force_predictor")
        return _text(value, f"case {self.name}: force_predictor")

    def text(self):
        """The ``cases { ... }`` block."""
        body = [f"name: {_quoted(self.name)}"]
        stage, field = _DELAY_MODELS[self.delay_model]
        body += [f"delay {{ {stage} {{ {field}: {d!r} }} }}" for d in self.delays]
        body += [f"delay {{ {s} }}" for s in self.stages]
        body += [f"compensation {{ {c} }}" for c in self.compensation]
        if self.force_predictor is not None:
            body.append(f"force_predictor {{ {self.force_predictor} }}")
        body += [link.text() for link in self.links]
        if self.expect_unstable:
            body.append("expect_unstable: true")
        if self.extra:
            body.append(self.extra)
        return "cases { " + " ".join(body) + " }"
