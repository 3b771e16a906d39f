#include "analysis/sweep.h"

#include <google/protobuf/text_format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "analysis/atomic_file.h"
#include "analysis/batch_kernel.h"
#include "analysis/compare.h"
#include "analysis/parallel_for.h"
#include "analysis/plot.h"
#include "core/integrators.h"
#include "core/metrics.h"
#include "core/simulation.h"
#include "core/stability.h"
#include "core/study.h"
#include "core/substructure.h"

namespace rths::analysis {
namespace {

constexpr const char* kCsvHeader =
    "index,period_s,delay_s,alpha,stiffness_N_per_m,dt_s,motion,model,peak_ref_m,peak_delayed_m,"
    "eq2_paper,nrmse_pct,peak_error_m,diverged";
constexpr const char* kSidecarFormat = "rths-sweep";
constexpr std::size_t kPeriodsPerFastItem = 16;
constexpr double kInf = std::numeric_limits<double>::infinity();

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

std::string format_number(double x) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", x);
  return buffer;
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

bool is_linear(const config::RestoringForce& model) {
  return model.kind_case() == config::RestoringForce::kLinear ||
         model.kind_case() == config::RestoringForce::KIND_NOT_SET;
}

std::vector<double> column0(const core::SimulationResult& result) {
  std::vector<double> u(static_cast<std::size_t>(result.displacement.rows()));
  for (std::size_t i = 0; i < u.size(); ++i) u[i] = result.displacement(static_cast<Eigen::Index>(i), 0);
  return u;
}

// Error measures of one point from the two displacement histories (analysis::compare). A diverged
// point keeps its peaks; its error measures are inf (they measure nothing once it has grown).
void fill_metrics(SweepRow& row, const std::vector<double>& reference, bool reference_diverged,
                  const std::vector<double>& delayed, bool delayed_diverged) {
  const Comparison c = compare(reference, delayed, delayed_diverged);
  row.diverged = reference_diverged || c.diverged;
  row.peak_reference = reference_diverged ? kInf : c.peak_reference_m;
  row.peak_delayed = delayed_diverged ? kInf : c.peak_m;
  if (row.diverged) {
    row.eq2_paper = row.nrmse_pct = row.peak_error = kInf;
    return;
  }
  row.eq2_paper = c.paper_eq2_as_printed;
  row.nrmse_pct = c.nrmse_pct;
  row.peak_error = c.peak_error_m;
}

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> cells;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    cells.push_back(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) return cells;
    start = comma + 1;
  }
}

std::size_t parse_index(const std::string& text, const std::string& where) {
  std::size_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size()) {
    throw std::invalid_argument(where + ": '" + text + "' is not a whole number");
  }
  return value;
}

double parse_double(const std::string& text, const std::string& where) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size()) {
    throw std::invalid_argument(where + ": '" + text + "' is not a number");
  }
  return value;
}

void write_csv_file(const std::filesystem::path& path, const std::string& grid_hash,
                    std::size_t points, const Shard& shard,
                    const std::vector<std::string>& lines) {
  // The sidecar first: a CSV is never in place without the metadata that says what it holds.
  AtomicFile sidecar(sweep_sidecar_path(path));
  sidecar.stream() << nlohmann::json{{"format", kSidecarFormat},
                                     {"csv", path.filename().string()},
                                     {"grid", grid_hash},
                                     {"points", points},
                                     {"shard", shard.to_string()}}
                          .dump(2)
                   << "\n";
  sidecar.commit();
  AtomicFile file(path);
  std::ofstream& out = file.stream();
  out << kCsvHeader << "\n";
  for (const std::string& line : lines) out << line << "\n";
  file.commit();
}

}  // namespace

std::filesystem::path sweep_sidecar_path(const std::filesystem::path& csv) {
  std::filesystem::path sidecar = csv;
  sidecar.replace_extension(".meta.json");
  return sidecar;
}

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
    if (study.motion().path().empty()) fail(source, "sweep.motions is empty and motion.path is not set");
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
  const bool any_delay = std::any_of(delays_.begin(), delays_.end(), [](double d) { return d > 0; });
  const bool any_experimental = std::any_of(alphas_.begin(), alphas_.end(), [](double a) { return a > 0; });
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
      fail(source, "sweep motion " + std::to_string(m) + " ('" + motion_configs[m].path() + "'): " + e.what());
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
        fail(source, "sweep: the shortest period " + format_number(shortest_period) +
                         " s at dt " + format_number(step) + " s: " + e.what());
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
  if (index >= size()) throw std::out_of_range("sweep index " + std::to_string(index) + " beyond the grid");
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

