#include "study/structure_config.h"

#include <gtest/gtest.h>

#include <fstream>
#include <optional>

#include "core/simulation.h"
#include "core/sparse_structure.h"
#include "core/stability.h"
#include "study/stability_config.h"
#include "study/study.h"

namespace rths::study {
namespace {

namespace fs = std::filesystem;

std::string motion() {
  return std::string(RTHS_DATA_DIR) + "/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2";
}

// Two storeys as matrices: K of storeys 3e6 and 2e6 N/m, floors 2000 and 1500 kg.
std::string two_storey_matrices(const std::string& substructuring, const std::string& cases = "") {
  return "name: \"m\" structure { matrices { mass { rows: 2 values: [2000, 0, 0, 1500] }"
         " stiffness { rows: 2 values: [5e6, -2e6, -2e6, 2e6] } } damping { modal_zeta: 0.05 } }"
         " motion { path: \"" +
         motion() + "\" duration: 4 } integrator { kind: EXPLICIT_NEWMARK dt: 0.002 } " +
         substructuring + " " + cases;
}

PreparedStudy prepare(const std::string& text) {
  return prepare_study(parse_study(text, "test"), fs::temp_directory_path());
}

template <typename F>
std::string error_of(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// A shear building of n floors in Matrix Market files under `dir` (diagonal M, tridiagonal K,
// storeys varying up the height), Rayleigh 5 %, floor 1 a third experimental, explicit Newmark.
std::string market_building(const fs::path& dir, int n, double duration) {
  fs::create_directories(dir);
  std::ofstream mass(dir / "mass.mtx"), stiffness(dir / "stiffness.mtx");
  mass << "%%MatrixMarket matrix coordinate real symmetric\n" << n << ' ' << n << ' ' << n << '\n';
  stiffness << "%%MatrixMarket matrix coordinate real symmetric\n"
            << n << ' ' << n << ' ' << 2 * n - 1 << '\n';
  stiffness.precision(17);
  const auto storey = [n](int i) { return 4e10 * (1.0 + 0.3 * (n - i) / n); };
  for (int i = 0; i < n; ++i) {
    mass << i + 1 << ' ' << i + 1 << ' ' << 1e5 * (1.0 + 0.1 * (i % 3)) << '\n';
    stiffness << i + 1 << ' ' << i + 1 << ' ' << storey(i) + (i + 1 < n ? storey(i + 1) : 0.0)
              << '\n';
    if (i > 0) stiffness << i + 1 << ' ' << i << ' ' << -storey(i) << '\n';
  }
  return "name: \"sparse\" structure { matrices { mass { file: \"mass.mtx\" } stiffness { file: "
         "\"stiffness.mtx\" } } damping { rayleigh { zeta: 0.05 mode_i: 1 mode_j: 2 } } }"
         " motion { path: \"" +
         motion() + "\" duration: " + std::to_string(duration) +
         " } integrator { kind: EXPLICIT_NEWMARK dt: 0.0009765625 }"
         " substructuring { experimental_dofs { dof: 1 stiffness: 1e10 } }"
         " cases { name: \"reference\" }";
}

// The same setup with its sparse matrices dropped: the dense path on the same M, C, K.
core::HybridSetup dense_copy(const core::HybridSetup& setup) {
  core::HybridSetup dense = setup;
  dense.model.sparse_mass = dense.model.sparse_damping = dense.model.sparse_stiffness = {};
  return dense;
}

TEST(StructureConfig, ALargeSparseModelIsHeldSparseAndRunsAsTheDensePathDoes) {
  for (int n : {120, 160}) {
    const fs::path dir = fs::temp_directory_path() / ("rths_sparse_study_" + std::to_string(n));
    const PreparedStudy p = prepare_study(parse_study(market_building(dir, n, 2.0), "t"), dir);
    ASSERT_TRUE(p.base.model.is_sparse()) << n;
    EXPECT_EQ(p.base.partition.numerical_matrix.nonZeros(), 3 * n - 2);
    const core::SimulationResult sparse = core::simulate(p.base, p.motion);
    const core::SimulationResult dense = core::simulate(dense_copy(p.base), p.motion);
    const double scale = dense.displacement.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    EXPECT_LE((sparse.displacement - dense.displacement).cwiseAbs().maxCoeff(), 1e-12 * scale);
    EXPECT_LE((sparse.measured_force - dense.measured_force).cwiseAbs().maxCoeff(),
              1e-12 * dense.measured_force.cwiseAbs().maxCoeff());
    fs::remove_all(dir);
  }
}

TEST(StructureConfig, ATwoThousandDofShearBuildingFromAMatrixMarketFileRuns) {
  const fs::path dir = fs::temp_directory_path() / "rths_sparse_study_2000";
  const PreparedStudy p = prepare_study(parse_study(market_building(dir, 2000, 0.25), "t"), dir);
  ASSERT_TRUE(p.base.model.is_sparse());
  EXPECT_EQ(p.base.partition.numerical_matrix.nonZeros(), 3 * 2000 - 2);
  const core::CriticalDelayCheck check = core::check_modal_critical_delay(
      p.base.model, p.base.partition.experimental_stiffness(), p.base.integrator, p.base.dt, 0.01);
  EXPECT_NE(check.assumed.find("the lowest 20 of 2000 modes"), std::string::npos) << check.assumed;
  const core::SimulationResult result = core::simulate(p.base, p.motion);
  EXPECT_EQ(result.steps(), p.motion.acceleration.size());
  EXPECT_FALSE(result.diverged);
  EXPECT_TRUE(result.displacement.allFinite());
  EXPECT_GT(result.displacement.cwiseAbs().maxCoeff(), 0.0);
  // The lowest modes of the model held sparse are those of its dense matrices.
  const core::Modes sparse = core::lowest_modes(p.base.model, 3);
  const core::Mat mass = p.base.model.mass, stiffness = p.base.model.stiffness;
  for (int i = 0; i < 3; ++i) {
    const core::Vec phi = sparse.shapes.col(i);
    const double rayleigh_quotient = phi.dot(stiffness * phi) / phi.dot(mass * phi);
    EXPECT_NEAR(std::sqrt(rayleigh_quotient), sparse.omega[i], 1e-9 * sparse.omega[i]);
    EXPECT_LE((stiffness * phi - rayleigh_quotient * (mass * phi)).norm(),
              1e-7 * (stiffness * phi).norm());
  }
  fs::remove_all(dir);
}

// Above kDenseSchemeMaxDofs the model is held sparse only, from the file to the split: the
// specimen's mass and dashpot leave M and C sparse, K_N is split sparse, omega_max is estimated
// once for the study, and the pre-run check and a run go through without an n x n matrix.
TEST(StructureConfig, ASparseOnlyModelIsSplitSparse) {
  const int n = 3000;
  const fs::path dir = fs::temp_directory_path() / "rths_sparse_only_3000";
  std::string text = market_building(dir, n, 0.05);
  const std::string grounded = "dof: 1 stiffness: 1e10";
  text.replace(text.find(grounded), grounded.size(),
               "dof: 2 stiffness: 1e10 mass: 1000 damping: 500");
  const PreparedStudy p = prepare_study(parse_study(text, "t"), dir);
  const core::StructuralModel& model = p.base.model;
  ASSERT_TRUE(model.is_sparse());
  EXPECT_EQ(model.mass.size(), 0);
  EXPECT_EQ(model.damping.size(), 0);
  EXPECT_EQ(model.sparse_mass.coeff(1, 1), 1.1e5 - 1000.0);
  EXPECT_EQ(model.sparse_mass.nonZeros(), n);
  const double storey = [n](int i) { return 4e10 * (1.0 + 0.3 * (n - i) / n); }(1);
  EXPECT_EQ(p.base.partition.numerical_matrix.coeff(1, 1),
            model.sparse_stiffness.coeff(1, 1) - 1e10);
  EXPECT_EQ(p.base.partition.numerical_matrix.coeff(1, 0), -storey);
  ASSERT_GT(model.known_max_omega, 0.0);
  core::StructuralModel fresh = model;
  fresh.known_max_omega = 0.0;
  EXPECT_EQ(core::max_omega(fresh), model.known_max_omega);
  const std::optional<core::CriticalDelayCheck> check = check_lag_critical_delay(p, 0.002);
  ASSERT_TRUE(check.has_value());
  EXPECT_NE(check->assumed.find("in the lowest 20 of 3000 modes"), std::string::npos)
      << check->assumed;
  const core::SimulationResult result = core::simulate(p.base, p.motion);
  EXPECT_FALSE(result.diverged);
  EXPECT_GT(result.displacement.cwiseAbs().maxCoeff(), 0.0);
  fs::remove_all(dir);
}

TEST(StructureConfig, ModalDampingOnAThousandDofModelStaysSparseAsALowRankTerm) {
  const int n = 1200;
  const fs::path dir = fs::temp_directory_path() / "rths_sparse_modal_1200";
  std::string text = market_building(dir, n, 0.1);
  const std::string rayleigh = "rayleigh { zeta: 0.05 mode_i: 1 mode_j: 2 }";
  text.replace(text.find(rayleigh), rayleigh.size(), "modal_zeta: 0.05");
  const PreparedStudy p = prepare_study(parse_study(text, "t"), dir);
  const core::StructuralModel& model = p.base.model;
  ASSERT_TRUE(model.is_sparse());
  const core::LowRankDamping& low = model.low_rank_damping;
  ASSERT_FALSE(low.empty());
  EXPECT_EQ(low.basis.rows(), n);
  EXPECT_GE(low.basis.cols(), core::kModalMinModes);
  EXPECT_LE(low.basis.cols(), core::kModalMaxModes);
  EXPECT_EQ(low.coefficients.size(), low.basis.cols());
  EXPECT_LE(model.sparse_damping.nonZeros(), 3 * n - 2);  // a1 K: C's sparse part, no fill
  bool stated = false;
  for (const std::string& line : p.warnings) stated = stated || line == low.statement;
  EXPECT_TRUE(stated) << "the modes kept are printed before the run";
  EXPECT_NE(low.statement.find("never formed dense"), std::string::npos) << low.statement;
  const core::SimulationResult result = core::simulate(p.base, p.motion);
  EXPECT_FALSE(result.diverged);
  EXPECT_TRUE(result.displacement.allFinite());
  EXPECT_GT(result.displacement.cwiseAbs().maxCoeff(), 0.0);
  fs::remove_all(dir);
}

TEST(StructureConfig, SplitTakesTheSpecimensMassDampingAndStiffnessOutOfTheNumericalPart) {
  const PreparedStudy p = prepare(two_storey_matrices(
      "substructuring { experimental_dofs { dof: 2 mass: 100 stiffness: 1e6 damping: 500 } }"));
  const core::StructuralModel whole = make_structure(p.config.structure());
  EXPECT_EQ(p.base.model.mass(1, 1), 1400.0);
  EXPECT_EQ(p.base.model.mass(0, 0), 2000.0);
  EXPECT_DOUBLE_EQ(p.base.model.damping(1, 1), whole.damping(1, 1) - 500.0);
  EXPECT_EQ(p.base.model.stiffness, whole.stiffness);  // the integrators' K0 stays whole
  EXPECT_EQ(p.base.partition.numerical_matrix.coeff(1, 1), 1e6);
  EXPECT_EQ(p.base.partition.numerical_matrix.coeff(0, 1), -2e6);
  ASSERT_EQ(p.base.partition.actuator_storeys, std::vector<int>{1});
  EXPECT_TRUE(p.base.partition.by_dofs);
  EXPECT_EQ(p.base.partition.experimental_stiffness()(1, 1), 1e6);
  EXPECT_EQ(p.base.partition.experimental_stiffness()(0, 1), 0.0);
}

TEST(StructureConfig, BadExperimentalDofsAreRefusedNamingTheField) {
  EXPECT_NE(error_of([] {
              prepare(two_storey_matrices(
                  "substructuring { experimental_dofs { dof: 3 stiffness: 1e6 } }"));
            }).find("substructuring.experimental_dofs[0].dof: 3 is outside 1..2"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              prepare(two_storey_matrices(
                  "substructuring { experimental_dofs { dof: 1 stiffness: 1e6 } "
                  "experimental_dofs { dof: 1 stiffness: 1e6 } }"));
            }).find("experimental_dofs[1].dof: 1 is listed twice"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              prepare(two_storey_matrices(
                  "substructuring { experimental_dofs { dof: 2 stiffness: 3e6 } }"));
            }).find("experimental_dofs[0].stiffness: 3e+06 N/m must be in (0, K(2, 2) = 2e+06]"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              prepare(two_storey_matrices(
                  "substructuring { experimental_dofs { dof: 2 stiffness: 1e6 mass: 1500 } }"));
            }).find("experimental_dofs[0].mass"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              prepare(two_storey_matrices("substructuring { experimental_fraction: 0.5 }"));
            }).find("split at experimental_dofs"),
            std::string::npos);
}

