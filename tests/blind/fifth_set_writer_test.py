#!/usr/bin/python3
"""fifth_set_writer's cases do what their truth says (tests/blind/fifth_set_writer.cpp): the set
is written at 15 s, each record exported by `rths export --csv`, and each effect is found in the
recorded signals against its own law on the rig (the brace ke = 0.6 * 12000 kg (2 pi / 0.8 s)^2
= 444 kN/m, dt 2 ms, no declared actuator stage): the clean rigs agree and follow the brace with
the rod on the command, the valve realises the command 3 steps late, the rod never moves faster
than 0.30 m/s, the clevis plays 0.3 mm each way, the brace yields bilinearly at 12 mm, the gusset
crack softens it with travel, the LVDT's bracket creeps 1.5 mm, the load cell holds one reading
for 0.3 s from 6 s, the pump's pressure dip caps the brace at 20 kN from 4 to 6 s, 9 spikes of
1.5 mm hit the recorded LVDT between 12 and 12.5 s, and 30 N of 50 Hz hum sits on the load cell.
truth.json: 12 cases, 2 clean, 3 windows, every seed its own.
Needs BLIND_RTHS, BLIND_FIFTH_WRITER and BLIND_DATA (ctest sets them). Exit 0 when all hold."""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import third_set_writer_test as third  # noqa: E402  (a record's signals)

KE = 0.6 * 12000.0 * (2.0 * math.pi / 0.8) ** 2  # N/m, the brace
DT = 0.002  # s
DURATION = 15.0  # s, the writer's default
# One reading's error: LVDT 2 um noise and 6.1 um quantum, load cell 1.5 N and 3.1 N; a bound
# holds at 5 sigma plus half a quantum.
LVDT_SLACK = 5 * 2e-6 + 0.5 * 0.4 / 65536  # m
FORCE_SLACK = 5 * 1.5 + 0.5 * 2e5 / 65536 + KE * LVDT_SLACK  # N, on F - KE y

fit_through_zero = third.fit_through_zero


def rms(values):
    values = list(values)
    return math.sqrt(sum(v * v for v in values) / len(values))


def play(signal, half_width):
    """The play operator: the output stays until the input leaves it by half_width."""
    out, end = [], 0.0
    for x in signal:
        end = min(max(end, x - half_width), x + half_width)
        out.append(end)
    return out


def bilinear(signal, yield_displacement, hardening):
    """Kinematic-hardening bilinear force (N) of the brace along signal (m)."""
    out, plastic = [], 0.0
    cap = (1 - hardening) * KE * yield_displacement
    for x in signal:
        elastic = (1 - hardening) * KE * (x - plastic)
        if abs(elastic) > cap:
            plastic = x - math.copysign(yield_displacement, elastic)
        out.append((1 - hardening) * KE * (x - plastic) + hardening * KE * x)
    return out


@unittest.skipUnless(os.environ.get("BLIND_RTHS") and os.environ.get("BLIND_FIFTH_WRITER"),
                     "BLIND_RTHS and BLIND_FIFTH_WRITER not set")