// --- running -----------------------------------------------------------------------------------
namespace {

struct GroupKey {
  std::size_t motion, dt_index, model, stiffness;
};

// The SDOF structure of one period and stiffness, built by core exactly as `rths run` would.
core::StructuralModel structure_for(const SweepGrid& grid, double period, double stiffness) {
  config::Structure structure = grid.study().structure();
  structure.mutable_sdof()->set_period(period);
  structure.mutable_sdof()->set_stiffness(stiffness);
  return core::make_structure(structure);
}

config::DelayStage stage_for(config::Sweep::DelayModel delay_model, double delay) {
  config::DelayStage stage;
  switch (delay_model) {
    case config::Sweep::EQ1: stage.mutable_eq1()->set_delay(delay); break;
    case config::Sweep::EQ1_LAG: stage.mutable_eq1_lag()->set_delay(delay); break;
    case config::Sweep::FIRST_ORDER: stage.mutable_first_order()->set_time_constant(delay); break;
    default: stage.mutable_shift()->set_delay(delay); break;
  }
  return stage;
}

class SweepRunner {
 public:
  SweepRunner(const SweepGrid& grid, const SweepOptions& options)
      : grid_(grid), options_(options) {
    std::tie(first_, last_) = grid.shard_range(options.shard);
    rows_.resize(last_ - first_);
    per_period_ = grid.alphas().size() * grid.delays().size();
    per_group_ = per_period_ * grid.periods().size();
  }

  std::vector<SweepRow> run() {
    build_items();
    parallel_for(items_.size(), options_.threads, [this](std::size_t i) { run_item(items_[i]); });
    return std::move(rows_);
  }

 private:
  struct Item {
    std::size_t group;
    std::size_t period_begin, period_end;
    bool fast;
  };

  GroupKey group_key(std::size_t group) const {
    std::size_t rest = group;
    GroupKey key{};
    key.stiffness = rest % grid_.stiffnesses().size();
    rest /= grid_.stiffnesses().size();
    key.model = rest % grid_.models().size();
    rest /= grid_.models().size();
    key.dt_index = rest % grid_.dts().size();
    key.motion = rest / grid_.dts().size();
    return key;
  }

  bool in_shard(std::size_t index) const { return index >= first_ && index < last_; }
  std::size_t index_of(std::size_t group, std::size_t period, std::size_t alpha, std::size_t delay) const {
    return group * per_group_ + period * per_period_ + alpha * grid_.delays().size() + delay;
  }

  void build_items() {
    if (first_ == last_) return;
    const std::size_t group_first = first_ / per_group_, group_last = (last_ - 1) / per_group_;
    for (std::size_t g = group_first; g <= group_last; ++g) {
      const std::size_t lo = std::max(first_, g * per_group_) - g * per_group_;
      const std::size_t hi = std::min(last_, (g + 1) * per_group_) - g * per_group_;
      const std::size_t period_begin = lo / per_period_, period_end = (hi - 1) / per_period_ + 1;
      const GroupKey key = group_key(g);
      const bool fast = !options_.general_path_only && is_linear(grid_.models()[key.model]) &&
                        core::integrator_kind(grid_.study().integrator()) ==
                            core::IntegratorKind::kExplicitNewmark &&
                        grid_.delay_model() == config::Sweep::SHIFT;
      const std::size_t step = fast ? kPeriodsPerFastItem : 1;
      for (std::size_t p = period_begin; p < period_end; p += step) {
        items_.push_back({g, p, std::min(period_end, p + step), fast});
      }
    }
  }

  void run_item(const Item& item) {
    const std::size_t done = item.fast ? run_fast(item) : run_general(item);
    if (options_.progress) {
      std::lock_guard<std::mutex> lock(progress_mutex_);
      completed_ += done;
      options_.progress(completed_, rows_.size());
    }
  }

  SweepRow& row_at(std::size_t index) { return rows_[index - first_]; }