TEST(StructureConfig, DampingMatrixAndRatiosAreExclusive) {
  const std::string both =
      "name: \"m\" structure { matrices { mass { rows: 1 values: 1 } stiffness { rows: 1 values: 1 "
      "}"
      " damping { rows: 1 values: 0.1 } } damping { modal_zeta: 0.05 } }";
  EXPECT_NE(error_of([&] { make_structure(parse_study(both, "t").structure()); }).find("not both"),
            std::string::npos);
}

// A shear building given as matrices and split at DOF 1 is the shear building split at storey 1
// (the storey between the ground and floor 1): the same response up to rounding.
TEST(StructureConfig, ShearBuildingAsMatricesRunsAsTheShearBuilding) {
  const std::string cases = "cases { name: \"lag\" delay { shift { delay: 0.006 } } }";
  const PreparedStudy matrices = prepare(
      two_storey_matrices("substructuring { experimental_dofs { dof: 1 stiffness: 3e6 } }", cases));
  const PreparedStudy storeys = prepare(
      "name: \"s\" structure { shear_building { storey_mass: [2000, 1500] storey_stiffness: [3e6, "
      "2e6] }"
      " damping { modal_zeta: 0.05 } } motion { path: \"" +
      motion() +
      "\" duration: 4 }"
      " integrator { kind: EXPLICIT_NEWMARK dt: 0.002 } substructuring { experimental_storeys: [1] "
      "} " +
      cases);
  const core::SimulationResult a =
      core::simulate(setup_for_case(matrices, matrices.config.cases(0)), matrices.motion);
  const core::SimulationResult b =
      core::simulate(setup_for_case(storeys, storeys.config.cases(0)), storeys.motion);
  ASSERT_EQ(a.steps(), b.steps());
  const double peak = b.displacement.cwiseAbs().maxCoeff();
  EXPECT_GT(peak, 1e-4);
  EXPECT_LT((a.displacement - b.displacement).cwiseAbs().maxCoeff(), 1e-9 * peak);
  EXPECT_LT((a.measured_force - b.measured_force).cwiseAbs().maxCoeff(), 1e-6);
}

