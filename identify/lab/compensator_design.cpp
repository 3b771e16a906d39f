#include "identify/lab/compensator_design.h"

#include "identify/model/study_config.h"
#include "study/compensation_config.h"

#include <google/protobuf/text_format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rths::identify {

CompensatorKind parse_compensator_kind(const std::string& name) {
  if (name == "polynomial") return CompensatorKind::kPolynomial;
  if (name == "ats" || name == "adaptive-time-series") return CompensatorKind::kAdaptiveTimeSeries;
  if (name == "model-based" || name == "model_based") return CompensatorKind::kModelBased;
  if (name == "model-based-adaptive" || name == "model_based_adaptive") {
    return CompensatorKind::kAdaptedModelBased;
  }
  throw std::invalid_argument("--design-compensator: unknown kind '" + name +
                              "' (polynomial, ats, model-based, model-based-adaptive)");
}

std::string compensator_kind_name(CompensatorKind kind) {
  switch (kind) {
    case CompensatorKind::kPolynomial: return "polynomial";
    case CompensatorKind::kAdaptiveTimeSeries: return "ats";
    case CompensatorKind::kModelBased: return "model-based";
    case CompensatorKind::kAdaptedModelBased: return "model-based-adaptive";
  }
  return "unknown";
}

namespace {

// The identified stages' low-frequency lag (delay excluded), and whether there are any.
struct PlantDynamics {
  double lag = 0.0;
  bool any = false;
};

// Appends the case's first-order and transfer-function stages to the plant.
PlantDynamics append_dynamics(const config::Case& study_case, core::PlantModel& plant) {
  PlantDynamics dynamics;
  for (const auto& stage : study_case.delay()) {
    if (stage.has_first_order()) {
      const double t = stage.first_order().time_constant();
      plant.append({1.0}, {t, 1.0});
      dynamics.lag += t;
      dynamics.any = true;
    } else if (stage.has_transfer_function()) {
      // wn^2 / (s^2 + 2 zeta wn s + wn^2): low-frequency lag 2 zeta / wn = den[1] / den[2].
      const auto& tf = stage.transfer_function();
      const std::vector<double> num(tf.numerator().begin(), tf.numerator().end());
      const std::vector<double> den(tf.denominator().begin(), tf.denominator().end());
      plant.append(num, den);
      dynamics.lag += den.at(1) / den.at(2);
      dynamics.any = true;
    }
  }
  return dynamics;
}

void set_polynomial(config::Compensation& c, double lead, double dt, std::ostringstream& summary) {
  auto* p = c.mutable_polynomial();
  p->set_order(2);
  p->set_lead(std::min(lead, 1.0));
  const long steps = std::max(1L, std::lround(0.5 * lead / dt));
  p->set_spacing(static_cast<double>(steps) * dt);
  summary << "polynomial order 2, lead " << p->lead() * 1e3 << " ms, spacing " << steps << " steps";
}

void set_adaptive_time_series(config::Compensation& c, double delay, double lead, double gain,
                              std::ostringstream& summary) {
  auto* a = c.mutable_adaptive_time_series();
  const double a2 = delay * (lead - delay) + 0.5 * delay * delay;
  a->set_window(1.0);
  a->set_initial_a0(1.0 / gain);
  a->set_initial_a1(lead);
  a->set_initial_a2(a2);
  a->mutable_a0_bounds()->set_min(0.5 / gain);
  a->mutable_a0_bounds()->set_max(2.0 / gain);
  a->mutable_a1_bounds()->set_min(0.0);
  a->mutable_a1_bounds()->set_max(3.0 * lead);
  const double a2_span = 3.0 * std::abs(a2) + 1e-6;
  a->mutable_a2_bounds()->set_min(-a2_span);
  a->mutable_a2_bounds()->set_max(a2_span);
  summary << "ATS window 1 s, initial a0 " << 1.0 / gain << ", a1 " << lead * 1e3 << " ms, a2 "
          << a2 << " s^2";
}

void set_model_based(config::Compensation& c, const config::Case& study_case, bool adapted,
                     double lead, double dt, std::ostringstream& summary) {
  auto* m = c.mutable_model_based();
  for (const auto& stage : study_case.delay()) *m->add_plant() = stage;
  m->set_lead_order(2);
  m->set_rolloff_frequency(std::min(50.0, 0.125 / dt));
  summary << "model-based inverse, lead order 2, roll-off " << m->rolloff_frequency() << " Hz";
  if (adapted) {
    auto* a = m->mutable_adaptive_correction();
    a->set_window(1.0);
    a->mutable_a0_bounds()->set_min(0.5);
    a->mutable_a0_bounds()->set_max(2.0);
    a->mutable_a1_bounds()->set_min(-lead);
    a->mutable_a1_bounds()->set_max(lead);
    a->mutable_a2_bounds()->set_min(-lead * lead);
    a->mutable_a2_bounds()->set_max(lead * lead);
    summary << ", adaptive correction window 1 s, a1 within +-" << lead * 1e3 << " ms, a2 within +-"
            << lead * lead << " s^2";
  }
}

}  // namespace