  std::size_t run_general(const Item& item) {
    const GroupKey key = group_key(item.group);
    const core::GroundMotion& motion = grid_.motion_at(key.motion, key.dt_index);
    const double stiffness = grid_.stiffnesses()[key.stiffness];
    const core::StoreyModelFactory factory = core::make_storey_factory(grid_.models()[key.model]);
    std::size_t done = 0;
    for (std::size_t p = item.period_begin; p < item.period_end; ++p) {
      core::HybridSetup setup;
      setup.model = structure_for(grid_, grid_.periods()[p], stiffness);
      setup.integrator = core::integrator_kind(grid_.study().integrator());
      setup.dt = motion.dt;
      setup.allow_unstable = grid_.study().integrator().allow_unstable();
      setup.partition = core::partition_by_fraction(setup.model.storey_stiffness, 0.0, factory);
      const core::SimulationResult reference = core::simulate(setup, motion);
      const std::vector<double> reference_u = column0(reference);
      for (std::size_t a = 0; a < grid_.alphas().size(); ++a) {
        for (std::size_t d = 0; d < grid_.delays().size(); ++d) {
          const std::size_t index = index_of(item.group, p, a, d);
          if (!in_shard(index)) continue;
          const double alpha = grid_.alphas()[a], delay = grid_.delays()[d];
          core::HybridSetup delayed = setup;
          delayed.partition = core::partition_by_fraction(setup.model.storey_stiffness, alpha, factory);
          delayed.delays.clear();
          if (delay > 0 && !delayed.partition.actuator_storeys.empty()) {
            const config::DelayStage stage = stage_for(grid_.delay_model(), delay);
            for (std::size_t act = 0; act < delayed.partition.actuator_storeys.size(); ++act) {
              core::DelayChain chain;
              chain.add(core::make_delay_stage(stage, motion.dt, grid_.base_dir()));
              delayed.delays.push_back(std::move(chain));
            }
          }
          const core::SimulationResult result = core::simulate(delayed, motion);
          SweepRow& row = row_at(index);
          row.point = grid_.point(index);
          fill_metrics(row, reference_u, reference.diverged, column0(result), result.diverged);
          ++done;
        }
      }
    }
    return done;
  }

  std::size_t run_fast(const Item& item) {
    const GroupKey key = group_key(item.group);
    const core::GroundMotion& motion = grid_.motion_at(key.motion, key.dt_index);
    const double stiffness = grid_.stiffnesses()[key.stiffness];
    BatchRunOptions batch_options;
    batch_options.threads = 1;  // the items are the parallel grain
    std::vector<core::StructuralModel> models;
    std::vector<SdofLane> reference_lanes;
    for (std::size_t p = item.period_begin; p < item.period_end; ++p) {
      models.push_back(structure_for(grid_, grid_.periods()[p], stiffness));
      const core::StructuralModel& model = models.back();
      // alpha = 0: the whole storey numerical, as core::partition_by_fraction(..., 0, ...).
      reference_lanes.push_back({model.mass(0, 0), model.damping(0, 0), model.storey_stiffness[0], 0.0});
    }
    std::vector<std::vector<double>> reference;
    const std::vector<LaneOutcome> reference_outcome = run_linear_sdof_lanes(
        reference_lanes, motion.acceleration, motion.dt, 0.0, batch_options, &reference);
    std::size_t done = 0;
    for (std::size_t d = 0; d < grid_.delays().size(); ++d) {
      std::vector<SdofLane> lanes;
      std::vector<std::pair<std::size_t, std::size_t>> lane_points;  // (period offset, index)
      for (std::size_t p = item.period_begin; p < item.period_end; ++p) {
        for (std::size_t a = 0; a < grid_.alphas().size(); ++a) {
          const std::size_t index = index_of(item.group, p, a, d);
          if (!in_shard(index)) continue;
          const core::StructuralModel& model = models[p - item.period_begin];
          const double k = model.storey_stiffness[0], alpha = grid_.alphas()[a];
          // The split of core::partition_by_fraction: (1 - alpha) k and alpha k, each present
          // only when non-zero.
          lanes.push_back({model.mass(0, 0), model.damping(0, 0), alpha < 1.0 ? (1.0 - alpha) * k : 0.0,
                           alpha > 0.0 ? alpha * k : 0.0});
          lane_points.emplace_back(p - item.period_begin, index);
        }
      }
      if (lanes.empty()) continue;
      std::vector<std::vector<double>> delayed;
      const std::vector<LaneOutcome> outcome = run_linear_sdof_lanes(
          lanes, motion.acceleration, motion.dt, grid_.delays()[d], batch_options, &delayed);
      for (std::size_t l = 0; l < lanes.size(); ++l) {
        const auto [offset, index] = lane_points[l];
        SweepRow& row = row_at(index);
        row.point = grid_.point(index);
        fill_metrics(row, reference[offset], reference_outcome[offset].diverged, delayed[l],
                     outcome[l].diverged);
        ++done;
      }
    }
    return done;
  }

