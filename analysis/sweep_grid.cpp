#include "analysis/sweep_grid.h"

#include <google/protobuf/text_format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "analysis/sweep_internal.h"
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
  core::validate_study(study, source);
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

  std::vector<config::GroundMotion> motion_configs(sweep.motions().begin(), sweep.motions().end());
  if (motion_configs.empty()) {
    if (study.motion().path().empty())
      fail(source, "sweep.motions is empty and motion.path is not set");
    motion_configs.push_back(study.motion());
  }

  models_.assign(sweep.models().begin(), sweep.models().end());
  if (models_.empty()) models_.push_back(study.substructuring().model());
  for (std::size_t m = 0; m < models_.size(); ++m) {
    try {
      (void)core::make_storey_factory(models_[m]);
    } catch (const std::invalid_argument& e) {
      fail(source, "sweep.models[" + std::to_string(m) + "]: " + e.what());
    }
    model_names_.push_back(model_name(models_[m]));
  }

  delay_model_ = sweep.delay_model();

  const core::IntegratorKind kind = core::integrator_kind(study.integrator());
  const bool any_delay =
      std::any_of(delays_.begin(), delays_.end(), [](double d) { return d > 0; });
  const bool any_experimental =
      std::any_of(alphas_.begin(), alphas_.end(), [](double a) { return a > 0; });
  if (!core::is_explicit(kind) && any_delay && any_experimental) {
    fail(source, "integrator " + core::to_string(kind) +
                     " cannot run a delayed experimental part; use an explicit integrator");
  }

  std::uint64_t hash = 14695981039346656037ULL;
  config::Study defining = study;
  defining.clear_output();  // where results go does not change them
  std::string text;
  google::protobuf::TextFormat::PrintToString(defining, &text);
  hash = fnv1a(hash, text.data(), text.size());

  const double shortest_period = *std::min_element(periods_.begin(), periods_.end());
  for (std::size_t m = 0; m < motion_configs.size(); ++m) {
    core::GroundMotion record;
    try {
      record = core::load_motion(motion_configs[m], base_dir);
    } catch (const std::exception& e) {
      fail(source, "sweep motion " + std::to_string(m) + " ('" + motion_configs[m].path() +
                       "'): " + e.what());
    }
    std::string name = std::filesystem::path(motion_configs[m].path()).stem().string();
    const double scale = motion_configs[m].scale();
    if (scale > 0 && scale != 1.0) name += "_x" + format_number(scale);
    motion_names_.push_back(cell_safe(name));
    std::vector<core::GroundMotion> at_dts;
    for (double dt : dts_) {
      const double step = dt > 0 ? dt : record.dt;
      core::GroundMotion motion =
          std::abs(step - record.dt) <= 1e-12 * step ? record : core::resampled(record, step);
      try {
        core::check_stability(kind, 2.0 * std::numbers::pi / shortest_period, step,
                              study.integrator().allow_unstable());
      } catch (const std::invalid_argument& e) {
        fail(source, "sweep: the shortest period " + format_number(shortest_period) + " s at dt " +
                         format_number(step) + " s: " + e.what());
      }
      hash = fnv1a(hash, &step, sizeof step);
      hash = fnv1a(hash, motion.acceleration.data(), motion.acceleration.size() * sizeof(double));
      at_dts.push_back(std::move(motion));
    }
    motions_.push_back(std::move(at_dts));
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

std::string SweepGrid::hash_hex() const {
  char buffer[20];
  std::snprintf(buffer, sizeof buffer, "%016llx", static_cast<unsigned long long>(hash_));
  return buffer;
}

const core::GroundMotion& SweepGrid::motion_at(std::size_t motion, std::size_t dt_index) const {
  return motions_.at(motion).at(dt_index);
}

}  // namespace rths::analysis