CompensatorDesign design_compensator(const ChannelModel& actuator, const SignalScales& scales,
                                     CompensatorKind kind, double dt) {
  if (actuator.channel != Channel::kMeasured) {
    throw std::invalid_argument(
        "compensator design needs the actuator model (channel 'measured'), "
        "got channel '" +
        channel_name(actuator.channel) + "'");
  }
  if (!(dt > 0.0)) throw std::invalid_argument("compensator design: dt must be > 0 s");
  CompensatorDesign design;
  ActuatorCase identified =
      actuator_case(actuator, scales, "identified_" + compensator_kind_name(kind));
  design.study_case = std::move(identified.study_case);
  design.ignored = std::move(identified.left_out);
  const auto& shift = design.study_case.delay(0);
  const double delay = shift.shift().delay();
  const double gain = shift.amplitude_gain() == 0.0 ? 1.0 : shift.amplitude_gain();
  design.plant.delay = delay;
  design.plant.gain = gain;
  const PlantDynamics dynamics = append_dynamics(design.study_case, design.plant);
  design.plant_lag = delay + dynamics.lag;
  if (!(design.plant_lag > 0.0)) {
    throw std::invalid_argument(
        "compensator design: the identification found no actuator delay or dynamics to "
        "compensate (model: " +
        actuator.describe(scales) +
        "); declare or allow the delay / first_order effects, or run without compensation "
        "knowingly");
  }
  const bool model_based =
      kind == CompensatorKind::kModelBased || kind == CompensatorKind::kAdaptedModelBased;
  if (model_based && !dynamics.any && delay == 0.0) {
    throw std::invalid_argument("compensator design: no actuator model to invert");
  }

  config::Compensation* c = design.study_case.add_compensation();
  const double lead = design.plant_lag;
  std::ostringstream summary;
  summary << "identified actuator: " << design.plant.describe() << ", low-frequency lag "
          << lead * 1e3 << " ms; ";
  switch (kind) {
    case CompensatorKind::kPolynomial: set_polynomial(*c, lead, dt, summary); break;
    case CompensatorKind::kAdaptiveTimeSeries:
      set_adaptive_time_series(*c, delay, lead, gain, summary);
      break;
    case CompensatorKind::kModelBased:
    case CompensatorKind::kAdaptedModelBased:
      set_model_based(*c, design.study_case, kind == CompensatorKind::kAdaptedModelBased, lead, dt,
                      summary);
      break;
  }
  // The block must build at this dt: a design that cannot run is an error here, not in the lab.
  study::make_compensator(*c, dt, "designed compensation");
  design.summary = summary.str();
  return design;
}

std::filesystem::path write_compensator_case(const CompensatorDesign& design,
                                             const std::filesystem::path& directory) {
  std::string body;
  google::protobuf::TextFormat::Printer printer;
  printer.SetInitialIndentLevel(1);
  if (!printer.PrintToString(design.study_case, &body)) {
    throw std::runtime_error("cannot print the designed case");
  }
  std::filesystem::create_directories(directory);
  const auto path = directory / ("compensator_" + design.study_case.name() + ".textproto");
  std::ofstream out(path);
  out << "# Designed by `rths identify --design-compensator`: " << design.summary << "\n"
      << "# Append this case to a study config (its delay stages are the identified actuator).\n";
  for (const auto& note : design.ignored) out << "# not compensated: " << note << "\n";
  out << "cases {\n" << body << "}\n";
  if (!out) throw std::runtime_error(path.string() + ": cannot write the compensator case");
  return path;
}

}  // namespace rths::identify
