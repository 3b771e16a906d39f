// rths pki init DIR: a lab's DDS Security PKI (security/pki.h): the lab CA, one identity per node,
// signed governance and per-node permissions. Nodes come from a study's deployment (--config;
// its default nodes when it declares none) and/or --node ID:KIND; the coordinator (node 0) is
// always included. Exit 2 for bad options, an existing CA in DIR or a bad config; 3 when files
// cannot be written.
// rths pki secret FILE: a run secret (security/run_secret.h) for processes started by hand,
// written to a new file of mode 0600 (an existing file is refused, exit 3); the secret itself is
// never printed.
#include <iostream>

#include "cli/commands.h"
#include "cli/support.h"
#include "runtime/node/plan.h"
#include "security/pki.h"
#include "security/run_secret.h"
#include "study/study.h"

namespace rths::cli {
namespace {

struct PkiArgs {
  std::string dir, config, case_name, organisation = "rths-lab";
  std::vector<std::string> nodes;
  int days = 365;
};

security::NodeIdentity parse_node(const std::string& text) {
  const auto colon = text.find(':');
  std::size_t used = 0;
  int id = -1;
  try {
    id = std::stoi(text.substr(0, colon), &used);
  } catch (const std::exception&) {
    used = std::string::npos;
  }
  if (colon == std::string::npos || used != colon)
    throw std::invalid_argument("--node '" + text +
                                "': expected ID:KIND, e.g. 2:actuator_emulator");
  security::NodeIdentity node{id, text.substr(colon + 1)};
  security::check_identity(node);
  return node;
}

std::vector<security::NodeIdentity> study_nodes(const std::string& config,
                                                const std::string& case_name) {
  const config::Study study = study::load_study(config);
  const config::Case& study_case =
      study::find_case(study, case_name.empty() ? study.deployment().case_name() : case_name);
  // Which nodes a study has depends on its partition, not on dt (0 = the record's, unread here).
  const double dt = study.integrator().dt() > 0 ? study.integrator().dt() : 0.01;
  const core::HybridSetup setup = runtime::setup_without_motion(
      study, std::filesystem::path(config).parent_path(), dt, study_case);
  std::vector<security::NodeIdentity> nodes;
  const config::Deployment deployment = runtime::with_default_nodes(study.deployment(), setup);
  for (const config::NodeSpec& node : deployment.nodes())
    nodes.push_back({node.id(), node.kind() == config::NodeSpec::SUBSTRUCTURE ? "substructure"
                                : node.kind() == config::NodeSpec::CONTROLLER
                                    ? "controller"
                                    : "actuator_emulator"});
  return nodes;
}

void run_pki_init(const PkiArgs& args) {
  security::PkiOptions options;
  options.organisation = args.organisation;
  options.days = args.days;
  if (!args.config.empty()) options.nodes = study_nodes(args.config, args.case_name);
  for (const std::string& text : args.nodes) options.nodes.push_back(parse_node(text));
  if (options.nodes.empty())
    throw std::invalid_argument("pki init: no nodes; give --config STUDY or --node ID:KIND");
  try {
    security::init_pki(args.dir, options);
  } catch (const std::invalid_argument&) {
    throw;
  } catch (const std::exception& e) {
    throw ExitError(kExitEnvironment, std::string("pki init: ") + e.what());
  }
  const std::filesystem::path dir(args.dir);
  std::cout << "lab CA: " << (dir / "ca" / "ca_cert.pem").string() << " (its key "
            << (dir / "ca" / "ca_key.pem").string() << " stays in the lab)\n";
  std::cout << "node 0 (coordinator): " << security::node_dir(dir, 0).string() << "\n";
  for (const security::NodeIdentity& node : options.nodes)
    if (node.node_id != security::kCoordinatorNodeId)
      std::cout << "node " << node.node_id << " (" << node.kind
                << "): " << security::node_dir(dir, node.node_id).string() << "\n";
  std::cout << "hand each site only its node_<id> folder; run with --security " << args.dir
            << " (rths launch / sites) or set deployment.security_dir\n";
}

void run_pki_secret(const std::string& file) {
  try {
    security::write_run_secret_file(file, security::generate_run_secret());
  } catch (const std::exception& e) {
    throw ExitError(kExitEnvironment, std::string("pki secret: ") + e.what());
  }
  std::cout << "run secret written to " << file
            << " (mode 0600); give every process of the run --secret-file " << file
            << " (or RTHS_RUN_SECRET_FILE), by a channel only the lab reads\n";
}

}  // namespace

void add_pki_command(CLI::App& app) {
  auto* pki = app.add_subcommand("pki", "DDS Security: the lab's certificates and documents");
  pki->require_subcommand(1);
  auto* init = pki->add_subcommand(
      "init", "Make a lab CA, one identity per node and signed governance and permissions");
  auto args = std::make_shared<PkiArgs>();
  init->add_option("dir", args->dir, "new folder for the PKI")->required();
  init->add_option("--config", args->config, "study whose deployment names the nodes");
  init->add_option("--case", args->case_name, "case whose default nodes are used (with --config)");
  init->add_option("--node", args->nodes,
                   "ID:KIND (substructure | actuator_emulator | controller), repeatable");
  init->add_option("--days", args->days,
                   "validity of certificates and grants in days (default 365)")
      ->check(in_range(study::Quantity::kDays));
  init->add_option("--organisation", args->organisation, "O= of every subject (default rths-lab)");
  init->callback([args] { run_pki_init(*args); });
  auto* secret = pki->add_subcommand(
      "secret", "Make a run secret for processes started by hand (without DDS Security)");
  auto file = std::make_shared<std::string>();
  secret->add_option("file", *file, "new file (mode 0600) for the secret")->required();
  secret->callback([file] { run_pki_secret(*file); });
}

}  // namespace rths::cli
