#include "study/study.h"

#include "core/rig_effects.h"
#include "study/case_link.h"
#include "study/compensation_config.h"
#include "study/delay_trace_file.h"
#include "study/known_enums.h"
#include "study/memory_budget.h"
#include "study/motion_files.h"
#include "study/ranges.h"
#include "study/restoring_force_config.h"
#include "study/structure_config.h"
#include "study/text_columns.h"
#include "study/text_format.h"
#include "study/tracking_config.h"
#include "util/sha256.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace rths::study {
namespace {

// A study that validated but cannot be prepared (its motion, its servo rate against dt).
void require(bool ok, const std::string& source, const std::string& message) {
  if (!ok) throw std::invalid_argument(source + ": " + message);
}

}  // namespace

config::Study parse_study(const std::string& text, const std::string& source_name) {
  config::Study study;
  parse_text_format(text, source_name, study);
  validate_study(study, source_name);
  return study;
}

config::Study load_study(const std::filesystem::path& path) {
  return parse_study(read_text_file(path, "config"), path.string());
}

core::StructuralModel make_structure(const config::Structure& structure,
                                     const std::filesystem::path& base_dir) {
  if (structure.has_matrices()) return matrix_structure(structure, base_dir);
  core::StructuralModel model;
  if (structure.has_sdof()) {
    const config::Sdof& sdof = structure.sdof();
    double mass = sdof.has_mass() ? sdof.mass() : 1.0;  // validated > 0 at load
    double stiffness = 0.0;
    if (sdof.period() > 0 && sdof.stiffness() > 0) {
      stiffness = sdof.stiffness();
      mass =
          stiffness * sdof.period() * sdof.period() / (4.0 * std::numbers::pi * std::numbers::pi);
    } else if (sdof.period() > 0) {
      const double omega = 2.0 * std::numbers::pi / sdof.period();
      stiffness = mass * omega * omega;
    } else {
      stiffness = sdof.stiffness();
    }
    model = core::make_shear_building({mass}, {stiffness});
  } else {
    const auto& b = structure.shear_building();
    model = core::make_shear_building({b.storey_mass().begin(), b.storey_mass().end()},
                                      {b.storey_stiffness().begin(), b.storey_stiffness().end()});
  }
  const config::Damping& damping = structure.damping();
  if (damping.has_rayleigh()) {
    const auto& r = damping.rayleigh();
    model.damping =
        core::rayleigh_damping(model.mass, model.stiffness, r.zeta(),
                               r.mode_i() == 0 ? 1 : r.mode_i(), r.mode_j() == 0 ? 2 : r.mode_j());
  } else if (model.dofs() == 1) {
    // 2 zeta m omega written out, so an SDOF from a config equals make_sdof() to the last bit.
    const double omega = std::sqrt(model.stiffness(0, 0) / model.mass(0, 0));
    model.damping(0, 0) = 2.0 * damping.modal_zeta() * model.mass(0, 0) * omega;
  } else {
    model.damping = core::modal_damping(model.mass, model.stiffness, damping.modal_zeta());
  }
  return model;
}

namespace {
// The one map between the config's integrator kinds and core's, read both ways.
constexpr std::pair<config::Integrator::Kind, core::IntegratorKind> kIntegratorKinds[] = {
    {config::Integrator::EXPLICIT_NEWMARK, core::IntegratorKind::kExplicitNewmark},
    {config::Integrator::CENTRAL_DIFFERENCE, core::IntegratorKind::kCentralDifference},
    {config::Integrator::CHEN_RICLES, core::IntegratorKind::kChenRicles},
    {config::Integrator::NEWMARK_AVERAGE_ACCELERATION,
     core::IntegratorKind::kNewmarkAverageAcceleration},
    {config::Integrator::ALPHA_OS, core::IntegratorKind::kAlphaOS},
    {config::Integrator::KR_ALPHA, core::IntegratorKind::kKRAlpha},
    {config::Integrator::EXACT_ZOH, core::IntegratorKind::kExactZoh}};
}  // namespace

core::IntegratorKind integrator_kind(const config::Integrator& integrator) {
  for (const auto& [config_kind, kind] : kIntegratorKinds)
    if (config_kind == integrator.kind()) return kind;
  // Never a default for a value nobody chose (a study is checked at load; this is for the rest).
  std::string why = "integrator.kind ";
  why += std::to_string(integrator.kind());
  why += " is not a known integrator";
  throw std::invalid_argument(why);
}