// Without lag, a specimen of stiffness only and the numerical rest sum to the whole structure:
// the hybrid run equals the 20-DOF frame integrated whole, for every integrator.
TEST(StructureConfig, UndelayedSplitOfTheTwentyDofFrameEqualsTheWholeFrame) {
  const std::string frame =
      "name: \"f\" structure { matrices { mass { file: \"matrices/frame20_mass.mtx\" }"
      " stiffness { file: \"matrices/frame20_stiffness.mtx\" } } damping { modal_zeta: 0.05 } }"
      " motion { path: \"" +
      motion() + "\" duration: 3 } ";
  for (const char* kind : {"EXPLICIT_NEWMARK", "CENTRAL_DIFFERENCE", "CHEN_RICLES",
                           "NEWMARK_AVERAGE_ACCELERATION", "ALPHA_OS", "KR_ALPHA"}) {
    const std::string integrator = std::string("integrator { kind: ") + kind + " dt: 0.002 } ";
    const fs::path configs = fs::path(RTHS_SOURCE_DIR) / "configs";
    const PreparedStudy split = prepare_study(
        parse_study(
            frame + integrator + "substructuring { experimental_dofs { dof: 1 stiffness: 2e6 } }",
            "t"),
        configs);
    const PreparedStudy whole = prepare_study(parse_study(frame + integrator, "t"), configs);
    EXPECT_TRUE(whole.base.partition.actuator_storeys.empty());
    const core::SimulationResult a = core::simulate(split.base, split.motion);
    const core::SimulationResult b = core::simulate(whole.base, whole.motion);
    const double peak = b.displacement.cwiseAbs().maxCoeff();
    EXPECT_GT(peak, 1e-3) << kind;
    EXPECT_LT((a.displacement - b.displacement).cwiseAbs().maxCoeff(), 1e-9 * peak) << kind;
  }
}

