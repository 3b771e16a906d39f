#pragma once
// The site's study for the paper's frame (T = 0.5 s, m = 1000 kg, 5 %, a third of the storey the
// specimen): the specimen column alone (every storey experimental), served to the client's model
// of the rest. Shared by the OpenSees-site tests.

#include <cmath>
#include <cstdio>
#include <string>

#include "study/study.h"

namespace rths::test {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kMass = 1000.0;
inline constexpr double kFraction = 0.3333333333333333;
// The paper frame's storey stiffness and its parts, as core computes them (k = m omega^2).
inline double storey_stiffness() {
  const double omega = 2 * kPi / 0.5;
  return kMass * omega * omega;
}
inline double specimen_stiffness() { return kFraction * storey_stiffness(); }
inline double numerical_stiffness() { return (1.0 - kFraction) * storey_stiffness(); }
inline double frame_damping() { return 2 * 0.05 * (2 * kPi / 0.5) * kMass; }

inline std::string motion_file() {
  return std::string(RTHS_DATA_DIR) + "/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2";
}

inline std::string exact(double x) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", x);
  return text;
}

// `deployment` is appended as is (config text).
inline std::string site_study(double duration, const std::string& deployment) {
  return "name: \"opensees_site\"\n"
         "structure { shear_building { storey_mass: [1000] storey_stiffness: [" +
         exact(specimen_stiffness()) +
         "] } }\n"
         "motion { path: \"" +
         motion_file() + "\" duration: " + std::to_string(duration) +
         " }\n"
         "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
         "substructuring { experimental_fraction: 1 model { linear {} } }\n"
         "cases { name: \"reference\" }\n"
         "cases { name: \"lag_shift_14ms\" delay { shift { delay: 0.014 } } }\n"
         "deployment { opensees { basic_dofs: 2 transformation: [-1, 1] } " +
         deployment + " }\n";
}

// The ground motion of the study at its dt (m/s^2).
inline std::vector<double> ground_motion(const std::string& study_text) {
  return study::prepare_study(study::parse_study(study_text, "test"), "/").motion.acceleration;
}

}  // namespace rths::test