config::Integrator::Kind config_integrator_kind(core::IntegratorKind kind) {
  for (const auto& [config_kind, core_kind] : kIntegratorKinds)
    if (core_kind == kind) return config_kind;
  throw std::invalid_argument("integrator " + core::to_string(kind) + " has no config kind");
}

int servo_substeps(const config::Study& study, double dt) {
  const double rate = study.servo().rate();
  if (rate == 0) return 1;
  const double per_step = rate * dt;
  const double whole = std::round(per_step);
  require(std::isfinite(rate) && rate > 0 && whole >= 1 && whole <= kMaxServoSubsteps &&
              std::abs(per_step - whole) <= 1e-6 * whole,
          "servo",
          "servo.rate = " + core::format_number(rate) + " Hz must be an integer multiple (1 to " +
              std::to_string(kMaxServoSubsteps) + ") of the integrator's rate " +
              core::format_number(1.0 / dt) + " Hz (dt = " + core::format_number(dt) + " s)");
  return static_cast<int>(whole);
}

// What a run of this study holds per step (study/recorders.h, run_bytes_per_step: its
// simulations, their responses, the results table and the motion) over `seconds` of record at
// dt (s), checked before any of it is allocated; `source` says where the seconds came from.
void require_run_memory(const PreparedStudy& prepared, double dt, double seconds,
                        const std::string& source) {
  const config::Study& study = prepared.config;
  const config::SafetyLimits& limits = study.deployment().limits();
  const double steps = seconds / dt;
  // 1.8e19 steps is past what a uint64 holds (2^64 = 1.8447e19): refused before the cast.
  require(std::isfinite(steps) && steps < 1.8e19, "integrator.dt",
          "integrator.dt = " + core::format_number(dt) + " s over the " +
              core::format_number(seconds) + " s record" + source + " is " +
              core::format_number(steps) + " steps, not a count a run can keep");
  require_memory(static_cast<std::uint64_t>(steps) + 2,
                 run_bytes_per_step(prepared.recorders, prepared.base.model.dofs(),
                                    prepared.base.partition.actuator_storeys.size(),
                                    static_cast<std::size_t>(std::max(1, study.cases_size())),
                                    limits.max_displacement() > 0 || limits.max_velocity() > 0),
                 "integrator.dt = " + core::format_number(dt) + " s over the " +
                     core::format_number(seconds) + " s record" + source);
}

core::HybridSetup base_setup(const config::Study& study, double dt,
                             const std::filesystem::path& base_dir,
                             std::vector<std::string>* warnings) {
  core::HybridSetup base;
  base.model = make_structure(study.structure(), base_dir);
  base.integrator = integrator_kind(study.integrator());
  base.dt = dt;
  base.allow_unstable = study.integrator().allow_unstable();
  base.servo_substeps = servo_substeps(study, dt);
  const auto& sub = study.substructuring();
  if (study.structure().has_matrices() || !sub.experimental_dofs().empty()) {
    if (warnings && !base.model.low_rank_damping.empty())
      warnings->push_back(base.model.low_rank_damping.statement);  // how modal damping is kept
    base.partition = split_at_dofs(base.model, sub, dt / base.servo_substeps, warnings);
    return base;
  }
  const core::StoreyModelFactory factory = make_storey_factory(sub.model());
  if (!sub.experimental_storeys().empty()) {
    std::vector<int> storeys;
    for (int s : sub.experimental_storeys()) storeys.push_back(s - 1);
    base.partition = core::partition_by_storeys(base.model.storey_stiffness, storeys, factory);
  } else {
    base.partition = core::partition_by_fraction(base.model.storey_stiffness,
                                                 sub.experimental_fraction(), factory);
  }
  return base;
}

