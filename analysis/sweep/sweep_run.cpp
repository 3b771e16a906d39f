#include "analysis/sweep/sweep_run.h"

#include <algorithm>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "analysis/common/compare.h"
#include "analysis/sweep/batch_kernel.h"
#include "core/integrators.h"
#include "core/simulation.h"
#include "core/stability.h"
#include "core/substructure.h"
#include "study/study.h"
#include "util/parallel_for.h"

namespace rths::analysis {
namespace {

constexpr std::size_t kPeriodsPerFastItem = 16;
constexpr double kInf = std::numeric_limits<double>::infinity();

bool is_linear(const config::RestoringForce& model) {
  return model.kind_case() == config::RestoringForce::kLinear ||
         model.kind_case() == config::RestoringForce::KIND_NOT_SET;
}

// Error measures of one point from the two displacement histories (analysis::compare). A diverged
// point (compare's rule, or `diverging` as `rths run` judges it: past its critical delay with an
// exponentially growing envelope) keeps its peaks; its error measures are inf (they measure
// nothing once it grows).
void fill_metrics(SweepRow& row, const std::vector<double>& reference, bool reference_diverged,
                  const std::vector<double>& delayed, bool delayed_diverged, bool diverging) {
  const Comparison c = compare(reference, delayed, delayed_diverged);
  row.diverged = reference_diverged || c.diverged || diverging;
  row.peak_reference = reference_diverged ? kInf : c.peak_reference_m;
  row.peak_delayed = delayed_diverged ? kInf : c.peak_m;
  if (row.diverged) {
    row.peak_error_pct = row.rms_error_pct = row.peak_error = kInf;
    row.nrmse_pct = row.eq2_paper = kInf;
    return;
  }
  row.peak_error_pct = c.peak_error_pct;
  row.rms_error_pct = c.rms_error_pct;
  row.peak_error = c.peak_error_m;
  row.nrmse_pct = c.nrmse_pct;
  row.eq2_paper = c.paper_eq2_as_printed;
}

struct GroupKey {
  std::size_t motion, dt_index, model, stiffness;
};

// The SDOF structure of one period and stiffness, built by core exactly as `rths run` would.
core::StructuralModel structure_for(const SweepGrid& grid, double period, double stiffness) {
  config::Structure structure = grid.study().structure();
  structure.mutable_sdof()->set_period(period);
  structure.mutable_sdof()->set_stiffness(stiffness);
  return study::make_structure(structure);
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
  SweepRunner(const SweepGrid& grid, const SweepOptions& options) : grid_(grid), options_(options) {
    std::tie(first_, last_) = grid.shard_range(options.shard);
    rows_.resize(last_ - first_);
    per_period_ = grid.alphas().size() * grid.delays().size();
    per_group_ = per_period_ * grid.periods().size();
    const CriticalDelayOf critical_delay = critical_delay_of(grid);
    for (double period : grid.periods())
      for (double alpha : grid.alphas())
        for (double dt : grid.dts())
          if (alpha > 0.0) critical_[{period, alpha, dt}] = critical_delay(period, alpha, dt);
  }

  std::vector<SweepRow> run() {
    build_items();
    util::parallel_for(items_.size(), options_.threads,
                       [this](std::size_t i) { run_item(items_[i]); });
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
  std::size_t index_of(std::size_t group, std::size_t period, std::size_t alpha,
                       std::size_t delay) const {
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
                        study::integrator_kind(grid_.study().integrator()) ==
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

  // The point's lag is past its critical delay and its envelope grows exponentially (at the SDOF's
  // period): what `rths run` calls diverging. The paper's Eq. 1 as printed is a lead (lag -delay).
  bool diverging(const SweepPoint& point, const std::vector<double>& u) const {
    if (!(point.alpha > 0.0) || !(point.delay > 0.0)) return false;
    const double lag = grid_.delay_model() == config::Sweep::EQ1 ? -point.delay : point.delay;
    const auto it = critical_.find({point.period, point.alpha, point.dt});
    const bool past = it != critical_.end() && it->second && lag >= *it->second;
    return analysis::diverging(u, point.dt, point.period, past);
  }

  std::size_t run_general(const Item& item) {
    const GroupKey key = group_key(item.group);
    const core::GroundMotion& motion = grid_.motion_at(key.motion, key.dt_index);
    const double stiffness = grid_.stiffnesses()[key.stiffness];
    const core::StoreyModelFactory factory = study::make_storey_factory(grid_.models()[key.model]);
    std::size_t done = 0;
    for (std::size_t p = item.period_begin; p < item.period_end; ++p) {
      core::HybridSetup setup;
      setup.model = structure_for(grid_, grid_.periods()[p], stiffness);
      setup.integrator = study::integrator_kind(grid_.study().integrator());
      setup.dt = motion.dt;
      setup.allow_unstable = grid_.study().integrator().allow_unstable();
      setup.partition = core::partition_by_fraction(setup.model.storey_stiffness, 0.0, factory);
      const core::SimulationResult reference = core::simulate(setup, motion);
      const std::vector<double> reference_u = floor_history(reference, 0);
      for (std::size_t a = 0; a < grid_.alphas().size(); ++a) {
        for (std::size_t d = 0; d < grid_.delays().size(); ++d) {
          const std::size_t index = index_of(item.group, p, a, d);
          if (!in_shard(index)) continue;
          const double alpha = grid_.alphas()[a], delay = grid_.delays()[d];
          core::HybridSetup delayed = setup;
          delayed.partition =
              core::partition_by_fraction(setup.model.storey_stiffness, alpha, factory);
          delayed.delays.clear();
          if (delay > 0 && !delayed.partition.actuator_storeys.empty()) {
            const config::DelayStage stage = stage_for(grid_.delay_model(), delay);
            for (std::size_t act = 0; act < delayed.partition.actuator_storeys.size(); ++act) {
              core::DelayChain chain;
              chain.add(study::make_delay_stage(stage, motion.dt, grid_.base_dir()));
              delayed.delays.push_back(std::move(chain));
            }
          }
          const core::SimulationResult result = core::simulate(delayed, motion);
          SweepRow& row = row_at(index);
          row.point = grid_.point(index);
          const std::vector<double> u = floor_history(result, 0);
          fill_metrics(row, reference_u, reference.diverged, u, result.diverged,
                       diverging(row.point, u));
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
      reference_lanes.push_back(
          {model.mass(0, 0), model.damping(0, 0), model.storey_stiffness[0], 0.0});
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
          lanes.push_back({model.mass(0, 0), model.damping(0, 0),
                           alpha < 1.0 ? (1.0 - alpha) * k : 0.0, alpha > 0.0 ? alpha * k : 0.0});
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
                     outcome[l].diverged, diverging(row.point, delayed[l]));
        ++done;
      }
    }
    return done;
  }

  const SweepGrid& grid_;
  const SweepOptions& options_;
  std::size_t first_ = 0, last_ = 0, per_period_ = 1, per_group_ = 1;
  std::vector<Item> items_;
  // (period, alpha, dt) -> critical delay (s); empty: stable for every delay.
  std::map<std::tuple<double, double, double>, std::optional<double>> critical_;
  std::vector<SweepRow> rows_;
  std::mutex progress_mutex_;
  std::size_t completed_ = 0;
};

}  // namespace

SweepStabilityCheck check_sweep_stability(const SweepGrid& grid) {
  SweepStabilityCheck out;
  const core::IntegratorKind kind = study::integrator_kind(grid.study().integrator());
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
            where << "T = " << period << " s, alpha = " << alpha << ", dt = " << dt * 1e3
                  << " ms: " << check.describe();
            out.worst = where.str();
          }
        }
      }
    }
  }
  return out;
}

