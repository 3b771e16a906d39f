#include "study/study_inputs.h"

#include "study/delay_trace_file.h"
#include "study/sparse_triplets.h"
#include "study/structure_io.h"
#include "util/sha256.h"

#include <vector>

namespace rths::study {

namespace {

std::string absolute_path(const std::filesystem::path& base_dir, const std::string& path) {
  return std::filesystem::absolute(base_dir / path).lexically_normal().string();
}

void embed_matrix(config::Matrix& matrix, const std::filesystem::path& base_dir,
                  const std::string& field) {
  if (matrix.file().empty()) return;
  const MatrixData read = read_matrix_data(matrix, base_dir, field);
  matrix.Clear();
  if (read.sparse_held) {
    *matrix.mutable_sparse() = write_sparse_triplets(read.sparse);
    return;
  }
  const core::Mat& values = read.dense;
  matrix.set_rows(static_cast<int>(values.rows()));
  for (Eigen::Index i = 0; i < values.rows(); ++i)
    for (Eigen::Index j = 0; j < values.cols(); ++j) matrix.add_values(values(i, j));
}

void embed_matrices(config::MatrixStructure& matrices, const std::filesystem::path& base_dir) {
  const std::string field = "structure.matrices";
  if (matrices.has_mass()) embed_matrix(*matrices.mutable_mass(), base_dir, field + ".mass");
  if (matrices.has_stiffness())
    embed_matrix(*matrices.mutable_stiffness(), base_dir, field + ".stiffness");
  if (matrices.has_damping())
    embed_matrix(*matrices.mutable_damping(), base_dir, field + ".damping");
  if (matrices.has_influence())
    embed_matrix(*matrices.mutable_influence(), base_dir, field + ".influence");
}

void embed_traces(google::protobuf::RepeatedPtrField<config::DelayStage>& stages,
                  const std::filesystem::path& base_dir) {
  for (config::DelayStage& stage : stages) {
    if (!stage.has_trace() || stage.trace().time_size() > 0) continue;
    config::DelayStage::Trace& trace = *stage.mutable_trace();
    trace.set_path(absolute_path(base_dir, trace.path()));
    const core::DelayTrace samples = read_delay_trace(trace.path());
    trace.mutable_time()->Add(samples.time.begin(), samples.time.end());
    trace.mutable_delay()->Add(samples.delay.begin(), samples.delay.end());
  }
}

void embed_motion(config::GroundMotion& motion, const core::GroundMotion& as_run,
                  const std::filesystem::path& base_dir) {
  if (motion.has_embedded()) return;
  config::EmbeddedMotion& embedded = *motion.mutable_embedded();
  embedded.set_name(as_run.name);
  embedded.set_dt(as_run.dt);
  embedded.mutable_acceleration()->Add(as_run.acceleration.begin(), as_run.acceleration.end());
  if (motion.path().empty()) return;
  motion.set_path(absolute_path(base_dir, motion.path()));
  embedded.set_source_sha256(util::file_sha256(motion.path()));
}

}  // namespace

config::Study with_embedded_inputs(const PreparedStudy& prepared) {
  config::Study study = prepared.config;
  embed_motion(*study.mutable_motion(), prepared.motion, prepared.base_dir);
  if (study.structure().has_matrices())
    embed_matrices(*study.mutable_structure()->mutable_matrices(), prepared.base_dir);
  for (config::Case& c : *study.mutable_cases())
    embed_traces(*c.mutable_delay(), prepared.base_dir);
  for (config::NodeSpec& node : *study.mutable_deployment()->mutable_nodes()) {
    embed_traces(*node.mutable_receive_delay(), prepared.base_dir);
    embed_traces(*node.mutable_send_delay(), prepared.base_dir);
  }
  return study;
}

std::string inputs_source(const config::Study& study, const std::filesystem::path& base_dir) {
  if (study.motion().has_embedded()) return "embedded in the record";
  std::vector<std::string> files;
  if (!study.motion().path().empty())
    files.push_back(absolute_path(base_dir, study.motion().path()));
  if (study.structure().has_matrices()) {
    const auto& m = study.structure().matrices();
    for (const config::Matrix* matrix : {&m.mass(), &m.stiffness(), &m.damping(), &m.influence()})
      if (!matrix->file().empty()) files.push_back(absolute_path(base_dir, matrix->file()));
  }
  std::string text = "files the study names (the record is older than embedded inputs):";
  for (const std::string& file : files) text += " " + file;
  return text;
}

}  // namespace rths::study
