#include "analysis/sweep/sweep_grid.h"

#include <fmt/format.h>
#include <google/protobuf/text_format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "analysis/sweep/sweep_internal.h"
#include "core/integrators.h"
#include "core/substructure.h"
#include "study/study.h"

namespace rths::analysis {
namespace {

using sweep_internal::format_number;
using sweep_internal::parse_index;

[[noreturn]] void fail(const std::string& source, const std::string& message) {
  throw std::invalid_argument(source + ": " + message);
}

std::uint64_t fnv1a(std::uint64_t hash, const void* data, std::size_t size) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= bytes[i];
    hash *= 1099511628211ULL;
  }
  return hash;
}

// Names go into CSV cells: no commas, quotes or blanks.
std::string cell_safe(std::string text) {
  for (char& c : text) {
    if (c == ',' || c == '"' || c == ' ' || c == '\t' || c == '\n' || c == '\r') c = '_';
  }
  return text;
}

std::string model_name(const config::RestoringForce& model) {
  std::ostringstream name;
  name.precision(6);
  switch (model.kind_case()) {
    case config::RestoringForce::kBilinear:
      name << "bilinear:uy=" << model.bilinear().yield_displacement()
           << ":b=" << model.bilinear().post_yield_ratio();
      break;
    case config::RestoringForce::kBoucWen:
      name << "bouc-wen:uy=" << model.bouc_wen().yield_displacement()
           << ":alpha=" << model.bouc_wen().alpha() << ":n=" << model.bouc_wen().n();
      break;
    default: name << "linear";
  }
  return cell_safe(name.str());
}

// The sweep's motions, or the study's own motion when the sweep lists none.
std::vector<config::GroundMotion> motion_configs_of(const config::Study& study,
                                                    const std::string& source) {
  const config::Sweep& sweep = study.sweep();
  std::vector<config::GroundMotion> motion_configs(sweep.motions().begin(), sweep.motions().end());
  if (motion_configs.empty()) {
    if (study.motion().path().empty())
      fail(source, "sweep.motions is empty and motion.path is not set");
    motion_configs.push_back(study.motion());
  }
  return motion_configs;
}

// Each model must build a storey; the names label the CSV rows.
std::vector<std::string> checked_model_names(const std::vector<config::RestoringForce>& models,
                                             const std::string& source) {
  std::vector<std::string> names;
  for (std::size_t m = 0; m < models.size(); ++m) {
    try {
      (void)study::make_storey_factory(models[m]);
    } catch (const std::invalid_argument& e) {
      fail(source, "sweep.models[" + std::to_string(m) + "]: " + e.what());
    }
    names.push_back(model_name(models[m]));
  }
  return names;
}

void check_integrator(core::IntegratorKind kind, const std::vector<double>& delays,
                      const std::vector<double>& alphas, const std::string& source) {
  const bool any_delay = std::any_of(delays.begin(), delays.end(), [](double d) { return d > 0; });
  const bool any_experimental =
      std::any_of(alphas.begin(), alphas.end(), [](double a) { return a > 0; });
  if (!core::is_explicit(kind) && any_delay && any_experimental) {
    fail(source, "integrator " + core::to_string(kind) +
                     " cannot run a delayed experimental part; use an explicit integrator");
  }
}

// The study's text without its output section: where results go does not change them.
std::uint64_t definition_hash(const config::Study& study) {
  std::uint64_t hash = 14695981039346656037ULL;
  config::Study defining = study;
  defining.clear_output();
  std::string text;
  google::protobuf::TextFormat::PrintToString(defining, &text);
  return fnv1a(hash, text.data(), text.size());
}

core::GroundMotion load_sweep_motion(const config::GroundMotion& motion,
                                     const std::filesystem::path& base_dir, std::size_t m,
                                     const std::string& source) {
  try {
    return study::load_motion(motion, base_dir);
  } catch (const std::exception& e) {
    fail(source, "sweep motion " + std::to_string(m) + " ('" + motion.path() + "'): " + e.what());
  }
}

std::string motion_label(const config::GroundMotion& motion) {
  std::string name = std::filesystem::path(motion.path()).stem().string();
  const double scale = motion.scale();
  if (scale > 0 && scale != 1.0) name += "_x" + format_number(scale);
  return cell_safe(name);
}

// The record at each grid dt (its own dt for 0), each checked for the integrator's stability at
// the shortest period; every step and record feeds the grid's hash.
std::vector<core::GroundMotion> motion_at_dts(const core::GroundMotion& record,
                                              const std::vector<double>& dts,
                                              core::IntegratorKind kind, double shortest_period,
                                              bool allow_unstable, const std::string& source,
                                              std::uint64_t& hash) {
  std::vector<core::GroundMotion> at_dts;
  for (double dt : dts) {
    const double step = dt > 0 ? dt : record.dt;
    core::GroundMotion motion =
        std::abs(step - record.dt) <= 1e-12 * step ? record : core::resampled(record, step);
    try {
      core::check_stability(kind, 2.0 * std::numbers::pi / shortest_period, step, allow_unstable);
    } catch (const std::invalid_argument& e) {
      fail(source, "sweep: the shortest period " + format_number(shortest_period) + " s at dt " +
                       format_number(step) + " s: " + e.what());
    }
    hash = fnv1a(hash, &step, sizeof step);
    hash = fnv1a(hash, motion.acceleration.data(), motion.acceleration.size() * sizeof(double));
    at_dts.push_back(std::move(motion));
  }
  return at_dts;
}

}  // namespace