class FifthSet(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.folder = tempfile.mkdtemp(prefix="blind_fifth_")
        subprocess.run([os.environ["BLIND_FIFTH_WRITER"], "--set", "fifth", "--out", cls.folder,
                        "--data", os.environ["BLIND_DATA"]], check=True, capture_output=True)
        with open(os.path.join(cls.folder, "truth.json")) as f:
            cls.truth = {c["name"]: c for c in json.load(f)["cases"]}

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.folder, ignore_errors=True)

    signals = third.ThirdSet.signals  # {command, y, force, u} as `rths export --csv` reads them

    def window_steps(self, name):
        t0, t1 = self.truth[name]["truth"]["window_s"]
        return round(t0 / DT), round(t1 / DT)

    def residual(self, s):
        return [f - KE * y for f, y in zip(s["force"], s["y"])]

    def test_truth_lists_twelve_cases_two_clean_three_windows(self):
        self.assertEqual(len(self.truth), 12)
        self.assertEqual(sum(1 for c in self.truth.values() if c["truth"]["part"] is None), 2)
        self.assertEqual(sum(1 for c in self.truth.values() if "window_s" in c["truth"]), 3)
        self.assertEqual(len({c["seed"] for c in self.truth.values()}), 12)
        self.assertEqual(self.truth["fifth_mains_hum"]["truth"]["frequency_hz"], 50)

    def test_clean_rigs_agree_and_follow_the_brace_on_the_command(self):
        a, b = self.signals("fifth_clean_a"), self.signals("fifth_clean_b")
        self.assertEqual(len(a["u"]), round(DURATION / DT) + 1)
        self.assertLess(max(abs(x - y) for x, y in zip(a["u"], b["u"])), 5e-5)
        self.assertGreater(max(abs(x) for x in a["u"]), 0.05)  # the motion drives the frame
        self.assertLess(max(abs(r) for r in self.residual(a)[1:]), FORCE_SLACK)
        self.assertLess(max(abs(y - c) for y, c in zip(a["y"], a["command"])), LVDT_SLACK)

    def test_valve_realises_the_command_3_steps_late(self):
        s = self.signals("fifth_valve_lag")
        misfit = {lag: rms(s["y"][k] - s["command"][k - lag] for k in range(5, len(s["y"])))
                  for lag in range(6)}
        self.assertEqual(min(misfit, key=misfit.get), 3)
        self.assertLess(misfit[3], 4e-6)
        self.assertGreater(misfit[0], 10 * misfit[3])

    def test_rod_never_moves_faster_than_0_30_m_per_s(self):
        y = self.signals("fifth_valve_rate_limit")["y"]
        speeds = [abs(y[k + 1] - y[k]) / DT for k in range(len(y) - 1)]
        slack = 2 * LVDT_SLACK / DT
        self.assertLess(max(speeds), 0.30 + slack)
        self.assertGreater(sum(1 for v in speeds if v > 0.30 - slack), 50)
        clean = self.signals("fifth_clean_a")["y"]
        self.assertGreater(max(abs(clean[k + 1] - clean[k]) / DT for k in range(len(clean) - 1)),
                           0.45)

    def test_clevis_plays_0_3_mm_each_way(self):
        s = self.signals("fifth_clevis_play")
        law = play(s["command"], 0.3e-3)
        self.assertLess(max(abs(y - x) for y, x in zip(s["y"], law)), LVDT_SLACK)
        self.assertGreater(max(abs(y - c) for y, c in zip(s["y"], s["command"])), 0.29e-3)
        self.assertLess(max(abs(r) for r in self.residual(s)[1:]), FORCE_SLACK)

    def test_brace_yields_bilinearly_at_12_mm(self):
        s = self.signals("fifth_brace_yield")
        law = bilinear(s["command"], 12e-3, 0.02)
        self.assertLess(max(abs(f - g) for f, g in zip(s["force"], law)), FORCE_SLACK)
        self.assertGreater(rms(self.residual(s)), 1000.0)
        self.assertLess(max(abs(f) for f in s["force"]), KE * 12e-3 * 1.2)

    def test_gusset_crack_softens_the_brace_with_travel(self):
        s = self.signals("fifth_gusset_crack")
        travel, law, last = 0.0, [], 0.0
        for x in s["command"]:
            travel, last = travel + abs(x - last), x
            law.append(KE * x * (1 - 0.35 * (1 - math.exp(-travel / 1.5))))
        self.assertLess(max(abs(f - g) for f, g in zip(s["force"], law)), FORCE_SLACK)
        self.assertGreater(travel, 1.5)  # the crack passes its e-fold within the run
        late = range(len(s["y"]) - 1500, len(s["y"]))
        self.assertLess(fit_through_zero([s["y"][k] for k in late],
                                         [s["force"][k] for k in late]) / KE, 0.85)

    def test_lvdt_bracket_creeps_1_5_mm_over_the_run(self):
        s = self.signals("fifth_lvdt_bracket_creep")
        creep = [1.5e-3 * k * DT / DURATION for k in range(len(s["y"]))]
        law = [KE * (y - d) for y, d in zip(s["y"], creep)]
        self.assertLess(max(abs(f - g) for f, g in zip(s["force"], law)), FORCE_SLACK)
        self.assertLess(max(abs(y - c) for y, c in zip(s["y"], s["command"])), LVDT_SLACK)
        self.assertAlmostEqual(sum(self.residual(s)[-500:]) / 500, -KE * 1.45e-3, delta=15.0)

    def test_load_cell_holds_one_reading_for_0_3_s_from_6_s(self):
        s = self.signals("fifth_force_sample_held")
        k0, k1 = self.window_steps("fifth_force_sample_held")
        self.assertEqual((k0, k1), (3000, 3150))
        self.assertTrue(all(s["force"][k] == s["force"][k0 - 1] for k in range(k0, k1)))
        self.assertGreater(max(abs(r) for r in self.residual(s)[k0:k1]), 1000.0)
        self.assertLess(max(abs(r) for r in self.residual(s)[1:k0]), FORCE_SLACK)
        self.assertLess(max(abs(r) for r in self.residual(s)[k1:]), FORCE_SLACK)

    def test_pump_pressure_dip_caps_the_brace_at_20_kn_from_4_to_6_s(self):
        s = self.signals("fifth_pump_pressure_dip")
        k0, k1 = self.window_steps("fifth_pump_pressure_dip")
        reach = 20e3 / KE
        law = [min(max(c, -reach), reach) if k0 <= k < k1 else c
               for k, c in enumerate(s["command"])]
        self.assertLess(max(abs(y - x) for y, x in zip(s["y"], law)), LVDT_SLACK)
        self.assertLess(max(abs(f) for f in s["force"][k0:k1]), 20e3 + FORCE_SLACK)
        self.assertGreater(sum(1 for c in s["command"][k0:k1] if abs(c) > reach + 1e-3), 20)
        self.assertGreater(max(abs(f) for f in s["force"][:k0]), 25e3)

    def test_welder_puts_9_spikes_of_1_5_mm_on_the_recorded_lvdt(self):
        s = self.signals("fifth_welder_spikes")
        k0, k1 = self.window_steps("fifth_welder_spikes")
        spikes = [k for k, (y, c) in enumerate(zip(s["y"], s["command"])) if abs(y - c) > 1e-3]
        self.assertEqual(len(spikes), 9)
        self.assertTrue(all(k0 <= k < k1 for k in spikes))
        for k in spikes:
            self.assertAlmostEqual(abs(s["y"][k] - s["command"][k]), 1.5e-3, delta=LVDT_SLACK)
        forces = [f - KE * c for f, c in zip(s["force"], s["command"])]
        self.assertLess(max(abs(r) for r in forces[1:]), FORCE_SLACK)

    def test_load_cell_hums_30_n_at_50_hz(self):
        r = self.residual(self.signals("fifth_mains_hum"))[1:]
        c = sum(x * math.cos(2 * math.pi * 50 * (k + 1) * DT) for k, x in enumerate(r))
        q = sum(x * math.sin(2 * math.pi * 50 * (k + 1) * DT) for k, x in enumerate(r))
        self.assertAlmostEqual(math.hypot(c, q) * 2 / len(r), 30.0, delta=1.5)
        clean = self.residual(self.signals("fifth_clean_a"))[1:]
        c = sum(x * math.cos(2 * math.pi * 50 * (k + 1) * DT) for k, x in enumerate(clean))
        self.assertLess(abs(c) * 2 / len(clean), 1.5)


if __name__ == "__main__":
    unittest.main()
