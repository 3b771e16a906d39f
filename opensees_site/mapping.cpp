#include "opensees_site/mapping.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rths::opensees {

namespace {

void require_finite(const google::protobuf::RepeatedField<double>& values, const char* field) {
  for (int i = 0; i < values.size(); ++i)
    if (!std::isfinite(values[i]))
      throw std::invalid_argument(std::string("deployment.opensees.") + field + "[" +
                                  std::to_string(i) + "] is " + std::to_string(values[i]) +
                                  "; must be finite");
}

}  // namespace

BasicMapping::BasicMapping(const config::OpenSeesSite& site,
                           const std::vector<double>& actuator_stiffness,
                           const std::vector<int>& actuator_storeys, int storeys)
    : storeys_of_(actuator_storeys) {
  const int actuators = static_cast<int>(actuator_stiffness.size());
  if (actuators < 1)
    throw std::invalid_argument(
        "opensees-site: the study's case has no actuator (no experimental storey)");
  if (site.basic_dofs() < 0 || site.basic_dofs() > 64)
    throw std::invalid_argument("deployment.opensees.basic_dofs is " +
                                std::to_string(site.basic_dofs()) +
                                "; allowed 0 (= actuators) to 64");
  const int n = site.basic_dofs() > 0 ? site.basic_dofs() : actuators;
  require_finite(site.transformation(), "transformation");
  require_finite(site.initial_stiffness(), "initial_stiffness");
  if (site.transformation().empty()) {
    if (n != actuators)
      throw std::invalid_argument(
          "deployment.opensees.transformation is empty (the identity) but basic_dofs is " +
          std::to_string(n) + " and the study has " + std::to_string(actuators) +
          " actuators; give actuators x basic_dofs values");
    t_ = core::Mat::Identity(n, n);
  } else {
    if (site.transformation_size() != actuators * n)
      throw std::invalid_argument("deployment.opensees.transformation has " +
                                  std::to_string(site.transformation_size()) + " values; " +
                                  std::to_string(actuators) + " actuators x " + std::to_string(n) +
                                  " basic DOFs need " + std::to_string(actuators * n));
    t_.resize(actuators, n);
    for (int a = 0; a < actuators; ++a)
      for (int j = 0; j < n; ++j) t_(a, j) = site.transformation(a * n + j);
  }
  if (site.initial_stiffness().empty()) {
    core::Vec k(actuators);
    for (int a = 0; a < actuators; ++a) k[a] = actuator_stiffness[static_cast<std::size_t>(a)];
    k_ = t_.transpose() * k.asDiagonal() * t_;
  } else {
    if (site.initial_stiffness_size() != n * n)
      throw std::invalid_argument("deployment.opensees.initial_stiffness has " +
                                  std::to_string(site.initial_stiffness_size()) +
                                  " values; basic_dofs " + std::to_string(n) + " needs " +
                                  std::to_string(n * n) + " (column-major)");
    k_.resize(n, n);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) k_(i, j) = site.initial_stiffness(j * n + i);
  }
  for (int storey : storeys_of_)
    if (storey < 0 || storey >= storeys)
      throw std::invalid_argument("opensees-site: actuator storey " + std::to_string(storey + 1) +
                                  " outside the study's " + std::to_string(storeys) + " storeys");
}

void BasicMapping::to_floors(const double* basic, core::Vec& drift, core::Vec& u) const {
  drift.noalias() = t_ * Eigen::Map<const core::Vec>(basic, t_.cols());
  u.setZero();
  for (int a = 0; a < actuators(); ++a) u[storeys_of_[static_cast<std::size_t>(a)]] = drift[a];
  for (Eigen::Index s = 1; s < u.size(); ++s) u[s] += u[s - 1];  // floors from storey drifts
}

void BasicMapping::to_basic(const core::Vec& measured, double* basic) const {
  Eigen::Map<core::Vec>(basic, t_.cols()).noalias() = t_.transpose() * measured;
}

}  // namespace rths::opensees
