#include "core/integrator.h"

#include <stdexcept>

namespace rths::core {

Integrator::Integrator(const StructuralModel& model, double dt)
    : m_(model.mass), c_(model.damping), k0_(model.stiffness), dt_(dt) {
  if (!(dt > 0)) throw std::invalid_argument("time step dt must be > 0 s");
  const int n = model.dofs();
  u_ = Vec::Zero(n);
  v_ = Vec::Zero(n);
  a_ = Vec::Zero(n);
}

}  // namespace rths::core