// --- shards ------------------------------------------------------------------------------------
std::string Shard::to_string() const { return std::to_string(index) + "/" + std::to_string(count); }

Shard parse_shard(const std::string& text) {
  const std::size_t slash = text.find('/');
  const std::string what = "--shard '" + text + "'";
  if (slash == std::string::npos) throw std::invalid_argument(what + ": expected i/N, e.g. 0/4");
  Shard shard;
  shard.index = parse_index(text.substr(0, slash), what);
  shard.count = parse_index(text.substr(slash + 1), what);
  if (shard.count == 0 || shard.index >= shard.count) {
    throw std::invalid_argument(what + ": needs 0 <= i < N (slices are numbered from 0)");
  }
  return shard;
}

// --- the grid ----------------------------------------------------------------------------------
SweepGrid::SweepGrid(const config::Study& study, const std::filesystem::path& base_dir,
                     const std::string& source)
    : study_(study), base_dir_(base_dir) {
  study::validate_study(study, source);
  const config::Sweep& sweep = study.sweep();
  if (!study.structure().has_sdof()) {
    fail(source, "sweep needs structure.sdof (the sweep varies an SDOF system's period)");
  }
  const config::Sdof& sdof = study.structure().sdof();

  periods_.assign(sweep.periods().begin(), sweep.periods().end());
  if (periods_.empty() && sdof.period() > 0) periods_.push_back(sdof.period());
  if (periods_.empty()) fail(source, "sweep.periods is empty and structure.sdof.period is not set");

  delays_.assign(sweep.delays().begin(), sweep.delays().end());
  if (delays_.empty()) fail(source, "sweep.delays is empty: give at least one delay in s");

  alphas_.assign(sweep.experimental_fractions().begin(), sweep.experimental_fractions().end());
  if (alphas_.empty()) {
    const double alpha = study.substructuring().experimental_fraction();
    alphas_.push_back(alpha > 0 ? alpha : 1.0);
  }

  stiffnesses_.assign(sweep.stiffnesses().begin(), sweep.stiffnesses().end());
  if (stiffnesses_.empty()) stiffnesses_.push_back(sdof.stiffness());  // 0: mass-based

  dts_.assign(sweep.dts().begin(), sweep.dts().end());
  if (dts_.empty()) dts_.push_back(study.integrator().dt());  // 0: each record's own dt

  const std::vector<config::GroundMotion> motion_configs = motion_configs_of(study, source);

  models_.assign(sweep.models().begin(), sweep.models().end());
  if (models_.empty()) models_.push_back(study.substructuring().model());
  model_names_ = checked_model_names(models_, source);

  delay_model_ = sweep.delay_model();

  const core::IntegratorKind kind = study::integrator_kind(study.integrator());
  check_integrator(kind, delays_, alphas_, source);

  std::uint64_t hash = definition_hash(study);
  const double shortest_period = *std::min_element(periods_.begin(), periods_.end());
  for (std::size_t m = 0; m < motion_configs.size(); ++m) {
    const core::GroundMotion record = load_sweep_motion(motion_configs[m], base_dir, m, source);
    motion_names_.push_back(motion_label(motion_configs[m]));
    motions_.push_back(motion_at_dts(record, dts_, kind, shortest_period,
                                     study.integrator().allow_unstable(), source, hash));
  }
  hash_ = hash;
}

std::size_t SweepGrid::size() const {
  return motions_.size() * dts_.size() * models_.size() * stiffnesses_.size() * periods_.size() *
         alphas_.size() * delays_.size();
}

SweepPoint SweepGrid::point(std::size_t index) const {
  if (index >= size())
    throw std::out_of_range("sweep index " + std::to_string(index) + " beyond the grid");
  SweepPoint p;
  p.index = index;
  std::size_t rest = index;
  const auto take = [&rest](std::size_t radix) {
    const std::size_t digit = rest % radix;
    rest /= radix;
    return digit;
  };
  const double delay = delays_[take(delays_.size())];
  const double alpha = alphas_[take(alphas_.size())];
  const double period = periods_[take(periods_.size())];
  const double stiffness = stiffnesses_[take(stiffnesses_.size())];
  p.model = take(models_.size());
  const std::size_t dt_index = take(dts_.size());
  p.motion = rest;
  p.delay = delay;
  p.alpha = alpha;
  p.period = period;
  p.stiffness = stiffness;
  p.dt = motions_[p.motion][dt_index].dt;
  return p;
}

std::pair<std::size_t, std::size_t> SweepGrid::shard_range(const Shard& shard) const {
  const std::size_t total = size();
  // 128-bit free: total * index fits when total < 2^40 and count < 2^24, far beyond any sweep.
  return {total * shard.index / shard.count, total * (shard.index + 1) / shard.count};
}

std::string SweepGrid::hash_hex() const { return fmt::format("{:016x}", hash_); }

const core::GroundMotion& SweepGrid::motion_at(std::size_t motion, std::size_t dt_index) const {
  return motions_.at(motion).at(dt_index);
}

}  // namespace rths::analysis