  const SweepGrid& grid_;
  const SweepOptions& options_;
  std::size_t first_ = 0, last_ = 0, per_period_ = 1, per_group_ = 1;
  std::vector<Item> items_;
  std::vector<SweepRow> rows_;
  std::mutex progress_mutex_;
  std::size_t completed_ = 0;
};

}  // namespace

SweepStabilityCheck check_sweep_stability(const SweepGrid& grid) {
  SweepStabilityCheck out;
  const core::IntegratorKind kind = core::integrator_kind(grid.study().integrator());
  const double zeta = grid.study().structure().damping().modal_zeta();
  for (double period : grid.periods()) {
    const core::StructuralModel model = core::make_sdof(period, zeta, 1.0);
    for (double alpha : grid.alphas()) {
      for (double dt : grid.dts()) {
        for (double delay : grid.delays()) {
          if (!(delay > 0) || !(alpha > 0)) continue;
          const core::CriticalDelayCheck check =
              core::check_critical_delay(model, {alpha * model.stiffness(0, 0)}, kind, dt, delay);
          ++out.combinations;
          if (check.past()) ++out.past;
          if (check.margin() < out.smallest_margin) {
            out.smallest_margin = check.margin();
            std::ostringstream where;
            where << "T = " << period << " s, alpha = " << alpha << ", dt = " << dt * 1e3 << " ms: " << check.describe();
            out.worst = where.str();
          }
        }
      }
    }
  }
  return out;
}

CriticalDelayOf critical_delay_of(const SweepGrid& grid) {
  const core::IntegratorKind kind = core::integrator_kind(grid.study().integrator());
  const double zeta = grid.study().structure().damping().modal_zeta();
  return [kind, zeta](double period, double alpha, double dt) -> std::optional<double> {
    const core::StructuralModel model = core::make_sdof(period, zeta, 1.0);
    // The lag only bounds the discrete search: search far enough to find the limit.
    const auto continuous = core::continuous_critical_delay(period, zeta, alpha).critical_delay;
    const double search = continuous ? 1.5 * *continuous : period;
    return core::check_critical_delay(model, {alpha * model.stiffness(0, 0)}, kind, dt, search).critical();
  };
}

std::vector<SweepRow> run_sweep(const SweepGrid& grid, const SweepOptions& options) {
  if (options.shard.count == 0 || options.shard.index >= options.shard.count) {
    throw std::invalid_argument("sweep shard " + options.shard.to_string() + " is not 0 <= i < N");
  }
  SweepRunner runner(grid, options);
  return runner.run();
}

// --- CSV ---------------------------------------------------------------------------------------
std::vector<SweepTableRow> to_table(const SweepGrid& grid, const std::vector<SweepRow>& rows) {
  std::vector<SweepTableRow> table;
  table.reserve(rows.size());
  for (const SweepRow& row : rows) {
    SweepTableRow t;
    t.index = row.point.index;
    t.period = row.point.period;
    t.delay = row.point.delay;
    t.alpha = row.point.alpha;
    t.stiffness = row.point.stiffness;
    t.dt = row.point.dt;
    t.motion = grid.motion_names()[row.point.motion];
    t.model = grid.model_names()[row.point.model];
    t.peak_reference = row.peak_reference;
    t.peak_delayed = row.peak_delayed;
    t.eq2_paper = row.eq2_paper;
    t.nrmse_pct = row.nrmse_pct;
    t.peak_error = row.peak_error;
    t.diverged = row.diverged;
    table.push_back(std::move(t));
  }
  return table;
}