PreparedStudy prepare_study(const config::Study& study, const std::filesystem::path& base_dir) {
  PreparedStudy prepared;
  prepared.config = study;
  prepared.base_dir = base_dir;
  // The run is sized from the motion file's extent before a sample of it is parsed, where the
  // file states its dt (motion_extent_before_reading), and again from the record once read.
  const std::optional<MotionFileExtent> extent =
      motion_extent_before_reading(study.motion(), base_dir);
  std::optional<core::GroundMotion> record;
  if (!extent) record = load_motion(study.motion(), base_dir);
  const bool dt_given = study.integrator().dt() > 0;
  double dt = dt_given ? study.integrator().dt() : (extent ? extent->dt : record->dt);
  prepared.base = base_setup(study, dt, base_dir, &prepared.warnings);
  prepared.recorders =
      plan_recorders(study, prepared.base.model.dofs(), experimental_dofs(prepared.base.partition));
  if (extent) {
    require_run_memory(prepared, dt, extent->seconds(),
                       " (" + std::to_string(extent->samples) +
                           " samples by the motion file's extent, before a sample is parsed)");
    record = load_motion(study.motion(), base_dir);
    if (!dt_given && std::abs(record->dt - dt) > 1e-12 * dt) {  // times unlike column_dt
      dt = record->dt;
      prepared.base = base_setup(study, dt, base_dir, nullptr);
    }
  }
  require(dt < record->duration(), "motion",
          "integrator.dt = " + core::format_number(dt) + " s is not shorter than the record (" +
              core::format_number(record->duration()) + " s)");
  require_run_memory(prepared, dt, record->duration(), "");
  prepared.motion =
      std::abs(dt - record->dt) <= 1e-12 * dt ? std::move(*record) : core::resampled(*record, dt);
  for (const config::Case& c : study.cases()) {
    const double lag = make_delay_chain(c.delay(), dt, base_dir).nominal_delay();
    require(lag < prepared.motion.duration(), "case '" + c.name() + "'",
            "its delay of " + core::format_number(lag) + " s is not shorter than the record (" +
                core::format_number(prepared.motion.duration()) + " s)");
  }
  return prepared;
}

core::HybridSetup setup_for_case(const PreparedStudy& prepared, const config::Case& study_case) {
  core::HybridSetup setup = prepared.base;
  setup.delays.clear();
  const std::size_t actuators = setup.partition.actuator_storeys.size();
  const double servo_period = setup.dt / setup.servo_substeps;
  for (std::size_t a = 0; a < actuators; ++a)
    setup.delays.push_back(make_delay_chain(study_case.delay(), servo_period, prepared.base_dir));
  std::vector<int> all(actuators);
  for (std::size_t a = 0; a < actuators; ++a) all[a] = static_cast<int>(a);
  apply_compensation(setup, all, study_case.compensation(), "case '" + study_case.name() + "'");
  if (study_case.has_force_predictor())
    apply_force_predictor(setup, study_case.force_predictor(),
                          "case '" + study_case.name() + "' force_predictor");
  apply_case_links(setup, study_case.link(), "case '" + study_case.name() + "' link");
  return setup;
}

void validate_force_predictor(const config::ForcePredictor& block, double dt,
                              const std::string& where) {
  for (int i = 0; i < block.actuators_size(); ++i) {
    const std::string field = where + ".actuators[" + std::to_string(i) + "]";
    if (block.actuators(i) < 1)
      throw std::invalid_argument(field + " = " + std::to_string(block.actuators(i)) +
                                  " must be >= 1 (actuators are 1-based)");
    for (int j = 0; j < i; ++j)
      if (block.actuators(j) == block.actuators(i))
        throw std::invalid_argument(field + " repeats actuator " +
                                    std::to_string(block.actuators(i)));
  }
  const auto finite_at_least = [&](double value, double least, bool strict, const char* name,
                                   const std::string& unit) {
    const bool ok = std::isfinite(value) && (strict ? value > least : value >= least);
    if (!ok)
      throw std::invalid_argument(where + "." + name + " = " + core::format_number(value) + unit +
                                  " must be " + (strict ? "> " : ">= ") +
                                  core::format_number(least) + unit);
  };
  finite_at_least(block.stiffness_factor(), 0.0, false, "stiffness_factor", "");
  finite_at_least(block.damping(), 0.0, false, "damping", " N s/m");
  finite_at_least(block.forgetting_time(), 0.0, false, "forgetting_time", " s");
  finite_at_least(block.min_displacement(), 0.0, false, "min_displacement", " m");
  finite_at_least(block.error_window(), 0.0, false, "error_window", " s");
  finite_at_least(block.max_relative_error(), 0.0, false, "max_relative_error", "");
  finite_at_least(block.force_lag(), 0.0, false, "force_lag", " s");
  if (block.has_model()) {
    if (block.linear_model())
      throw std::invalid_argument(where +
                                  ".model gives the model's shape and linear_model: true asks "
                                  "for none: give one of them");
    try {
      make_storey_factory(block.model());
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where + ".model." + e.what());
    }
  }
  if (block.error_window() > 0 && dt > 0 && block.error_window() < dt)
    throw std::invalid_argument(
        where + ".error_window = " + core::format_number(block.error_window()) +
        " s is shorter than one step (integrator.dt = " + core::format_number(dt) + " s)");
}

double predictor_stiffness_factor(const config::ForcePredictor& block) {
  return block.stiffness_factor() > 0 ? block.stiffness_factor() : 1.0;
}

