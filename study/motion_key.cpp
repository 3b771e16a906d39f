#include "study/motion_key.h"

#include <vector>

#include "util/sha256.h"

namespace rths::study {

std::string motion_key(const core::GroundMotion& motion) {
  std::vector<double> values{motion.dt};
  values.insert(values.end(), motion.acceleration.begin(), motion.acceleration.end());
  return util::bytes_sha256(values.data(), values.size() * sizeof(double));
}

}  // namespace rths::study
