#include "runtime/record/measurements.h"

#include <stdexcept>

namespace rths::runtime {

void LinkLagAccumulator::reserve(int node_id, std::size_t answers) {
  LinkSeries& s = links_[node_id];
  s.node_id = node_id;
  // resize then clear: the capacity stays and its pages are touched now, so the live run neither
  // allocates nor takes a page fault per answer (the process's RSS is flat over the run).
  for (auto* v : {&s.time, &s.round_trip, &s.injected, &s.one_way_down, &s.one_way_up}) {
    v->resize(answers);
    v->clear();
  }
  for (auto* v : {&s.answered_step, &s.answers}) {
    v->resize(answers);
    v->clear();
  }
}

void LinkLagAccumulator::add(double time, const LinkSample& sample) {
  if (sample.answered_step() == 0) return;
  LinkSeries& s = links_[sample.node_id()];
  s.node_id = sample.node_id();
  if (!s.answered_step.empty() && s.answered_step.back() == sample.answered_step()) return;
  s.time.push_back(time);
  s.answered_step.push_back(sample.answered_step());
  s.answers.push_back(static_cast<std::int64_t>(sample.answers()));
  s.round_trip.push_back(sample.round_trip());
  s.injected.push_back(sample.injected_lag());
  s.one_way_down.push_back(sample.one_way_down());
  s.one_way_up.push_back(sample.one_way_up());
}

RunMeasurements measure_run(const RecordContents& record) {
  const RunHeader* header = record.header();
  if (header == nullptr)
    throw std::invalid_argument(
        "run record has no header" +
        (record.lost_entries() ? " (" + record.loss_report() + ")" : std::string()));
  RunMeasurements m;
  m.clock = header->clock();
  m.case_name = header->case_name();
  const auto steps = record.steps();
  const auto rows = static_cast<Eigen::Index>(steps.size());
  const int dofs = recorded_columns(*header), actuators = header->actuators();
  core::SimulationResult& r = m.steps;
  r.dt = header->dt();
  r.dofs.assign(header->recorded_dofs().begin(), header->recorded_dofs().end());
  r.time.resize(steps.size());
  r.displacement = core::Mat::Zero(rows, dofs);
  r.velocity = core::Mat::Zero(rows, dofs);
  r.acceleration = core::Mat::Zero(rows, dofs);
  r.command = core::Mat::Zero(rows, actuators);
  r.realised = core::Mat::Zero(rows, actuators);
  r.measured_force = core::Mat::Zero(rows, actuators);
  LinkLagAccumulator links;
  for (int id : header->link_node_ids()) links.reserve(id, 0);
  for (Eigen::Index k = 0; k < rows; ++k) {
    const StepRecord& s = *steps[static_cast<std::size_t>(k)];
    r.time[static_cast<std::size_t>(k)] = s.time();
    for (int i = 0; i < dofs && i < s.displacement_size(); ++i) {
      r.displacement(k, i) = s.displacement(i);
      r.velocity(k, i) = i < s.velocity_size() ? s.velocity(i) : 0.0;
      r.acceleration(k, i) = i < s.acceleration_size() ? s.acceleration(i) : 0.0;
    }
    for (int a = 0; a < actuators && a < s.command_size(); ++a) {
      r.command(k, a) = s.command(a);
      r.realised(k, a) = a < s.realised_size() ? s.realised(a) : 0.0;
      r.measured_force(k, a) = a < s.measured_force_size() ? s.measured_force(a) : 0.0;
    }
    for (const LinkSample& link : s.links()) links.add(s.time(), link);
  }
  m.links = links.links();
  if (const RunFooter* f = record.footer()) {
    m.has_footer = true;
    m.footer = *f;
    r.diverged = f->diverged();
  }
  return m;
}

}  // namespace rths::runtime
