#include "study/restoring_force_config.h"

#include <memory>
#include <stdexcept>

#include "core/restoring_force.h"

namespace rths::study {

core::StoreyModelFactory make_storey_factory(const config::RestoringForce& model) {
  switch (model.kind_case()) {
    case config::RestoringForce::kBilinear: {
      const double uy = model.bilinear().yield_displacement();
      const double b = model.bilinear().post_yield_ratio();
      if (!(uy > 0)) throw std::invalid_argument("bilinear.yield_displacement must be > 0 m");
      if (!(b >= 0 && b <= 1))
        throw std::invalid_argument("bilinear.post_yield_ratio must be in [0, 1]");
      return [uy, b](double k) { return std::make_unique<core::BilinearKinematic>(k, uy, b); };
    }
    case config::RestoringForce::kBoucWen: {
      const auto& bw = model.bouc_wen();
      if (!(bw.yield_displacement() > 0))
        throw std::invalid_argument("bouc_wen.yield_displacement must be > 0 m");
      const double n = bw.n() == 0 ? 1.0 : bw.n();
      const double beta = bw.beta() == 0 ? 0.5 : bw.beta();
      const double uy = bw.yield_displacement(), alpha = bw.alpha();
      return [=](double k) { return std::make_unique<core::BoucWen>(k, uy, alpha, n, beta); };
    }
    default: return core::linear_factory();
  }
}

}  // namespace rths::study