void write_sweep_csv(const std::filesystem::path& path, const SweepGrid& grid, const Shard& shard,
                     const std::vector<SweepRow>& rows) {
  std::vector<std::string> lines;
  lines.reserve(rows.size());
  for (const SweepTableRow& t : to_table(grid, rows)) {
    std::string line = std::to_string(t.index);
    for (double x : {t.period, t.delay, t.alpha, t.stiffness, t.dt}) line += "," + format_number(x);
    line += "," + t.motion + "," + t.model;
    for (double x : {t.peak_reference, t.peak_delayed, t.eq2_paper, t.nrmse_pct, t.peak_error}) {
      line += "," + format_number(x);
    }
    line += t.diverged ? ",1" : ",0";
    lines.push_back(std::move(line));
  }
  write_csv_file(path, grid.hash_hex(), grid.size(), shard, lines);
}

SweepCsv read_sweep_csv(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path.string() + ": cannot open the sweep CSV");
  SweepCsv csv;
  std::string line;
  const std::string name = path.string();
  const std::filesystem::path sidecar_path = sweep_sidecar_path(path);
  const std::string sidecar_name = sidecar_path.string();
  std::ifstream sidecar_in(sidecar_path);
  if (!sidecar_in) {
    throw std::invalid_argument(name + ": its metadata " + sidecar_name +
                                " is missing (grid, points, shard: written beside every sweep CSV)");
  }
  nlohmann::json sidecar;
  try {
    sidecar = nlohmann::json::parse(sidecar_in);
    if (sidecar.value("format", "") != kSidecarFormat) throw std::invalid_argument("not an rths-sweep sidecar");
    csv.grid_hash = sidecar.at("grid").get<std::string>();
    csv.points = sidecar.at("points").get<std::size_t>();
    csv.shard = parse_shard(sidecar.at("shard").get<std::string>());
  } catch (const std::exception& e) {
    throw std::invalid_argument(sidecar_name + ": not a sweep CSV's metadata (format, grid, points, shard): " +
                                e.what());
  }
  if (csv.grid_hash.empty()) throw std::invalid_argument(sidecar_name + ": empty grid hash");
  if (!std::getline(in, line) || line != kCsvHeader) {
    throw std::invalid_argument(name + ":1: expected the column header '" + std::string(kCsvHeader) + "'");
  }
  csv.header = line;
  std::size_t line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty()) continue;
    const std::string where = name + ":" + std::to_string(line_number);
    const std::size_t comma = line.find(',');
    csv.indices.push_back(parse_index(line.substr(0, comma), where + ": index"));
    if (split_csv(line).size() != split_csv(kCsvHeader).size()) {
      throw std::invalid_argument(where + ": expected " + std::to_string(split_csv(kCsvHeader).size()) +
                                  " columns (a truncated file?)");
    }
    csv.lines.push_back(line);
  }
  return csv;
}

SweepCsv merge_sweep_csvs(const std::vector<std::filesystem::path>& shards,
                          const std::filesystem::path& out) {
  if (shards.empty()) throw std::invalid_argument("merge: no shard CSVs given");
  std::vector<SweepCsv> parts;
  for (const auto& path : shards) parts.push_back(read_sweep_csv(path));
  const SweepCsv& first = parts.front();
  for (std::size_t i = 1; i < parts.size(); ++i) {
    if (parts[i].grid_hash != first.grid_hash || parts[i].points != first.points) {
      throw std::invalid_argument("merge: " + shards[i].string() + " comes from another grid (grid=" +
                                  parts[i].grid_hash + ", " + std::to_string(parts[i].points) +
                                  " points) than " + shards[0].string() + " (grid=" + first.grid_hash +
                                  ", " + std::to_string(first.points) + " points)");
    }
  }
  const std::size_t total = first.points;
  std::vector<int> owner(total, -1);
  std::vector<const std::string*> line_of(total, nullptr);
  for (std::size_t s = 0; s < parts.size(); ++s) {
    for (std::size_t r = 0; r < parts[s].indices.size(); ++r) {
      const std::size_t index = parts[s].indices[r];
      if (index >= total) {
        throw std::invalid_argument("merge: " + shards[s].string() + " holds index " +
                                    std::to_string(index) + " beyond the grid's " +
                                    std::to_string(total) + " points");
      }
      if (owner[index] >= 0) {
        throw std::invalid_argument("merge: point " + std::to_string(index) + " appears twice (in " +
                                    shards[owner[index]].string() + " and " + shards[s].string() +
                                    "); was a shard given twice?");
      }
      owner[index] = static_cast<int>(s);
      line_of[index] = &parts[s].lines[r];
    }
  }
  std::vector<std::size_t> missing;
  for (std::size_t i = 0; i < total; ++i) {
    if (owner[i] < 0) missing.push_back(i);
  }
  if (!missing.empty()) {
    std::string message = "merge: " + std::to_string(missing.size()) + " of " + std::to_string(total) +
                          " points are missing (first index " + std::to_string(missing.front()) +
                          ", last " + std::to_string(missing.back()) + ")";
    const std::size_t count = first.shard.count;
    if (count > 1) {
      std::set<std::size_t> lacking;
      for (std::size_t i : missing) lacking.insert(std::min(count - 1, (i * count + count - 1) / total));
      // Shard s holds [s T / N, (s+1) T / N); name the ones whose points are absent.
      std::string names;
      for (std::size_t s = 0; s < count; ++s) {
        const std::size_t lo = total * s / count, hi = total * (s + 1) / count;
        if (lo < hi && owner[lo] < 0) names += (names.empty() ? "" : ", ") + std::to_string(s) + "/" + std::to_string(count);
      }
      if (!names.empty()) message += "; missing shard(s) " + names;
    }
    throw std::invalid_argument(message);
  }
  SweepCsv merged;
  merged.grid_hash = first.grid_hash;
  merged.points = total;
  merged.shard = Shard{};
  merged.header = kCsvHeader;
  merged.indices.resize(total);
  merged.lines.reserve(total);
  for (std::size_t i = 0; i < total; ++i) {
    merged.indices[i] = i;
    merged.lines.push_back(*line_of[i]);
  }
  write_csv_file(out, merged.grid_hash, total, merged.shard, merged.lines);
  return merged;
}

