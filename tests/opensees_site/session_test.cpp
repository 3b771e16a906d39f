// The session in process: a client speaking genericClient's protocol over loopback TCP, the site's
// study evaluated by core::HybridRestoring (what the actuator emulator runs) in place of DDS.
#include "opensees_site/session.h"

#include <gtest/gtest.h>

#include <future>
#include <thread>

#include "coordinator/coordinator.h"
#include "core/simulation.h"
#include "frame_study.h"
#include "generic_client.h"
#include "runtime/node/plan.h"

namespace rths::opensees {
namespace {

struct Served {
  core::SimulationResult result;
  std::string refusal, ending;
};

// Serves one client on `listener` with the study's case, in process.
class InProcessSite {
 public:
  InProcessSite(const std::string& text, const std::string& case_name)
      : prepared_(study::prepare_study(study::parse_study(text, "test"), "/")),
        setup_(study::setup_for_case(prepared_, study::find_case(prepared_.config, case_name))),
        mapping_(prepared_.config.deployment().opensees(),
                 {setup_.partition.experimental[0]->initial_stiffness()},
                 setup_.partition.actuator_storeys, 1),
        listener_("127.0.0.1", 0) {}

  int port() const { return listener_.port(); }
  const BasicMapping& mapping() const { return mapping_; }

  std::future<Served> serve(std::chrono::milliseconds frame_timeout = std::chrono::seconds(5)) {
    return std::async(std::launch::async, [this, frame_timeout] {
      Served served;
      auto client = listener_.accept(std::chrono::seconds(10));
      if (!client) {
        served.refusal = "no client";
        return served;
      }
      SizeMessage sizes{};
      client->read_exact(sizes.data(), sizeof sizes, std::chrono::seconds(5));
      SessionOptions o;
      o.dt = setup_.dt;
      o.max_steps = prepared_.motion.acceleration.size() + 1;  // as the Site: step N at t = N dt
      o.dofs = 1;
      try {
        o.frame_size = check_size_message(sizes, mapping_.basic_dofs(), 0);
      } catch (const ProtocolError& e) {
        served.refusal = e.what();
        return served;
      }
      o.frame_timeout = frame_timeout;
      o.frame_timeout_reason = "the test's";
      o.client = "client";
      core::HybridRestoring restoring(setup_.partition, setup_.delays, setup_.dt,
                                      setup_.servo_substeps);
      core::StepHooks hooks;
      Session session(*client, mapping_, o);
      try {
        session.drive(restoring, hooks, served.result);
      } catch (const coordinator::RunAborted& e) {
        served.refusal = e.what();
      }
      served.ending = session.ending();
      return served;
    });
  }

