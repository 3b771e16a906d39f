#pragma once
// Shared by the runtime tests: small studies written as config text, and helpers to run them.

#include <unistd.h>
#include <filesystem>
#include <sstream>
#include <string>

#include "study/study.h"

namespace rths::test {

inline std::string motion_path() {
  return std::string(RTHS_DATA_DIR) + "/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2";
}

// Two storeys, bilinear storeys, storey 2 experimental, the 1979 record truncated.
// `cases` and `deployment` are config text appended as is.
inline const char* kStorey2Bilinear =
    "substructuring { experimental_storeys: [2] model { bilinear { yield_displacement: 0.004 "
    "post_yield_ratio: 0.1 } } }";
inline std::string two_storey_study(double duration, const std::string& cases,
                                    const std::string& deployment,
                                    const std::string& substructuring = kStorey2Bilinear) {
  return "name: \"two_storey\"\n"
         "structure { shear_building { storey_mass: [2000, 1500] storey_stiffness: [3.0e6, "
         "2.0e6] } damping { modal_zeta: 0.05 } }\n"
         "motion { path: \"" +
         motion_path() + "\" duration: " + std::to_string(duration) +
         " scale: 2 }\n"
         "integrator { kind: EXPLICIT_NEWMARK dt: 0.002 }\n" +
         substructuring + "\n" + cases + "\n" + deployment;
}

// The paper's frame (configs/paper_frame.textproto) truncated to `duration` seconds.
inline std::string paper_frame_study(double duration, const std::string& deployment) {
  return "name: \"paper_frame\"\n"
         "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }\n"
         "motion { path: \"" +
         motion_path() + "\" duration: " + std::to_string(duration) +
         " }\n"
         "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
         "substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }\n"
         "cases { name: \"reference\" }\n"
         "cases { name: \"lag_shift_14ms\" delay { shift { delay: 0.014 } } }\n"
         "cases { name: \"jitter\" delay { jitter { mean_delay: 0.01 std_dev: 0.003 seed: 5 } } "
         "}\n" +
         deployment;
}

// `storeys` storeys of 1e5 kg and `stiffness` N/m each, 5 % Rayleigh damping on modes 1 and 2,
// storey 1 experimental, `duration` s of the 1979 record at 2 ms, one reference case: a model
// past study::kAllDofsLimit, whose record keeps only its recorders' DOFs.
inline std::string uniform_storeys_study(int storeys, double stiffness, double duration) {
  std::ostringstream masses, stiffnesses;
  for (int i = 0; i < storeys; ++i) {
    masses << (i ? ", " : "") << "1e5";
    stiffnesses << (i ? ", " : "") << stiffness;
  }
  return "name: \"storeys" + std::to_string(storeys) +
         "\"\n"
         "structure { shear_building { storey_mass: [" +
         masses.str() + "] storey_stiffness: [" + stiffnesses.str() +
         "] } damping { rayleigh { zeta: 0.05 mode_i: 1 mode_j: 2 } } }\n"
         "motion { path: \"" +
         motion_path() + "\" duration: " + std::to_string(duration) +
         " }\n"
         "integrator { kind: EXPLICIT_NEWMARK dt: 0.002 }\n"
         "substructuring { experimental_storeys: [1] }\n"
         "cases { name: \"reference\" }\n";
}

inline study::PreparedStudy prepare(const std::string& text) {
  return study::prepare_study(study::parse_study(text, "test"),
                              std::filesystem::temp_directory_path());
}

}  // namespace rths::test

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <thread>

#include "core/simulation.h"
#include "runtime/launch/launch.h"
#include "runtime/node/plan.h"
#include "runtime/record/record.h"
#include "util/process.h"

namespace rths::test {

// A fresh directory for one test's files.
inline std::filesystem::path scratch_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("rths_runtime_" + name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::filesystem::path write_config(const std::filesystem::path& dir,
                                          const std::string& text) {
  const auto path = dir / "study.textproto";
  std::ofstream(path) << text;
  return path;
}

inline std::filesystem::path program(const std::string& name, const std::string& subdir) {
  return std::filesystem::path(RTHS_BINARY_DIR) / subdir / name;
}

inline std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The in-process reference of one case.
inline core::SimulationResult reference_result(const std::string& text,
                                               const std::string& case_name) {
  const study::PreparedStudy prepared = prepare(text);
  return core::simulate(
      study::setup_for_case(prepared, study::find_case(prepared.config, case_name)),
      prepared.motion);
}

// Every recorded step equals the reference row exactly (the doubles went over the wire as bits).
inline void expect_record_equals(const runtime::RecordContents& record,
                                 const core::SimulationResult& reference) {
  const auto steps = record.steps();
  ASSERT_EQ(steps.size(), reference.steps());
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const runtime::StepRecord& s = *steps[k];
    const auto row = static_cast<Eigen::Index>(k);
    ASSERT_EQ(s.step(), static_cast<std::int64_t>(k));
    for (int i = 0; i < reference.displacement.cols(); ++i) {
      ASSERT_EQ(s.displacement(i), reference.displacement(row, i)) << "step " << k;
      ASSERT_EQ(s.velocity(i), reference.velocity(row, i)) << "step " << k;
      ASSERT_EQ(s.acceleration(i), reference.acceleration(row, i)) << "step " << k;
    }
    for (int a = 0; a < reference.command.cols(); ++a) {
      ASSERT_EQ(s.command(a), reference.command(row, a)) << "step " << k;
      ASSERT_EQ(s.realised(a), reference.realised(row, a)) << "step " << k;
      ASSERT_EQ(s.measured_force(a), reference.measured_force(row, a)) << "step " << k;
    }
  }
}

// Polls the live record at `record` (a run still writing it) until it holds `steps` intact steps;
// false when `timeout` passes first. A record's size is no measure of its steps: the header and
// the inputs (the motion) may land in separate writes, and the inputs outgrow hundreds of steps.
inline bool wait_for_steps(const std::filesystem::path& record, std::size_t steps,
                           std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    try {
      if (runtime::read_record(record).steps().size() >= steps) return true;
    } catch (const std::exception&) {
      // not yet created, or not yet past its preamble
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

struct LaunchedRun {
  runtime::LaunchResult launch;
  runtime::RecordContents record;
  std::filesystem::path dir;
};

inline LaunchedRun launch(const std::string& name, const std::string& text,
                          const std::string& case_name, int domain, double timeout = 60) {
  LaunchedRun run;
  run.dir = scratch_dir(name);
  runtime::LaunchOptions options;
  options.config = write_config(run.dir, text);
  options.case_name = case_name;
  options.run_id = name;
  options.domain = domain;
  options.programs_dir = RTHS_BINARY_DIR;
  options.record = run.dir / "run.rthsrec";
  options.log_dir = run.dir;
  options.timeout = timeout;
  // Tests judge behaviour, not this machine: no platform measurement, and it is recorded so.
  options.platform_seconds = 0;
  options.accept_platform = true;
  run.launch = runtime::launch_run(options);
  run.record = runtime::read_record(options.record);
  return run;
}

}  // namespace rths::test
