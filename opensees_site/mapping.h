#pragma once
// The element's basic DOFs and the study's actuators.
//
//   drift  = T u_b             (m; actuators x n, T from deployment.opensees.transformation)
//   f_b    = T^T f_measured    (N; the element's basic force, what getForce answers)
//   K_b    = declared initial_stiffness, else T^T diag(k_a) T (N/m; k_a the specimens' initial
//            stiffness), the answer to getInitialStiff and getTangentStiff
//   u      = the study's floor displacements with drift a at storey actuator_storeys[a] and no
//            drift elsewhere (u_s = sum of drifts of storeys 1..s), what the coordinator trials.

#include <vector>

#include "core/integrators.h"
#include "rths/proto/opensees.pb.h"

namespace rths::opensees {

class BasicMapping {
 public:
  // actuator_stiffness: k_a (N/m) per actuator; actuator_storeys: the study's storey (0-based) of
  // each actuator; storeys: the study's storey count. Throws std::invalid_argument naming the
  // field of deployment.opensees, the value and what it must be.
  BasicMapping(const config::OpenSeesSite& site, const std::vector<double>& actuator_stiffness,
               const std::vector<int>& actuator_storeys, int storeys);

  int basic_dofs() const { return static_cast<int>(t_.cols()); }
  int actuators() const { return static_cast<int>(t_.rows()); }
  // u (floor displacements) from n basic values; allocates nothing once `u` has its size.
  void to_floors(const double* basic, core::Vec& drift, core::Vec& u) const;
  // n basic forces from the actuators' measured forces.
  void to_basic(const core::Vec& measured, double* basic) const;
  const core::Mat& transformation() const { return t_; }
  const core::Mat& stiffness() const { return k_; }

 private:
  core::Mat t_, k_;
  std::vector<int> storeys_of_;
};

}  // namespace rths::opensees
