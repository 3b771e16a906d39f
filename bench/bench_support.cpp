#include "bench/bench_support.h"

#include <chrono>
#include <cstdio>
#include <fstream>

#include "security/run_secret.h"
#include "study/study.h"

namespace rths::bench {

std::string imperial_valley_path() {
  return std::string(RTHS_DATA_DIR) + "/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2";
}

std::string imperial_valley_motion(double seconds) {
  return "motion { path: \"" + imperial_valley_path() + "\" duration: " + std::to_string(seconds) +
         " }\n";
}

std::string sdof_study_text(const std::string& name, double dt, const std::string& motion,
                            const std::string& deployment) {
  char dt_text[32];
  std::snprintf(dt_text, sizeof dt_text, "%.17g", dt);  // exact: 1/1024 is not 0.000977
  return "name: \"" + name +
         "\"\n"
         "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }\n" +
         motion + "integrator { kind: EXPLICIT_NEWMARK dt: " + dt_text +
         " }\n"
         "substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }\n"
         "cases { name: \"lag\" delay { shift { delay: 0.014 } } }\n" +
         deployment;
}

namespace {

std::vector<std::string> node_arguments(int id, int domain, const std::string& run_id,
                                        bool run_secret) {
  std::vector<std::string> args{
      "--node-id", std::to_string(id), "--domain", std::to_string(domain), "--run-id", run_id};
  if (!run_secret) args.emplace_back("--insecure");
  return args;
}

}  // namespace

DistributedRun::DistributedRun(const RunSpec& spec)
    : dir_(std::filesystem::temp_directory_path() / spec.directory),
      record_(dir_ / "run.rthsrec"),
      run_id_(spec.run_id),
      secret_(spec.run_secret ? security::generate_run_secret() : ""),
      domain_(spec.domain) {
  std::filesystem::create_directories(dir_);
  const auto config = dir_ / "study.textproto";
  std::ofstream(config) << spec.study_text;
  study_ = study::load_study(config);
  if (spec.keep_off_loop_cpu) off_loop_cpu_ = runtime::keep_off_loop_cpu(study_.deployment());
  // Measured as deployed: every message carries its MAC under the run's secret.
  util::ChildOptions trusted;
  if (spec.run_secret) trusted.environment = {{security::kSecretEnv, secret_}};
  const int count = spec.nodes.substructures + spec.nodes.emulators;
  for (int i = 0; i < count; ++i) {
    const bool substructure = i < spec.nodes.substructures;
    const int id = spec.nodes.substructures == 0 ? 2 + i : i + 1;
    nodes_.emplace_back(std::filesystem::path(RTHS_BINARY_DIR) /
                            (substructure ? "substructure_nodes/rths-substructure-node"
                                          : "actuator_emulator/rths-actuator-emulator"),
                        node_arguments(id, domain_, run_id_, spec.run_secret),
                        dir_ / ("node_" + std::to_string(id) + ".log"), trusted);
  }
}

study::PreparedStudy DistributedRun::prepared() const { return study::prepare_study(study_, dir_); }

coordinator::Coordinator& DistributedRun::start(coordinator::CoordinatorOptions options) {
  endpoint_ = std::make_unique<transport::DdsEndpoint>(transport::DdsEndpointOptions{
      static_cast<std::uint32_t>(domain_), true, 0, "rths", 64, {}, secret_});
  // As rths-coordinator does: the transport's drops for want of a MAC reach the footer.
  options.unauthenticated = [endpoint = endpoint_.get()] { return endpoint->unauthenticated(); };
  options.run_id = run_id_;
  options.record = record_;
  coordinator_ = std::make_unique<coordinator::Coordinator>(study::prepare_study(study_, dir_),
                                                            *endpoint_, options);
  return *coordinator_;
}

void DistributedRun::wait_for_nodes() {
  using namespace std::chrono_literals;
  for (auto& n : nodes_) n.wait_for(5000ms);
}

}  // namespace rths::bench
