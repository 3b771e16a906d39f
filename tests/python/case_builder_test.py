"""rths.Case and rths.Link: every case a config file can hold, built in code (stacked delays, any
delay stage, a force predictor, the network link in process), runs as the same case written by
hand. Run from ctest (python_case_builder) with PYTHONPATH=build/python and RTHS_SOURCE_DIR set.
In process only: no DDS domain."""
import os
from pathlib import Path

import numpy as np
import pytest

import rths

SOURCE = Path(os.environ["RTHS_SOURCE_DIR"])
MOTION = str(SOURCE / "data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2")


def frame(name="frame"):
    return (rths.Study(name)
            .sdof(period=0.5, zeta=0.05)
            .motion(MOTION)
            .integrator("explicit-newmark", dt=0.001)
            .experimental(fraction=2 / 3))


# The same four cases as a config file writes them, by hand.
HAND_WRITTEN_CASES = """
cases { name: "reference" }
cases {
  name: "predicted_60ms_soft"
  delay { shift { delay: 0.060 } }
  delay { shift { delay: 0.014 } }
  force_predictor { stiffness_factor: 0.7 max_relative_error: 0.5 }
}
cases {
  name: "sites_link"
  delay { shift { delay: 0.014 } }
  link {
    to_node { one_way_delay: 0.030 jitter: 0.0025 loss: 0.01 seed: 521 network { drift_rate: 0.0001 } }
    from_node { one_way_delay: 0.030 jitter: 0.0025 loss: 0.01 seed: 522 network { drift_rate: 0.0001 } }
  }
  force_predictor { }
}
cases {
  name: "actuator_stages"
  delay { first_order { time_constant: 0.004 } }
  delay { jitter { mean_delay: 0.002 std_dev: 0.0005 seed: 7 } }
}
"""


def built_in_code():
    return (frame()
            .case("reference")
            .case("predicted_60ms_soft", delay=[0.060, 0.014],
                  force_predictor={"stiffness_factor": 0.7, "max_relative_error": 0.5})
            .case("sites_link", delay=0.014, force_predictor=True,
                  link=rths.Link(0.030, jitter=0.0025, loss=0.01, drift_rate=0.0001, seed=521))
            .case("actuator_stages", stages=["first_order { time_constant: 0.004 }",
                                             "jitter { mean_delay: 0.002 std_dev: 0.0005 seed: 7 }"]))


def test_predictor_stacked_delays_stages_and_a_link_run_as_the_hand_written_config():
    study = built_in_code()
    head = study.text.split("cases {")[0]
    by_hand = rths.parse_study(head + HAND_WRITTEN_CASES, study.base_dir, "<by hand>")
    ours, theirs = study.run(), rths.run(by_hand)
    assert [c["name"] for c in ours["summary"]["cases"]] == [
        "reference", "predicted_60ms_soft", "sites_link", "actuator_stages"]
    for case, hand in zip(ours["summary"]["cases"], theirs["summary"]["cases"]):
        assert case["delay"] == hand["delay"]
        assert case["status"] == hand["status"] == "completed", case["status_detail"]
    for name, series in theirs["series"].items():
        np.testing.assert_array_equal(ours["series"][name], series, err_msg=name)
    cases = {c["name"]: c for c in ours["summary"]["cases"]}
    assert cases["predicted_60ms_soft"]["delay"].startswith("shift(60 ms) -> shift(14 ms)")
    link = cases["sites_link"]
    assert "link 30 ms, jitter 2.5 ms, loss 1 %, drift 0.1 ms/s each way" in link["delay"]
    # The link's lag is in the case's check and its answers are what the predictor fitted on: the
    # error against the reference is small and not nothing.
    assert link["nominal_delay_s"] == pytest.approx(0.074)
    assert 0.0 < link["rms_error_pct"] < 5.0
    assert link["prediction_error"] is not None


def test_the_link_the_case_and_its_answer_way_write_their_fields():
    link = rths.Link(0.05, jitter=0.001, seed=9, spike_delay=0.02, spike_every=100, spike_steps=5,
                     back={"one_way_delay": 0.04, "loss": 0.02})
    assert link.text() == (
        "link { to_node { one_way_delay: 0.05 jitter: 0.001 seed: 9 network { spike_delay: 0.02 "
        "spike_every: 100 spike_steps: 5 } } from_node { one_way_delay: 0.04 jitter: 0.001 "
        "loss: 0.02 seed: 10 network { spike_delay: 0.02 spike_every: 100 spike_steps: 5 } } }")
    case = rths.Case("c", force_predictor={"actuators": [1, 2], "linear_model": True})
    assert "force_predictor { actuators: 1 actuators: 2 linear_model: true }" in case.text()


def test_a_force_predictor_given_as_compensation_is_named_with_the_way_to_give_it():
    with pytest.raises(rths.BadInputError, match="force_predictor=True, a dict"):
        frame().case("reference").case("p", delay=0.06, compensation="force_predictor { }")


def test_a_link_out_of_range_or_of_the_wrong_count_is_named():
    lossy = frame().case("reference").case("lossy", link=rths.Link(0.03, loss=1.5))
    with pytest.raises(rths.BadInputError, match=r"link\[0\]\.to_node\.loss = 1\.5 is outside"):
        lossy.compile()
    two = frame().case("reference").case("two", link=[rths.Link(0.01), rths.Link(0.02)])
    with pytest.raises(rths.BadInputError, match="2 link blocks for 1 actuators"):
        two.run()
    with pytest.raises(TypeError, match="Link: jitter: expected a number"):
        rths.Link(0.03, jitter="2 ms")
    with pytest.raises(TypeError, match="link must be an rths.Link"):
        rths.Case("c", link={"one_way_delay": 0.03})