TEST(StructureConfig, AnElementBetweenTwoDofsTakesItsRowOutOfTheNumericalPart) {
  const PreparedStudy p = prepare(two_storey_matrices(
      "substructuring { experimental_dofs { dof: 2 from_dof: 1 mass: 100 stiffness: 1e6 "
      "damping: 500 } }"));
  const core::StructuralModel whole = make_structure(p.config.structure());
  const core::HybridPartition& partition = p.base.partition;
  ASSERT_EQ(partition.elements.size(), 1u);
  EXPECT_EQ(partition.actuator_storeys, std::vector<int>{2});
  EXPECT_EQ(partition.numerical_matrix.coeff(0, 0), 4e6);
  EXPECT_EQ(partition.numerical_matrix.coeff(0, 1), -1e6);
  EXPECT_EQ(partition.numerical_matrix.coeff(1, 1), 1e6);
  // m b b^T and c b b^T leave the numerical part too.
  EXPECT_EQ(p.base.model.mass(0, 0), 1900.0);
  EXPECT_EQ(p.base.model.mass(0, 1), 100.0);
  EXPECT_EQ(p.base.model.mass(1, 1), 1400.0);
  EXPECT_DOUBLE_EQ(p.base.model.damping(0, 1), whole.damping(0, 1) + 500.0);
  EXPECT_TRUE(p.warnings.empty());
}

