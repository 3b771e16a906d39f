#pragma once
// Shared by the runtime tests: small studies written as config text, and helpers to run them.

#include <filesystem>
#include <string>

#include "core/study.h"

namespace rths::test {

inline std::string motion_path() {
  return std::string(RTHS_SHARED_DATA_DIR) + "/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2";
}

// Two storeys, bilinear storeys, storey 2 experimental, the 1979 record truncated.
// `cases` and `deployment` are config text appended as is.
inline const char* kStorey2Bilinear =
    "substructuring { experimental_storeys: [2] model { bilinear { yield_displacement: 0.004 "
    "post_yield_ratio: 0.1 } } }";
inline std::string two_storey_study(double duration, const std::string& cases,
                                    const std::string& deployment,
                                    const std::string& substructuring = kStorey2Bilinear) {
  return "name: \"two_storey\"\n"
         "structure { shear_building { storey_mass: [2000, 1500] storey_stiffness: [3.0e6, "
         "2.0e6] } damping { modal_zeta: 0.05 } }\n"
         "motion { path: \"" + motion_path() + "\" duration: " + std::to_string(duration) +
         " scale: 2 }\n"
         "integrator { kind: EXPLICIT_NEWMARK dt: 0.002 }\n" +
         substructuring + "\n" + cases + "\n" + deployment;
}

// The paper's frame (configs/paper_frame.textproto) truncated to `duration` seconds.
inline std::string paper_frame_study(double duration, const std::string& deployment) {
  return "name: \"paper_frame\"\n"
         "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }\n"
         "motion { path: \"" + motion_path() + "\" duration: " + std::to_string(duration) + " }\n"
         "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
         "substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }\n"
         "cases { name: \"reference\" }\n"
         "cases { name: \"lag_shift_14ms\" delay { shift { delay: 0.014 } } }\n"
         "cases { name: \"jitter\" delay { jitter { mean_delay: 0.01 std_dev: 0.003 seed: 5 } } }\n" +
         deployment;
}

inline core::PreparedStudy prepare(const std::string& text) {
  return core::prepare_study(core::parse_study(text, "test"), std::filesystem::temp_directory_path());
}

}  // namespace rths::test
