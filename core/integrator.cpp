#include "core/integrator.h"

#include <stdexcept>

namespace rths::core {

Integrator::Integrator(const StructuralModel& model, double dt, bool keep_dense) : dt_(dt) {
  if (!(dt > 0)) throw std::invalid_argument("time step dt must be > 0 s");
  if (keep_dense) {
    m_ = model.mass;
    c_ = model.damping;
    k0_ = model.stiffness;
  }
  const int n = model.dofs();
  u_ = Vec::Zero(n);
  v_ = Vec::Zero(n);
  a_ = Vec::Zero(n);
}

}  // namespace rths::core