std::vector<SweepTableRow> parse_sweep_rows(const SweepCsv& csv, const std::string& source) {
  std::vector<SweepTableRow> rows;
  rows.reserve(csv.lines.size());
  for (std::size_t r = 0; r < csv.lines.size(); ++r) {
    const std::vector<std::string> c = split_csv(csv.lines[r]);
    const std::string where = source + " row " + std::to_string(r + 1);
    if (c.size() != 14) throw std::invalid_argument(where + ": expected 14 columns");
    SweepTableRow t;
    t.index = parse_index(c[0], where);
    t.period = parse_double(c[1], where + " period");
    t.delay = parse_double(c[2], where + " delay");
    t.alpha = parse_double(c[3], where + " alpha");
    t.stiffness = parse_double(c[4], where + " stiffness");
    t.dt = parse_double(c[5], where + " dt");
    t.motion = c[6];
    t.model = c[7];
    t.peak_reference = parse_double(c[8], where + " peak_ref");
    t.peak_delayed = parse_double(c[9], where + " peak_delayed");
    t.eq2_paper = parse_double(c[10], where + " eq2_paper");
    t.nrmse_pct = parse_double(c[11], where + " nrmse_pct");
    t.peak_error = parse_double(c[12], where + " peak_error");
    t.diverged = c[13] == "1";
    rows.push_back(std::move(t));
  }
  return rows;
}

// --- plot and trends ---------------------------------------------------------------------------
namespace {

// Series key: everything but period and stiffness.
using SeriesKey = std::tuple<std::string, double, double, std::string, double>;  // model, alpha, dt, motion, delay

SeriesKey series_key(const SweepTableRow& r) { return {r.model, r.alpha, r.dt, r.motion, r.delay}; }

std::string delay_label(double delay) {
  std::ostringstream s;
  s.precision(4);
  s << delay * 1e3 << " ms";
  return s.str();
}

}  // namespace

std::filesystem::path sweep_delay_plot_path(const std::filesystem::path& png) {
  std::filesystem::path out = png;
  out.replace_filename(png.stem().string() + "_vs_delay" + png.extension().string());
  return out;
}