CriticalDelayOf critical_delay_of(const SweepGrid& grid) {
  const core::IntegratorKind kind = study::integrator_kind(grid.study().integrator());
  const double zeta = grid.study().structure().damping().modal_zeta();
  return [kind, zeta](double period, double alpha, double dt) -> std::optional<double> {
    const core::StructuralModel model = core::make_sdof(period, zeta, 1.0);
    // The lag only bounds the discrete search: search far enough to find the limit.
    const auto continuous = core::continuous_critical_delay(period, zeta, alpha).critical_delay;
    const double search = continuous ? 1.5 * *continuous : period;
    return core::check_critical_delay(model, {alpha * model.stiffness(0, 0)}, kind, dt, search)
        .critical();
  };
}

std::vector<SweepRow> run_sweep(const SweepGrid& grid, const SweepOptions& options) {
  if (options.shard.count == 0 || options.shard.index >= options.shard.count) {
    throw std::invalid_argument("sweep shard " + options.shard.to_string() + " is not 0 <= i < N");
  }
  SweepRunner runner(grid, options);
  return runner.run();
}

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
    t.peak_error_pct = row.peak_error_pct;
    t.rms_error_pct = row.rms_error_pct;
    t.peak_error = row.peak_error;
    t.nrmse_pct = row.nrmse_pct;
    t.eq2_paper = row.eq2_paper;
    t.diverged = row.diverged;
    table.push_back(std::move(t));
  }
  return table;
}

}  // namespace rths::analysis
