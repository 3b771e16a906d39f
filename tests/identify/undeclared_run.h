#pragma once
// Records of rths's own distributed runs with an effect the run's config does not declare, for the
// identification tests: coordinator + node services in one process (tests/support), the actuator
// emulator carrying extra stages, then the record's header given the declared config, as a lab's
// record holds the config it meant to run.

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <string>

#include "identify/run/run_record.h"
#include "runtime/record/record.h"
#include "study/study_inputs.h"
#include "tests/runtime/test_support.h"
#include "tests/support/in_process_run.h"
#include "util/crc32c.h"

namespace rths::test {

inline const std::string kDeclared =
    "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR } }";

inline std::filesystem::path scratch(const std::string& name) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_run_record_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  return dir / (name + ".rthsrec");
}

// Every entry of `record` written again, with `edit` applied to each first; each header then
// names the (edited) inputs entry by its CRC-32C, as the coordinator's headers do, so the record
// stays one whose header and inputs agree.
template <class Edit>
void rewrite(const std::filesystem::path& record, Edit edit) {
  runtime::RecordContents contents = runtime::read_record(record);
  std::uint32_t inputs_crc32c = 0;
  for (auto& entry : contents.entries) {
    edit(entry);
    if (entry.has_inputs() && inputs_crc32c == 0)
      inputs_crc32c = util::crc32c(entry.SerializeAsString());
  }
  runtime::RecordWriter writer(record);
  for (auto& entry : contents.entries) {
    if (entry.has_header() && inputs_crc32c != 0)
      entry.mutable_header()->set_inputs_crc32c(inputs_crc32c);
    writer.write(entry);
  }
}

// A run of study `actual` (config text), case `case_name`, whose record's header and inputs are
// then given the study `declared`, as a lab's record holds the config it meant to run;
// `expect_ok` = false for a run meant to fail (e.g. diverge).
inline std::filesystem::path record_declaring(const std::string& name, const std::string& actual,
                                              const std::string& declared_text,
                                              const std::string& case_name, bool expect_ok) {
  coordinator::CoordinatorOptions options;
  options.run_id = name;
  options.case_name = case_name;
  options.record = scratch(name);
  const auto outcome = coordinator::run_in_process(prepare(actual), options);
  EXPECT_EQ(outcome.ok, expect_ok) << outcome.status;
  const study::PreparedStudy declared = prepare(declared_text);
  rewrite(options.record, [&](runtime::RecordEntry& e) {
    if (e.has_header()) *e.mutable_header()->mutable_study() = declared.config;
    if (e.has_inputs())
      *e.mutable_inputs()->mutable_study() = study::with_embedded_inputs(declared);
  });
  return options.record;
}

// A `duration` s paper-frame run of case `case_name` whose actuator emulator carries
// `emulator_stages` (config text of DelayStage fields) that the declared config lacks.
inline std::filesystem::path run_with_undeclared(const std::string& name,
                                                 const std::string& emulator_stages,
                                                 const std::string& case_name = "lag_shift_14ms",
                                                 double duration = 10.0, bool expect_ok = true) {
  const std::string actual =
      paper_frame_study(duration,
                        "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: "
                        "ACTUATOR_EMULATOR " +
                            emulator_stages + " } }");
  return record_declaring(name, actual, paper_frame_study(duration, kDeclared), case_name,
                          expect_ok);
}

// The paper frame, damped 20 %, driven by a ground motion whose band ends below 3 Hz: three
// sines under a 1 s cosine ramp at each end for 6 s, then 4 s at rest (10 s at the integrator's
// 1 ms, embedded in the study). A specimen moved by it has no acceleration above the band, which
// the force model's acceleration (central differences of the displacement smoothed over 5 ms,
// signals.h) would smooth away, and the record ends at rest: the force model's zero-phase
// filters start their backward pass at the record's last sample as at rest, so a record that
// ends moving reads a transient acceleration there that no mass explains.
inline std::string smooth_frame_study(const std::string& deployment) {
  std::string study = test::paper_frame_study(10.0, deployment);
  const std::size_t from = study.find("motion {");
  const std::size_t to = study.find("}\n", from) + 2;
  std::string motion = "motion { embedded { name: \"three_sines\" dt: 0.001 acceleration: [";
  constexpr double kPi = 3.14159265358979323846;
  for (int i = 0; i < 10000; ++i) {
    const double t = 0.001 * i;
    const double ramp = std::clamp(std::min(t, 6.0 - t), 0.0, 1.0);
    const double envelope = 0.5 - 0.5 * std::cos(kPi * ramp);
    const double a = std::sin(2 * kPi * 1.3 * t) + 0.6 * std::sin(2 * kPi * 2.1 * t + 1.0) +
                     0.4 * std::sin(2 * kPi * 0.7 * t + 2.0);
    motion += (i ? ", " : "") + std::to_string(3.0 * envelope * a);
  }
  study.replace(from, to - from, motion + "] } }\n");
  const std::string damping = "modal_zeta: 0.05";
  study.replace(study.find(damping), damping.size(), "modal_zeta: 0.2");
  return study;
}

// `study` (paper_frame_study or smooth_frame_study) whose case lag_shift_14ms carries `stage`
// (DelayStage fields) behind its shift, where it acts on the specimen's motion.
inline std::string behind_the_shift(std::string study, const std::string& stage) {
  const std::string shift = "delay { shift { delay: 0.014 } }";
  study.insert(study.find(shift) + shift.size(), " delay { " + stage + " }");
  return study;
}

// The effects identified on the link to node `node`.
inline std::set<std::string> link_effects(const identify::RunIdentification& run, int node) {
  std::set<std::string> out;
  for (const auto& l : run.links) {
    if (l.node_id != node) continue;
    for (const auto& e : l.effects) out.insert(e.name);
  }
  return out;
}

}  // namespace rths::test
