// DDS Security on real processes over Cyclone DDS on loopback (domains 170-179): only the lab's
// participants deliver anything, permissions bind each node kind to its own topics, and bad
// documents stop a program at start-up with exit 2, naming the file and the reason.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <regex>

#include "../runtime/test_support.h"
#include "runtime/launch/launch.h"
#include "runtime/record/record.h"
#include "security/check.h"
#include "support.h"
#include "util/process.h"

namespace rths {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using util::ChildProcess;

fs::path binary(const std::string& subdir, const std::string& name) {
  return fs::path(RTHS_BINARY_DIR) / subdir / name;
}

struct Probe {
  util::ChildProcess process;
  fs::path log;
};

// A dds_probe (tests/security/dds_probe.cpp) in `domain`; security off when `node_dir` is empty.
Probe probe(const fs::path& logs, const std::string& label, const std::string& mode, int domain,
            const std::string& role, int node_id, const fs::path& node_dir, double seconds,
            int identity = -1, int peer = 1) {
  std::vector<std::string> args{mode,
                                "--domain",
                                std::to_string(domain),
                                "--prefix",
                                "sec" + std::to_string(domain),
                                "--as",
                                role,
                                "--node-id",
                                std::to_string(node_id),
                                "--seconds",
                                std::to_string(seconds),
                                "--peer",
                                std::to_string(peer)};
  if (!node_dir.empty()) args.insert(args.end(), {"--security", node_dir.string()});
  if (identity >= 0) args.insert(args.end(), {"--identity", std::to_string(identity)});
  const fs::path log = logs / (label + ".log");
  return {util::ChildProcess(binary("tests/security", "rths_dds_probe"), args, log), log};
}

long count_in(const fs::path& log, const std::string& word) {
  std::smatch match;
  const std::string text = test::slurp(log);
  if (!std::regex_search(text, match, std::regex(word + " ([0-9]+)"))) return -1;
  return std::stol(match[1]);
}

class DdsSecurity : public ::testing::Test {
 protected:
  void SetUp() override {
    runtime::ensure_dds_config();
    lab_ = test::make_lab(::testing::UnitTest::GetInstance()->current_test_info()->name());
    logs_ = lab_ / "logs";
    fs::create_directories(logs_);
  }
  void TearDown() override {  // logs are kept when the test failed
    if (!HasFailure()) fs::remove_all(lab_);
  }
  fs::path lab_, logs_;
};

// Three domains side by side: the lab's own node (control: it must deliver), a participant with
// no security at all, and one whose certificate and documents come from another lab's CA. The
// receiver in each is the lab's coordinator.
TEST_F(DdsSecurity, OnlyTheLabsParticipantsDeliverAnyMessage) {
  const fs::path stranger = test::make_lab("outsider_lab");
  constexpr double kListen = 9.0, kSend = 7.0;
  const fs::path coordinator = security::node_dir(lab_, 0);
  Probe own_rx = probe(logs_, "own_rx", "receive", 170, "coordinator", 0, coordinator, kListen);
  Probe plain_rx = probe(logs_, "plain_rx", "receive", 171, "coordinator", 0, coordinator, kListen);
  Probe alien_rx = probe(logs_, "alien_rx", "receive", 172, "coordinator", 0, coordinator, kListen);
  Probe own_tx = probe(logs_, "own_tx", "send", 170, "node", 1, security::node_dir(lab_, 1), kSend);
  Probe plain_tx = probe(logs_, "plain_tx", "send", 171, "node", 1, "", kSend);
  Probe alien_tx =
      probe(logs_, "alien_tx", "send", 172, "node", 1, security::node_dir(stranger, 1), kSend);
  for (Probe* p : {&own_tx, &plain_tx, &alien_tx, &own_rx, &plain_rx, &alien_rx})
    EXPECT_EQ(p->process.wait(), 0) << test::slurp(p->log);
  // Every sender really sent; only the lab's own was delivered.
  for (Probe* p : {&own_tx, &plain_tx, &alien_tx}) EXPECT_GT(count_in(p->log, "sent"), 500);
  EXPECT_GT(count_in(own_rx.log, "received"), 100) << "control: the lab's node must get through";
  EXPECT_EQ(count_in(plain_rx.log, "received"), 0);
  EXPECT_EQ(count_in(alien_rx.log, "received"), 0);
}

// Node 1's permissions allow publishing on its own up topic only. With its own valid identity in
// the coordinator's role (our start-up check passes: the folder is node 1's), DDS access control
// refuses the command writer (*_down) and the node listening for commands receives nothing. The
// coordinator's identity, in the next domain, is the control. Without --identity, our own check
// refuses the same folder first, naming the certificate.
TEST_F(DdsSecurity, ANodeCannotPublishOnTheCommandTopic) {
  const fs::path node1 = security::node_dir(lab_, 1), node2 = security::node_dir(lab_, 2);
  Probe rx = probe(logs_, "rx", "receive", 173, "node", 2, node2, 7.0);
  Probe control_rx = probe(logs_, "control_rx", "receive", 174, "node", 2, node2, 7.0);
  Probe forger = probe(logs_, "forger", "send", 173, "coordinator", 0, node1, 5.0, 1, 2);
  Probe control = probe(logs_, "control", "send", 174, "coordinator", 0,
                        security::node_dir(lab_, 0), 5.0, -1, 2);
  Probe unchecked = probe(logs_, "unchecked", "send", 173, "coordinator", 0, node1, 5.0, -1, 2);
  EXPECT_EQ(forger.process.wait(), 3);
  // Refused at its first entity outside node 1's own topics (its listener's node-2 topic or the
  // command writer).
  EXPECT_THAT(test::slurp(forger.log), AllOf(HasSubstr("dds_create_"), HasSubstr("Security")));
  EXPECT_EQ(unchecked.process.wait(), 2);
  EXPECT_THAT(test::slurp(unchecked.log),
              AllOf(HasSubstr("cert.pem"), HasSubstr("is for rths-node-1, not for node 0")));
  EXPECT_EQ(control.process.wait(), 0) << test::slurp(control.log);
  EXPECT_EQ(rx.process.wait(), 0);
  EXPECT_EQ(control_rx.process.wait(), 0);
  EXPECT_EQ(count_in(rx.log, "received"), 0);
  EXPECT_GT(count_in(control_rx.log, "received"), 100);
}

// Identity bound to node: an insider holding node 2's certificate (valid, of this lab) tries to
// answer as node 1 on node 1's topic. Node 2's permissions allow only its own two topics, so DDS
// refuses the writer and the coordinator listening to node 1 receives nothing; node 1's own
// certificate, in the next domain, is the control.
TEST_F(DdsSecurity, ANodesCertificateCannotPublishAsAnotherNode) {
  const fs::path node0 = security::node_dir(lab_, 0);
  Probe rx = probe(logs_, "rx", "receive", 87, "coordinator", 0, node0, 7.0, -1, 1);
  Probe control_rx = probe(logs_, "control_rx", "receive", 88, "coordinator", 0, node0, 7.0, -1, 1);
  Probe insider =
      probe(logs_, "insider", "send", 87, "node", 1, security::node_dir(lab_, 2), 5.0, 2);
  Probe own = probe(logs_, "own", "send", 88, "node", 1, security::node_dir(lab_, 1), 5.0);
  EXPECT_EQ(insider.process.wait(), 3);
  EXPECT_THAT(test::slurp(insider.log), AllOf(HasSubstr("dds_create_"), HasSubstr("Security")));
  EXPECT_EQ(own.process.wait(), 0) << test::slurp(own.log);
  EXPECT_EQ(rx.process.wait(), 0);
  EXPECT_EQ(control_rx.process.wait(), 0);
  EXPECT_EQ(count_in(rx.log, "received"), 0);
  EXPECT_GT(count_in(control_rx.log, "received"), 100);
}

// The node programs check their folder before DDS starts: exit 2, naming the file and the reason.
TEST_F(DdsSecurity, NodeProgramsRefuseBadCertificatesAtStartUp) {
  const auto run = [&](const std::string& label, const fs::path& program, int node_id,
                       const fs::path& folder) {
    util::ChildProcess node(program,
                            {"--node-id", std::to_string(node_id), "--domain", "176",
                             "--assign-timeout", "3", "--security", folder.string()},
                            logs_ / (label + ".log"));
    const int code = node.wait();  // before the log is read
    return std::make_pair(code, test::slurp(logs_ / (label + ".log")));
  };
  const fs::path emulator = binary("actuator_emulator", "rths-actuator-emulator");
  const fs::path substructure = binary("substructure_nodes", "rths-substructure-node");
  security::issue_node(lab_, {2, "actuator_emulator"}, "rths-lab",
                       {std::chrono::seconds(-7 * 86400), std::chrono::seconds(-3600)});
  const auto [expired_code, expired] = run("expired", emulator, 2, security::node_dir(lab_, 2));
  EXPECT_EQ(expired_code, 2);
  EXPECT_THAT(expired, AllOf(HasSubstr((security::node_dir(lab_, 2) / "cert.pem").string()),
                             HasSubstr("certificate has expired")));
  const auto [other_code, other] = run("other", substructure, 1, security::node_dir(lab_, 0));
  EXPECT_EQ(other_code, 2);
  EXPECT_THAT(other, HasSubstr("is for rths-node-0, not for node 1"));
  const fs::path stranger = test::make_lab("stranger_for_programs");
  fs::copy_file(security::node_dir(stranger, 1) / "cert.pem",
                security::node_dir(lab_, 1) / "cert.pem", fs::copy_options::overwrite_existing);
  const auto [unsigned_code, unsigned_text] =
      run("unsigned", substructure, 1, security::node_dir(lab_, 1));
  EXPECT_EQ(unsigned_code, 2);
  EXPECT_THAT(unsigned_text, AllOf(HasSubstr("cert.pem"), HasSubstr("not signed by the lab CA")));
}

// A malformed governance document (well signed, broken XML) stops the coordinator at start-up:
// exit 2 naming the file, no record opened, nothing sent -- not a run without security.
TEST_F(DdsSecurity, CoordinatorRefusesAMalformedGovernanceBeforeSendingAnything) {
  test::sign_with_openssl(lab_, "<dds><domain_access_rules><domain_rule><domains>",
                          security::node_dir(lab_, 0) / "governance.p7s");
  const fs::path config = test::write_config(
      lab_, test::paper_frame_study(
                0.2, "deployment { domain_id: 176 security_dir: \"" + lab_.string() + "\" }"));
  util::ChildProcess coordinator(
      binary("coordinator", "rths-coordinator"),
      {"--config", config.string(), "--record", (lab_ / "run.rthsrec").string()},
      logs_ / "coordinator.log");
  EXPECT_EQ(coordinator.wait(), 2);
  EXPECT_THAT(test::slurp(logs_ / "coordinator.log"),
              AllOf(HasSubstr("governance.p7s"), HasSubstr("not well-formed XML")));
  EXPECT_FALSE(fs::exists(lab_ / "run.rthsrec"));
}

// `rths launch` with security on: every process authenticates and the lockstep run still equals
// the in-process simulation bit for bit.
TEST_F(DdsSecurity, LaunchedSecuredLockstepRunEqualsInProcess) {
  const std::string text = test::paper_frame_study(
      0.3, "deployment { domain_id: 177 security_dir: \"" + lab_.string() + "\" }");
  runtime::LaunchOptions options;
  options.config = test::write_config(lab_, text);
  options.case_name = "lag_shift_14ms";
  options.run_id = "secured";
  options.programs_dir = RTHS_BINARY_DIR;
  options.record = lab_ / "run.rthsrec";
  options.log_dir = logs_;
  options.timeout = 120;
  const runtime::LaunchResult result = runtime::launch_run(options);
  ASSERT_EQ(result.coordinator_exit, 0) << test::slurp(result.coordinator_log);
  for (const int code : result.node_exits) EXPECT_EQ(code, 0);
  EXPECT_THAT(test::slurp(logs_ / "node_2.log"), ::testing::Not(HasSubstr("rror")));
  test::expect_record_equals(runtime::read_record(options.record),
                             test::reference_result(text, "lag_shift_14ms"));
}

// A bad folder stops `rths launch` before any process starts.
TEST_F(DdsSecurity, LaunchRefusesBadDocumentsBeforeStartingAnyProcess) {
  fs::remove(security::node_dir(lab_, 2) / "permissions.p7s");
  runtime::LaunchOptions options;
  options.config =
      test::write_config(lab_, test::paper_frame_study(0.2, "deployment { domain_id: 177 }"));
  options.security_dir = lab_;
  options.programs_dir = RTHS_BINARY_DIR;
  options.record = lab_ / "run.rthsrec";
  options.log_dir = logs_ / "launch";
  try {
    runtime::launch_run(options);
    ADD_FAILURE() << "launched with a missing permissions document";
  } catch (const security::SecurityError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("node_2/permissions.p7s"), HasSubstr("missing")));
  }
  EXPECT_FALSE(fs::exists(options.log_dir / "coordinator.log"));
}

}  // namespace
}  // namespace rths