core::PredictorParameters predictor_parameters(const config::ForcePredictor& block,
                                               double declared_stiffness) {
  core::PredictorParameters p;
  p.stiffness = declared_stiffness * predictor_stiffness_factor(block);
  p.damping = block.damping();
  p.adapt = !block.fixed_model();
  if (block.forgetting_time() > 0) p.forgetting_time = block.forgetting_time();
  if (block.min_displacement() > 0) p.min_displacement = block.min_displacement();
  if (block.error_window() > 0) p.error_window = block.error_window();
  p.max_relative_error = block.max_relative_error();
  p.specimen_shape = !block.linear_model();
  p.force_lag = block.force_lag();
  // The model's own shape at the declared specimen's initial stiffness (validated above).
  if (block.has_model()) p.shape = make_storey_factory(block.model())(declared_stiffness);
  return p;
}

void apply_force_predictor(core::HybridSetup& setup, const config::ForcePredictor& block,
                           const std::string& where) {
  validate_force_predictor(block, setup.dt, where);
  const auto& storeys = setup.partition.actuator_storeys;
  const int actuators = static_cast<int>(storeys.size());
  std::vector<int> chosen;
  for (int a : block.actuators()) {
    if (a > actuators)
      throw std::invalid_argument(where + ".actuators names actuator " + std::to_string(a) +
                                  " but the study has " + std::to_string(actuators));
    chosen.push_back(a - 1);
  }
  if (chosen.empty())
    for (int a = 0; a < actuators; ++a) chosen.push_back(a);
  setup.predictors.assign(static_cast<std::size_t>(actuators), std::nullopt);
  for (int a : chosen) {
    const auto& specimen =
        setup.partition
            .experimental[static_cast<std::size_t>(storeys[static_cast<std::size_t>(a)])];
    if (!specimen)
      throw std::invalid_argument(where + ": actuator " + std::to_string(a + 1) +
                                  " has no declared specimen to start its model from");
    core::PredictorParameters p = predictor_parameters(block, specimen->initial_stiffness());
    // Built once here so that a parameter out of range is refused before any run, named.
    core::ForcePredictor check(p, setup.dt, where + " (actuator " + std::to_string(a + 1) + ")",
                               specimen.get());
    setup.predictors[static_cast<std::size_t>(a)] = p;
  }
}

void apply_compensation(core::HybridSetup& setup, const std::vector<int>& actuators,
                        const google::protobuf::RepeatedPtrField<config::Compensation>& blocks,
                        const std::string& where) {
  if (blocks.empty()) return;
  const auto count = static_cast<std::size_t>(blocks.size());
  if (count > 1 && count != actuators.size()) {
    throw std::invalid_argument(where + ": " + std::to_string(count) + " compensation blocks for " +
                                std::to_string(actuators.size()) +
                                " actuators; give one (for every actuator) or one per actuator");
  }
  const double servo_period = setup.dt / setup.servo_substeps;
  for (std::size_t i = 0; i < actuators.size(); ++i) {
    const int a = actuators[i];
    if (a < 0 || a >= static_cast<int>(setup.delays.size()))
      throw std::invalid_argument(where + ": actuator " + std::to_string(a + 1) +
                                  " does not exist");
    const std::size_t b = count == 1 ? 0 : i;
    const std::string block_name = where + " compensation[" + std::to_string(b) + "]";
    if (setup.delays[static_cast<std::size_t>(a)].compensator())
      throw std::invalid_argument(
          block_name + ": actuator " + std::to_string(a + 1) +
          " already has a compensator (from its case); give it in one place");
    setup.delays[static_cast<std::size_t>(a)].set_compensator(
        make_compensator(blocks[static_cast<int>(b)], servo_period, block_name));
  }
}

const config::Case& reference_case(const config::Study& study) {
  if (study.cases_size() == 0) throw std::invalid_argument("the study has no cases");
  if (!study.reference_case().empty()) {
    for (const config::Case& c : study.cases()) {
      if (c.name() == study.reference_case()) return c;
    }
    throw std::invalid_argument("reference_case '" + study.reference_case() +
                                "' is not among the cases");
  }
  return study.cases(0);
}

const config::Case* case_named(const config::Study& study, const std::string& name) {
  if (name.empty()) return &reference_case(study);
  for (const config::Case& c : study.cases())
    if (c.name() == name) return &c;
  return nullptr;
}

const config::Case& find_case(const config::Study& study, const std::string& name) {
  if (const config::Case* c = case_named(study, name)) return *c;
  throw std::invalid_argument("case '" + name + "' is not among the study's cases");
}

}  // namespace rths::study
