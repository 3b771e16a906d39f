#include "cli/config_kind.h"

#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>

#include "rths/analysis/joint_lag.pb.h"
#include "rths/proto/config.pb.h"
#include "study/text_format.h"
#if __has_include("rths/deploy/sites.pb.h")
#include "rths/deploy/sites.pb.h"
#define RTHS_CLI_HAS_DEPLOY 1
#endif

namespace rths::cli {
namespace {

class SilentErrors : public google::protobuf::io::ErrorCollector {
 public:
  void AddError(int, google::protobuf::io::ColumnNumber, const std::string&) override {}
};

bool parses_as(const std::string& text, google::protobuf::Message& message) {
  SilentErrors errors;
  google::protobuf::TextFormat::Parser parser;
  parser.RecordErrorsTo(&errors);
  return parser.ParseFromString(text, &message);
}

}  // namespace

std::string config_kind_of(const std::filesystem::path& path) {
  std::string text;
  try {
    text = study::read_text_file(path, "config");
  } catch (const std::invalid_argument&) {
    return "";
  }
  config::Study study;
  if (parses_as(text, study)) return "study (rths.config.Study)";
  analysis::JointLagStudy joint;
  if (parses_as(text, joint)) return "joint-lag study (rths.analysis.JointLagStudy)";
#ifdef RTHS_CLI_HAS_DEPLOY
  deploy::Sites sites;
  if (parses_as(text, sites)) return "sites (rths.deploy.Sites)";
#endif
  return "";
}

void rethrow_with_config_kind(const std::filesystem::path& path, const std::string& expected_kind,
                              const std::invalid_argument& error) {
  const std::string kind = config_kind_of(path);
  if (kind.empty() || kind.rfind(expected_kind, 0) == 0) return;
  std::string command = "run";
  if (kind.rfind("joint-lag", 0) == 0) command = "joint-lag";
  if (kind.rfind("sites", 0) == 0) command = "sites";
  throw std::invalid_argument(path.string() + " is a " + kind + " config, not a " + expected_kind +
                              " config: try `rths " + command + " " + path.string() + "` (" +
                              error.what() + ")");
}

}  // namespace rths::cli