TEST(StructureConfig, ABraceAndAnInfluenceRowAreTheSameElement) {
  const PreparedStudy brace = prepare(two_storey_matrices(
      "substructuring { experimental_dofs { dof: 2 from_dof: 1 angle_degrees: 60 stiffness: 4e6 "
      "} }"));
  const PreparedStudy row = prepare(two_storey_matrices(
      "substructuring { experimental_dofs { influence: [-0.5, 0.5] stiffness: 4e6 } }"));
  EXPECT_LE((core::Mat(brace.base.partition.numerical_matrix) -
             core::Mat(row.base.partition.numerical_matrix))
                .cwiseAbs()
                .maxCoeff(),
            1e-6);
  EXPECT_NEAR(row.base.partition.numerical_matrix.coeff(1, 1), 1e6, 1e-6);
}

TEST(StructureConfig, BadElementsAreRefusedNamingTheField) {
  const auto error = [](const std::string& spec) {
    return error_of([&] {
      prepare(two_storey_matrices("substructuring { experimental_dofs { " + spec + " } }"));
    });
  };
  EXPECT_NE(error("dof: 2 from_dof: 2 stiffness: 1e6").find("from_dof: an element joins two"),
            std::string::npos);
  EXPECT_NE(error("dof: 2 from_dof: 4 stiffness: 1e6").find("from_dof: 4 is outside 1..2"),
            std::string::npos);
  EXPECT_NE(error("dof: 2 from_dof: 1 angle_degrees: 90 stiffness: 1e6").find("angle_degrees"),
            std::string::npos);
  EXPECT_NE(error("influence: [1] stiffness: 1e6").find("1 entries for 2 DOFs"), std::string::npos);
  EXPECT_NE(error("dof: 1 influence: [1, 0] stiffness: 1e6").find("not both"), std::string::npos);
  EXPECT_NE(error("influence: [0, 0] stiffness: 1e6").find("every entry is 0"), std::string::npos);
  EXPECT_NE(error("dof: 2 from_dof: 1 stiffness: 3e6").find("stiffer than the structure"),
            std::string::npos);
}

TEST(StructureConfig, AGroundedSpecimenThatMeansAStoreyIsWarnedOfWithBothFractions) {
  // DOF 2 of the two-storey frame is tied to the ground by nothing of its own: a grounded
  // specimen there is most likely storey 2.
  const PreparedStudy p = prepare(
      two_storey_matrices("substructuring { experimental_dofs { dof: 2 stiffness: 1e6 } }"));
  ASSERT_EQ(p.warnings.size(), 1u);
  const std::string& warning = p.warnings[0];
  EXPECT_NE(warning.find("experimental_dofs[0]"), std::string::npos) << warning;
  EXPECT_NE(warning.find("by only 0 N/m"), std::string::npos) << warning;
  EXPECT_NE(warning.find("experimental fraction of"), std::string::npos) << warning;
  EXPECT_NE(warning.find("from_dof: 1"), std::string::npos) << warning;
  // DOF 1 carries the first storey to the ground: no warning.
  EXPECT_TRUE(
      prepare(two_storey_matrices("substructuring { experimental_dofs { dof: 1 stiffness: 2e6 } }"))
          .warnings.empty());
}

TEST(StructureConfig, AShearBuildingTakesElementsAsItsMatrices) {
  const std::string building =
      "name: \"s\" structure { shear_building { storey_mass: [2000, 1500] storey_stiffness: "
      "[3e6, 2e6] } damping { modal_zeta: 0.05 } } motion { path: \"" +
      motion() + "\" duration: 4 } integrator { kind: EXPLICIT_NEWMARK dt: 0.002 } ";
  const PreparedStudy p = prepare(
      building + "substructuring { experimental_dofs { dof: 2 from_dof: 1 stiffness: 1e6 } }");
  EXPECT_TRUE(p.base.partition.by_dofs);
  EXPECT_EQ(p.base.partition.numerical_matrix.coeff(1, 1), 1e6);
  EXPECT_NE(error_of([&] {
              prepare(building +
                      "substructuring { model { bilinear { yield_displacement: 0.01 } } "
                      "experimental_dofs { dof: 2 from_dof: 1 stiffness: 1e6 } }");
            }).find("needs a linear storey model"),
            std::string::npos);
}

}  // namespace
}  // namespace rths::study