void write_sweep_plot(const std::vector<SweepTableRow>& rows, const std::filesystem::path& png,
                      const std::string& title, const CriticalDelayOf& critical_delay) {
  if (rows.empty()) throw std::invalid_argument("sweep plot: no rows");
  double stiffness = rows.front().stiffness;
  std::set<std::string> models, motions;
  std::set<double> alphas, dts;
  for (const auto& r : rows) {
    stiffness = std::min(stiffness, r.stiffness);
    models.insert(r.model);
    motions.insert(r.motion);
    alphas.insert(r.alpha);
    dts.insert(r.dt);
  }
  struct Point {
    double period, nrmse_pct, eq2;
    bool diverged;
  };
  std::map<SeriesKey, std::vector<Point>> series;
  double largest = 0.0, smallest = std::numeric_limits<double>::infinity();
  for (const auto& r : rows) {
    if (r.stiffness != stiffness || !(r.delay > 0)) continue;
    series[series_key(r)].push_back({r.period, r.nrmse_pct, r.eq2_paper, r.diverged});
    if (!r.diverged && std::isfinite(r.nrmse_pct) && r.nrmse_pct > 0) {
      largest = std::max(largest, r.nrmse_pct);
      smallest = std::min(smallest, r.nrmse_pct);
    }
  }
  const std::string& name = title;
  PlotSpec nrmse_panel{name + ": NRMSE = 100 sqrt(mean e^2) / median|u_ref| (the paper's Fig. 4)",
                       "period T (s)", "NRMSE (%, log)", {}, true};
  PlotSpec eq2_panel{name + ": the paper's Eq. 2 as printed (depends on N)", "period T (s)",
                     "Eq. 2 (log)", {}, true};
  nrmse_panel.height = eq2_panel.height = 500;
  // Diverged points sit on a row above every bounded value, so they are seen but set no scale.
  const double diverged_row = largest > 0 ? largest * 3.0 : 1.0;
  if (largest > 0) {
    nrmse_panel.y_min = smallest / 2.0;
    nrmse_panel.y_max = diverged_row * 2.0;
  }
  Series diverged{"diverged (marked above the curves)", {}, {}, "points pt 2 ps 1.6 lw 2"};
  auto label_of = [&](const SeriesKey& key) {
    const auto& [model, alpha, dt, motion, delay] = key;
    std::string label = delay_label(delay);
    if (models.size() > 1) label += " " + model;
    if (alphas.size() > 1) label += " alpha=" + format_number(alpha);
    if (dts.size() > 1) label += " dt=" + format_number(dt);
    if (motions.size() > 1) label += " " + motion;
    return label;
  };
  for (auto& [key, points] : series) {
    std::sort(points.begin(), points.end(), [](const Point& l, const Point& r) { return l.period < r.period; });
    const std::string label = label_of(key);
    Series a{label, {}, {}, "linespoints"}, b{label, {}, {}, "linespoints"};
    for (const Point& p : points) {
      a.x.push_back(p.period);
      a.y.push_back(p.diverged ? std::nan("") : p.nrmse_pct);
      b.x.push_back(p.period);
      b.y.push_back(p.diverged ? std::nan("") : p.eq2);
      if (p.diverged) {
        diverged.x.push_back(p.period);
        diverged.y.push_back(diverged_row);
      }
    }
    nrmse_panel.series.push_back(std::move(a));
    eq2_panel.series.push_back(std::move(b));
  }
  if (nrmse_panel.series.empty()) throw std::invalid_argument("sweep plot: no delay > 0 in the rows");
  if (!diverged.x.empty()) nrmse_panel.series.push_back(std::move(diverged));
  write_png_panels({nrmse_panel, eq2_panel}, png);

  // Error against delay, one curve per period (at most kPeriodsDrawn, spread over the range), at
  // the first model, fraction, dt and record; the critical delay of each period drawn.
  constexpr std::size_t kPeriodsDrawn = 6;
  std::set<double> periods;
  for (const auto& r : rows) periods.insert(r.period);
  std::vector<double> all(periods.begin(), periods.end()), drawn;
  for (std::size_t i = 0; i < std::min(kPeriodsDrawn, all.size()); ++i) {
    const std::size_t at = all.size() <= kPeriodsDrawn ? i : i * (all.size() - 1) / (kPeriodsDrawn - 1);
    drawn.push_back(all[at]);
  }
  const SweepTableRow& first = rows.front();
  PlotSpec by_delay{name + ": NRMSE against delay, one curve per period", "delay (ms)", "NRMSE (%, log)", {}, true};
  if (largest > 0) {
    by_delay.y_min = nrmse_panel.y_min;
    by_delay.y_max = nrmse_panel.y_max;
  }
  Series diverged_by_delay{"diverged (marked above the curves)", {}, {}, "points pt 2 ps 1.6 lw 2"};
  double largest_delay = 0.0;
  for (double period : drawn) {
    std::vector<std::pair<double, const SweepTableRow*>> points;
    for (const auto& r : rows) {
      if (r.period == period && r.stiffness == stiffness && r.model == first.model && r.alpha == first.alpha &&
          r.dt == first.dt && r.motion == first.motion && r.delay > 0) {
        points.push_back({r.delay, &r});
        largest_delay = std::max(largest_delay, r.delay);
      }
    }
    std::sort(points.begin(), points.end());
    std::ostringstream label;
    label << "T = " << period << " s";
    Series curve{label.str(), {}, {}, "linespoints"};
    for (const auto& [delay, row] : points) {
      curve.x.push_back(delay * 1e3);
      curve.y.push_back(row->diverged ? std::nan("") : row->nrmse_pct);
      if (row->diverged) {
        diverged_by_delay.x.push_back(delay * 1e3);
        diverged_by_delay.y.push_back(diverged_row);
      }
    }
    if (curve.x.empty()) continue;
    if (critical_delay) {
      if (const auto critical = critical_delay(period, first.alpha, first.dt)) {
        std::ostringstream text;
        text.precision(3);
        text << "critical, T = " << period << " s: " << *critical * 1e3 << " ms";
        by_delay.markers.push_back({*critical * 1e3, text.str()});
      }
    }
    by_delay.series.push_back(std::move(curve));
  }
  if (!diverged_by_delay.x.empty()) by_delay.series.push_back(std::move(diverged_by_delay));
  by_delay.x_min = 0.0;
  by_delay.x_max = largest_delay * 1e3 * 1.15;
  // Critical delays beyond the swept range would squeeze the curves: drop them, say so in the title.
  const std::size_t before = by_delay.markers.size();
  std::erase_if(by_delay.markers, [&](const VerticalMarker& m) { return m.x > *by_delay.x_max; });
  if (by_delay.markers.size() < before) by_delay.title += " (critical delays beyond the swept range not drawn)";
  if (!by_delay.series.empty()) write_png_plot(by_delay, sweep_delay_plot_path(png));
}

