#pragma once
// Study configs: reading the Protobuf text format with errors that name file, line, column and
// field, and turning a config into core blocks (motion at dt, hybrid setup per case).
// Relative paths inside a config resolve against the config file's folder.

#include <filesystem>
#include <string>

#include "core/delay.h"
#include "core/ground_motion.h"
#include "core/simulation.h"
#include "core/substructure.h"
#include "rths/proto/config.pb.h"

namespace rths::core {

// Parses a text-format Study. Throws std::invalid_argument "FILE:LINE:COL: message" on unknown
// fields, wrong types or syntax errors, and on semantic errors (negative period or delay, both
// experimental_fraction and experimental_storeys, ...) naming the field.
config::Study load_study(const std::filesystem::path& path);
config::Study parse_study(const std::string& text, const std::string& source_name);

// Checks the semantic rules above; throws std::invalid_argument naming the field.
void validate_study(const config::Study& study, const std::string& source_name);

GroundMotion load_motion(const config::GroundMotion& motion, const std::filesystem::path& base_dir);

std::unique_ptr<DelayStage> make_delay_stage(const config::DelayStage& stage, double dt,
                                             const std::filesystem::path& base_dir);
DelayChain make_delay_chain(const google::protobuf::RepeatedPtrField<config::DelayStage>& stages,
                            double dt, const std::filesystem::path& base_dir);

StoreyModelFactory make_storey_factory(const config::RestoringForce& model);
StructuralModel make_structure(const config::Structure& structure);
IntegratorKind integrator_kind(const config::Integrator& integrator);

// A study made ready to run: the motion resampled to the step, the structure and the partition.
struct PreparedStudy {
  config::Study config;
  std::filesystem::path base_dir;
  GroundMotion motion;  // at dt
  HybridSetup base;     // no delay stages
};
PreparedStudy prepare_study(const config::Study& study, const std::filesystem::path& base_dir);

// The base setup with the case's delay stages on every actuator.
HybridSetup setup_for_case(const PreparedStudy& prepared, const config::Case& study_case);

// The case named `reference_case`, else the first. Throws if there are none.
const config::Case& reference_case(const config::Study& study);

}  // namespace rths::core