 private:
  study::PreparedStudy prepared_;
  core::HybridSetup setup_;
  BasicMapping mapping_;
  Listener listener_;
};

test::OneStoreyFrame frame() {
  test::OneStoreyFrame f;
  f.k_num = test::numerical_stiffness();
  f.k_spec = test::specimen_stiffness();
  f.damping = test::frame_damping();
  return f;
}

double peak_relative_difference(const test::FrameRun& a, const test::FrameRun& b) {
  double worst = 0;
  for (std::size_t k = 0; k < a.u.size(); ++k) worst = std::max(worst, std::abs(a.u[k] - b.u[k]));
  return worst / b.peak();
}

TEST(Session, LagFreeServedColumnEqualsTheElasticElement) {
  const std::string text = test::site_study(4, "");
  const auto ground = test::ground_motion(text);
  InProcessSite site(text, "reference");
  auto served = site.serve();
  test::GenericClient client(site.port(), 2);
  client.send_sizes();
  const test::FrameRun run = test::run_frame(frame(), ground, test::served_specimen(client));
  client.send_action(99);
  const Served s = served.get();
  ASSERT_TRUE(s.refusal.empty()) << s.refusal;
  EXPECT_NE(s.ending.find("(DIE) after step " + std::to_string(ground.size())), std::string::npos);
  const double k = frame().k_spec;
  const test::FrameRun elastic =
      test::run_frame(frame(), ground, [k](double u, double, double) { return k * u; });
  EXPECT_GT(elastic.peak(), 1e-3);  // m: the record has begun to shake the frame
  EXPECT_LE(peak_relative_difference(run, elastic), 1e-9);
  ASSERT_EQ(s.result.steps(), ground.size() + 1);
  EXPECT_EQ(s.result.displacement(100, 0), run.u[100]);
  EXPECT_EQ(s.result.command(100, 0), run.u[100]);
}

// The paper's 14 ms of actuator lag enlarges the client's peak as much as it enlarges rths's own
// run of the paper's frame.
TEST(Session, FourteenMsOfLagGrowsThePeakAsRthsOwnPaperFrameRunDoes) {
  const std::string text = test::site_study(6, "");
  const auto ground = test::ground_motion(text);
  InProcessSite site(text, "lag_shift_14ms");
  auto served = site.serve();
  test::GenericClient client(site.port(), 2);
  client.send_sizes();
  test::FrameRun lagged = test::run_frame(frame(), ground, test::served_specimen(client));
  client.close();
  ASSERT_TRUE(served.get().refusal.empty());
  const double k = frame().k_spec;
  test::FrameRun elastic =
      test::run_frame(frame(), ground, [k](double u, double, double) { return k * u; });
  // Over the motion's own samples: rths's run below has no step past the record's end.
  lagged.u.resize(ground.size());
  elastic.u.resize(ground.size());
  const double growth = lagged.peak() / elastic.peak();

  const std::string paper =
      "name: \"paper_frame\"\nstructure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: "
      "0.05 } }\nmotion { path: \"" +
      test::motion_file() +
      "\" duration: 6 }\n"
      "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
      "substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }\n"
      "cases { name: \"reference\" }\ncases { name: \"lag\" delay { shift { delay: 0.014 } } }\n";
  const study::PreparedStudy p = study::prepare_study(study::parse_study(paper, "paper"), "/");
  const auto peak = [&](const char* name) {
    const auto r =
        core::simulate(study::setup_for_case(p, study::find_case(p.config, name)), p.motion);
    return r.displacement.cwiseAbs().maxCoeff();
  };
  const double rths_growth = peak("lag") / peak("reference");
  EXPECT_GT(growth, 1.05);  // the lag matters on this record
  EXPECT_NEAR(growth, rths_growth, 1e-6 * rths_growth);
}

// ExplicitDifference: 3, 10, 14, then a second 3 at the same displacement (new velocity), 5.
// CentralDifference: the force at the displacement the previous step's update set.
TEST(Session, OpenSeesOrdersOfExplicitIntegratorsCommandOncePerStep) {
  InProcessSite site(test::site_study(1, ""), "reference");
  auto served = site.serve();
  test::GenericClient client(site.port(), 2);
  client.send_sizes();
  for (int k = 1; k <= 3; ++k) {
    const double u = 1e-3 * k, t = 1e-3 * k;
    client.set_trial({0, u}, {0, 0.1}, {0, 0}, t);
    const auto f = client.ask(10);
    EXPECT_DOUBLE_EQ(f[1], test::specimen_stiffness() * u);
    EXPECT_DOUBLE_EQ(f[0], -f[1]);
    client.ask(14);
    client.set_trial({0, u}, {0, 0.2}, {0, 1}, t);
    EXPECT_EQ(client.ask(10)[1], f[1]);  // the same step: no second command
    client.send_action(5);
  }
  client.send_action(99);
  const Served s = served.get();
  ASSERT_TRUE(s.refusal.empty()) << s.refusal;
  EXPECT_EQ(s.result.steps(), 4u);
}

TEST(Session, StiffnessIsAnsweredColumnMajorAndDampingAndMassAreZero) {
  InProcessSite site(test::site_study(1, ""), "reference");
  auto served = site.serve();
  test::GenericClient client(site.port(), 2);
  client.send_sizes();
  const double k = test::specimen_stiffness();
  for (int action : {12, 13}) {
    const auto m = client.ask(action);
    EXPECT_EQ(m[0], k);
    EXPECT_EQ(m[1], -k);
    EXPECT_EQ(m[2], -k);
    EXPECT_EQ(m[3], k);
    EXPECT_EQ(m[4], 0.0);
  }
  for (int action : {14, 15})
    for (double x : client.ask(action)) EXPECT_EQ(x, 0.0);
  client.send_action(99);
  EXPECT_TRUE(served.get().refusal.empty());
}

// A refused session: the client's frames, then what the server said.
std::string refusal_after(const std::function<void(test::GenericClient&)>& frames,
                          std::chrono::milliseconds frame_timeout = std::chrono::seconds(5)) {
  InProcessSite site(test::site_study(1, ""), "reference");
  auto served = site.serve(frame_timeout);
  test::GenericClient client(site.port(), 2);
  client.send_sizes();
  try {
    frames(client);
  } catch (const std::runtime_error&) {
    // The server refused a frame and closed before the answer the client waited for.
  }
  const Served s = served.get();
  EXPECT_TRUE(client.closed_by_server(2000) || !s.refusal.empty());
  return s.refusal;
}

TEST(Session, AnImplicitIterationIsRefusedWithTheReason) {
  const std::string why = refusal_after([](test::GenericClient& c) {
    c.set_trial({0, 1e-3}, {0, 0}, {0, 0}, 0.001);
    c.ask(13);
    c.ask(10);
    c.set_trial({0, 1.1e-3}, {0, 0}, {0, 0}, 0.001);  // Newton's next iteration
    c.send_action(10);
  });
  EXPECT_NE(why.find("new displacement inside step 1"), std::string::npos) << why;
  EXPECT_NE(why.find("cannot take a displacement back"), std::string::npos) << why;
}

TEST(Session, NaNTrialIsRefusedNamingTheSlot) {
  const std::string why = refusal_after([](test::GenericClient& c) {
    c.set_trial({0, std::nan("")}, {0, 0}, {0, 0}, 0.001);
  });
  EXPECT_NE(why.find("slot 2 (disp of basic DOF 2)"), std::string::npos) << why;
}

TEST(Session, UnknownActionIsRefused) {
  const std::string why = refusal_after([](test::GenericClient& c) { c.send_action(7); });
  EXPECT_NE(why.find("unknown action code 7"), std::string::npos) << why;
}

TEST(Session, TruncatedFrameIsRefused) {
  const std::string why = refusal_after([](test::GenericClient& c) {
    std::vector<double> half(100, 0.0);
    half[0] = 10;
    c.send_bytes(half.data(), half.size() * sizeof(double));
    c.close();
  });
  EXPECT_NE(why.find("truncated frame: 800 of 2048 bytes"), std::string::npos) << why;
}

TEST(Session, ASilentClientIsStoppedNotWaitedFor) {
  const auto start = std::chrono::steady_clock::now();
  const std::string why = refusal_after(
      [](test::GenericClient& c) {
        c.set_trial({0, 1e-3}, {0, 0}, {0, 0}, 0.001);
        c.ask(10);
      },
      std::chrono::milliseconds(300));
  EXPECT_NE(why.find("sent nothing for 0.3"), std::string::npos) << why;
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
}

// A one-second motion at 1 ms: 1000 samples, so OpenSees' `analyze 1000 0.001` is the longest
// analysis it serves; a step past it is refused, and the client reads the close.
TEST(Session, AStepPastTheAnalysisAsLongAsTheMotionIsRefused) {
  bool client_saw_the_close = false;
  const std::string why = refusal_after([&](test::GenericClient& c) {
    for (int k = 1; k <= 1001; ++k) {
      c.set_trial({0, 1e-6 * k}, {0, 0}, {0, 0}, 0.001 * k);
      try {
        c.ask(10);
      } catch (const std::runtime_error&) {
        client_saw_the_close = k == 1001;
        throw;
      }
      c.send_action(5);
    }
  });
  EXPECT_TRUE(client_saw_the_close);
  EXPECT_NE(why.find("step 1001 is beyond the study's motion"), std::string::npos) << why;
}

TEST(Session, ADieInsideAnOpenStepIsRefused) {
  const std::string why = refusal_after([](test::GenericClient& c) {
    c.set_trial({0, 1e-3}, {0, 0}, {0, 0}, 0.001);
    c.ask(10);
    c.send_action(99);  // no commitState (5) first
  });
  EXPECT_NE(why.find("(DIE) inside step 1, before committing it"), std::string::npos) << why;
}

TEST(Session, AClientTimeStepOtherThanTheStudysIsRefused) {
  const std::string why = refusal_after([](test::GenericClient& c) {
    for (int k = 1; k <= 2; ++k) {
      c.set_trial({0, 1e-4 * k}, {0, 0}, {0, 0}, 0.002 * k);
      c.ask(10);
      c.send_action(5);
    }
  });
  EXPECT_NE(why.find("the study's dt is 0.001"), std::string::npos) << why;
}

TEST(Session, ASecondClientIsRefusedWhileTheFirstIsServed) {
  InProcessSite site(test::site_study(1, ""), "reference");
  auto served = site.serve();
  test::GenericClient first(site.port(), 2);
  first.send_sizes();
  first.set_trial({0, 1e-3}, {0, 0}, {0, 0}, 0.001);
  first.ask(10);
  test::GenericClient second(site.port(), 2);
  second.send_sizes();
  first.send_action(5);
  first.set_trial({0, 2e-3}, {0, 0}, {0, 0}, 0.002);
  first.ask(10);  // the server polls the listener while it waits for this frame
  EXPECT_TRUE(second.closed_by_server(3000));
  first.send_action(5);  // commitState, then the element's end, as OpenSees ends an analysis
  first.send_action(99);
  EXPECT_TRUE(served.get().refusal.empty());
}

}  // namespace
}  // namespace rths::opensees
