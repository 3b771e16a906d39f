#include "runtime/node/controller_link.h"

#include <google/protobuf/text_format.h>
#include <gtest/gtest.h>

#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "runtime/node/plan.h"
#include "test_support.h"

namespace rths::runtime {
namespace {

// The shipped controller study's block: the docs' example of a lab's link.
config::Study shipped_controller_study() {
  std::ifstream in(std::string(RTHS_SOURCE_DIR) + "/configs/paper_frame_controller.textproto");
  std::stringstream text;
  text << in.rdbuf();
  config::Study study;
  EXPECT_TRUE(google::protobuf::TextFormat::ParseFromString(text.str(), &study));
  return study;
}

config::ControllerLink shipped_link() {
  return shipped_controller_study().deployment().nodes(0).controller();
}

std::string error_of(const config::ControllerLink& link, const config::Deployment& deployment = {},
                     double dt = 0.001) {
  try {
    check_controller_link(link, answer_window(deployment, dt), 1, "deployment.nodes[id 2]");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(ControllerLink, TheShippedLinkPasses) { EXPECT_EQ(error_of(shipped_link()), ""); }

TEST(ControllerLink, EachBadFieldIsNamedWithTheNode) {
  struct Case {
    std::string what;
    void (*spoil)(config::ControllerLink&);
    std::string named;
  };
  const Case cases[] = {
      {"address", [](config::ControllerLink& l) { l.set_peer_address("localhost"); },
       "controller.peer_address 'localhost' is not an IPv4 address"},
      {"port", [](config::ControllerLink& l) { l.set_local_port(0); },
       "controller.local_port 0 is not in [1, 65535]"},
      {"hold", [](config::ControllerLink& l) { l.set_hold_time_ms(70000); },
       "controller.hold_time_ms must be in [0, 60000]"},
      {"force", [](config::ControllerLink& l) { l.set_max_force(-1); },
       "controller.max_force must be finite and >= 0"},
      {"steps", [](config::ControllerLink& l) { l.set_tracking_error_steps(-2); },
       "controller.tracking_error_steps must be >= 0"},
      {"counter",
       [](config::ControllerLink& l) { l.mutable_feedback()->mutable_fields()->Clear(); },
       "controller.feedback: no COUNTER field"},
      {"size",
       [](config::ControllerLink& l) {
         for (int i = 0; i < 300; ++i) {
           auto* f = l.mutable_command()->add_fields();
           f->set_role(config::FrameField::PADDING);
           f->set_type(config::FrameField::F64);
         }
       },
       "bytes (at most 2048)"},
  };
  for (const Case& c : cases) {
    config::ControllerLink link = shipped_link();
    c.spoil(link);
    const std::string error = error_of(link);
    EXPECT_EQ(error.rfind("deployment.nodes[id 2]: ", 0), 0u) << c.what << ": " << error;
    EXPECT_NE(error.find(c.named), std::string::npos) << c.what << ": " << error;
  }
}

TEST(ControllerLink, AReplyTimeoutPastTheAnswerWindowIsRefusedAndTheDefaultsResolve) {
  config::Deployment real_time;
  real_time.set_clock(config::Deployment::REAL_TIME);
  real_time.set_answer_window_ms(20);
  config::ControllerLink link = shipped_link();  // reply_timeout_ms 500
  EXPECT_NE(error_of(link, real_time).find("is longer than the answer window"), std::string::npos);
  link.set_reply_timeout_ms(0);
  EXPECT_EQ(error_of(link, real_time), "");
  // Half the 20-step window at dt = 1 ms; lockstep: 1 s; the hold: 500 ms.
  EXPECT_DOUBLE_EQ(controller_reply_timeout(link, answer_window(real_time, 0.001)), 0.010);
  EXPECT_DOUBLE_EQ(controller_reply_timeout(link, answer_window(config::Deployment{}, 0.001)), 1.0);
  EXPECT_DOUBLE_EQ(controller_hold_time(link), 0.5);
}

// A jump floor that is not a number is refused (< 0 turns the check off: controller_checks_text
// in plan_test.cpp).
TEST(ControllerLink, AJumpFloorThatIsNotANumberIsRefused) {
  config::ControllerLink link = shipped_link();
  link.set_jump_floor(std::numeric_limits<double>::quiet_NaN());
  EXPECT_NE(error_of(link).find("controller.jump_floor must be finite"), std::string::npos);
  link.set_jump_floor(-1);
  EXPECT_EQ(error_of(link), "");
}

// The one check every command runs: the deployment's plan refuses the block, naming the node.
TEST(ControllerLink, CheckDeploymentNamesTheNodeAndTheField) {
  config::Study study = shipped_controller_study();
  const std::string configs = std::string(RTHS_SOURCE_DIR) + "/configs";
  const study::PreparedStudy good = study::prepare_study(study, configs);
  EXPECT_NO_THROW(check_deployment(good));
  study.mutable_deployment()->mutable_nodes(0)->mutable_controller()->set_peer_port(70000);
  const study::PreparedStudy bad = study::prepare_study(study, configs);
  try {
    check_deployment(bad);
    FAIL() << "a peer port of 70000 passed";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "deployment.nodes[id 2]: controller.peer_port 70000 is not in [1, 65535]");
  }
}

}  // namespace
}  // namespace rths::runtime
