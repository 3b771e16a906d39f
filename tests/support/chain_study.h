#pragma once
// Test support: a lab-sized model as a lab's files give it. A chain of n floors (1e5 kg each,
// storeys of 4e10/3 N/m: not a power of two, so that any altered bit of a value shows) written as
// Matrix Market symmetric coordinate files (mass.mtx diagonal, stiffness.mtx tridiagonal, lower
// triangle) into `folder`, and a study of it naming them: modal damping 5 %, floor 1
// experimental (1e10 N/m), explicit Newmark at 1/1024 s over `seconds` of the Imperial Valley
// record, one case `reference`. Its M and K hold n + 3n - 2 nonzeros.

#include <filesystem>
#include <fstream>
#include <string>

#include "study/study.h"

namespace rths::test {

inline config::Study chain_study(int n, const std::filesystem::path& folder, double seconds = 0.1) {
  std::ofstream mass(folder / "mass.mtx"), stiffness(folder / "stiffness.mtx");
  mass << "%%MatrixMarket matrix coordinate real symmetric\n" << n << " " << n << " " << n << "\n";
  stiffness.precision(17);
  stiffness << "%%MatrixMarket matrix coordinate real symmetric\n"
            << n << " " << n << " " << 2 * n - 1 << "\n";
  const double k = 4e10 / 3;
  for (int i = 1; i <= n; ++i) {
    mass << i << " " << i << " 1e5\n";
    stiffness << i << " " << i << " " << (i < n ? 2 * k : k) << "\n";
    if (i > 1) stiffness << i << " " << i - 1 << " " << -k << "\n";
  }
  const std::filesystem::path motion =
      std::filesystem::path(RTHS_SOURCE_DIR) / "data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2";
  return study::parse_study(
      "structure { matrices { mass { file: \"mass.mtx\" } stiffness { file: \"stiffness.mtx\" } }"
      " damping { modal_zeta: 0.05 } }\n"
      "motion { path: \"" +
          motion.string() + "\" duration: " + std::to_string(seconds) +
          " }\n"
          "integrator { kind: EXPLICIT_NEWMARK dt: 0.0009765625 }\n"
          "substructuring { experimental_dofs { dof: 1 stiffness: 1e10 } }\n"
          "cases { name: \"reference\" }\n",
      "chain.textproto");
}

}  // namespace rths::test