SweepTrends measure_trends(const std::vector<SweepTableRow>& rows) {
  SweepTrends trends;
  // Stiffness: same point but stiffness.
  std::map<std::tuple<SeriesKey, double>, std::vector<double>> by_point;
  std::map<std::tuple<SeriesKey, double>, std::vector<std::pair<double, double>>> by_series;
  for (const auto& r : rows) {
    if (r.diverged) {
      ++trends.diverged_points;
      continue;
    }
    if (!(r.delay > 0)) continue;  // a zero delay leaves only round-off to compare
    by_point[{series_key(r), r.period}].push_back(r.nrmse_pct);
    by_series[{series_key(r), r.stiffness}].push_back({r.period, r.nrmse_pct});
  }
  for (const auto& [key, values] : by_point) {
    if (values.size() < 2) continue;
    const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
    const double scale = std::max(std::abs(*lo), std::abs(*hi));
    if (scale > 0) trends.stiffness_max_relative_difference =
        std::max(trends.stiffness_max_relative_difference, (*hi - *lo) / scale);
  }
  std::size_t pairs = 0, falling = 0;
  for (auto& [key, points] : by_series) {
    std::sort(points.begin(), points.end());
    for (std::size_t i = 1; i < points.size(); ++i) {
      ++pairs;
      if (points[i].second < points[i - 1].second) ++falling;
    }
  }
  trends.period_falling_fraction = pairs ? static_cast<double>(falling) / pairs : std::nan("");
  std::map<std::tuple<double, double, std::string, double, double, double>, double> linear;
  for (const auto& r : rows) {
    if (r.model == "linear" && !r.diverged && r.delay > 0) {
      linear[{r.alpha, r.dt, r.motion, r.delay, r.period, r.stiffness}] = r.nrmse_pct;
    }
  }
  std::vector<double> ratios;
  for (const auto& r : rows) {
    if (r.model == "linear" || r.diverged || !(r.delay > 0)) continue;
    const auto it = linear.find({r.alpha, r.dt, r.motion, r.delay, r.period, r.stiffness});
    if (it != linear.end() && it->second > 0) ratios.push_back(r.nrmse_pct / it->second);
  }
  trends.nonlinear_to_linear_median_ratio = ratios.empty() ? std::nan("") : core::median(std::move(ratios));
  return trends;
}

}  // namespace rths::analysis
