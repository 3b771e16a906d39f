#include "core/sparse_structure.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/structure.h"

namespace rths::core {
namespace {

// A shear building whose storeys differ, so no two modes coincide.
StructuralModel building(int n) {
  std::vector<double> mass, stiffness;
  for (int i = 0; i < n; ++i) {
    mass.push_back(1e4 * (1.0 + 0.3 * std::sin(i)));
    stiffness.push_back(2e7 * (1.0 + 0.5 * std::cos(0.7 * i)));
  }
  return make_shear_building(mass, stiffness);
}

TEST(SparseStructure, TheFillRuleHoldsLargeSparseModelsSparseAndKeepsTheRestDense) {
  EXPECT_TRUE(prefer_sparse(100, 300));
  EXPECT_FALSE(prefer_sparse(99, 300));         // small: dense, bit-identical to before
  EXPECT_FALSE(prefer_sparse(300, 300 * 300));  // a condensed (full) model
  EXPECT_FALSE(prefer_sparse(300, 300 * 16));   // above 5 % fill
  StructuralModel large = building(200);
  hold_sparse_if_sparse(large);
  EXPECT_TRUE(large.is_sparse());
  EXPECT_EQ(large.sparse_stiffness.nonZeros(), 3 * 200 - 2);
  EXPECT_EQ(Mat(large.sparse_stiffness), large.stiffness);
  StructuralModel small = building(50);
  hold_sparse_if_sparse(small);
  EXPECT_FALSE(small.is_sparse());
  large.damping = modal_damping(large.mass, large.stiffness, 0.05);  // full C
  hold_sparse_if_sparse(large);
  EXPECT_FALSE(large.is_sparse());
}

TEST(SparseStructure, LowestModesMatchTheDenseAnalysis) {
  StructuralModel model = building(400);
  const Modes dense = modal_analysis(model.mass, model.stiffness);
  hold_sparse_if_sparse(model);
  ASSERT_TRUE(model.is_sparse());
  const Modes sparse = lowest_modes(model, 6);
  ASSERT_EQ(sparse.omega.size(), 6);
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(sparse.omega[i], dense.omega[i], 1e-9 * dense.omega[i]) << "mode " << i + 1;
    // Mass-normalised shapes equal up to sign.
    const double sign = sparse.shapes.col(i).dot(dense.shapes.col(i)) > 0 ? 1.0 : -1.0;
    EXPECT_LE((sign * sparse.shapes.col(i) - dense.shapes.col(i)).cwiseAbs().maxCoeff(),
              1e-7 * dense.shapes.col(i).cwiseAbs().maxCoeff())
        << "mode " << i + 1;
  }
}

TEST(SparseStructure, HighestOmegaMatchesTheDenseOne) {
  StructuralModel model = building(300);
  const double dense = modal_analysis(model.mass, model.stiffness).omega.maxCoeff();
  hold_sparse_if_sparse(model);
  const double sparse = max_omega(model);
  EXPECT_NEAR(sparse, dense, 1e-8 * dense);
}

TEST(SparseStructure, DenseModelsKeepTheirDenseModesBitForBit) {
  const StructuralModel model = building(20);
  const Modes direct = modal_analysis(model.mass, model.stiffness);
  const Modes through = lowest_modes(model, 3);
  EXPECT_EQ(through.omega, direct.omega);
  EXPECT_EQ(max_omega(model), direct.omega.maxCoeff());
}

TEST(SparseStructure, RayleighDampingEqualsTheDenseOne) {
  StructuralModel model = building(150);
  const Mat dense = rayleigh_damping(model.mass, model.stiffness, 0.05, 1, 3);
  hold_sparse_if_sparse(model);
  sparse_rayleigh_damping(model, 0.05, 1, 3);
  EXPECT_LE((model.damping - dense).cwiseAbs().maxCoeff(), 1e-9 * dense.cwiseAbs().maxCoeff());
  EXPECT_LE((Mat(model.sparse_damping) - dense).cwiseAbs().maxCoeff(),
            1e-9 * dense.cwiseAbs().maxCoeff());
  EXPECT_THROW(sparse_rayleigh_damping(model, 0.05, 2, 2), std::invalid_argument);
}

// C as one dense matrix: the sparse part plus B diag(c) B^T (formed here only to compare).
Mat whole_damping(const StructuralModel& model) {
  const LowRankDamping& low = model.low_rank_damping;
  return Mat(model.sparse_damping) +
         low.basis * low.coefficients.asDiagonal() * low.basis.transpose();
}

TEST(SparseStructure, ModalDampingThroughTheLowestModesEqualsTheDenseOneOnTheModesKept) {
  StructuralModel model = building(150);
  const Mat dense = modal_damping(model.mass, model.stiffness, 0.05);
  const Modes modes = modal_analysis(model.mass, model.stiffness);
  hold_sparse_if_sparse(model);
  ASSERT_TRUE(model.is_sparse());
  const SparseModalDamping chosen = sparse_modal_damping(model, 0.05);
  const int m = chosen.modes;
  ASSERT_GE(m, kModalMinModes);
  ASSERT_LT(m, 150);
  EXPECT_EQ(model.low_rank_damping.basis.cols(), m);  // factors, rank m, not n x n
  EXPECT_TRUE(chosen.mass_share >= kModalMassShare || m == kModalMaxModes) << chosen.mass_share;
  EXPECT_EQ(model.sparse_damping.nonZeros(), model.sparse_stiffness.nonZeros());  // a1 K
  const Mat c = whole_damping(model);
  // C phi_i = 2 zeta omega_i M phi_i for every mode kept, as the dense modal C gives it.
  for (int i = 0; i < m; ++i) {
    const Vec expected = dense * modes.shapes.col(i);
    EXPECT_LE((c * modes.shapes.col(i) - expected).cwiseAbs().maxCoeff(),
              1e-7 * expected.cwiseAbs().maxCoeff())
        << "mode " << i + 1;
    EXPECT_NEAR(damping_quadratic(model, modes.shapes.col(i)) / (2.0 * modes.omega[i]), 0.05, 1e-8)
        << "mode " << i + 1;
  }
  // The modes above: stiffness-proportional, zeta omega_j / omega_{m+1} >= zeta, as stated.
  for (int j = m; j < 150; j += 13) {
    const double zeta_j = damping_quadratic(model, modes.shapes.col(j)) / (2.0 * modes.omega[j]);
    EXPECT_NEAR(zeta_j, 0.05 * modes.omega[j] / modes.omega[m], 1e-6 * zeta_j) << "mode " << j + 1;
    EXPECT_GE(zeta_j, 0.05 * (1 - 1e-6)) << "mode " << j + 1;
  }
  // Phi^T C Phi over the kept modes: diag(2 zeta omega), the low-rank term in it.
  const Mat in_modes = damping_in_modes(model, modes.shapes.leftCols(m));
  const Vec diagonal = 2.0 * 0.05 * modes.omega.head(m);
  EXPECT_LE((in_modes - Mat(diagonal.asDiagonal())).cwiseAbs().maxCoeff(),
            1e-8 * diagonal.maxCoeff());
  EXPECT_NE(chosen.text.find("lowest " + std::to_string(m) + " modes"), std::string::npos)
      << chosen.text;
  EXPECT_EQ(model.low_rank_damping.statement, chosen.text);
  hold_sparse_if_sparse(model);  // C's sparse part a1 K fills no more than K: still sparse
  EXPECT_TRUE(model.is_sparse());
}

TEST(SparseStructure, ModalDampingRefusesADenseModelAndARatioOutOfRange) {
  StructuralModel dense = building(20);
  EXPECT_THROW(sparse_modal_damping(dense, 0.05), std::invalid_argument);
  StructuralModel model = building(120);
  hold_sparse_if_sparse(model);
  EXPECT_THROW(sparse_modal_damping(model, 0.0), std::invalid_argument);
  EXPECT_THROW(sparse_modal_damping(model, 1.5), std::invalid_argument);
}

TEST(SparseStructure, DefinitenessByInertia) {
  StructuralModel model = building(120);
  hold_sparse_if_sparse(model);
  EXPECT_FALSE(check_sparse_definite(model.sparse_mass, true));
  EXPECT_FALSE(check_sparse_definite(model.sparse_stiffness, true));
  SparseMat indefinite = model.sparse_stiffness;
  indefinite.coeffRef(5, 5) = -1e7;
  const auto why = check_sparse_definite(indefinite, false);
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("not positive semi-definite"), std::string::npos) << *why;
  // A free-floating chain (no ground spring): singular, semi-definite, not definite.
  SparseMat floating = model.sparse_stiffness;
  floating.coeffRef(0, 0) -= model.storey_stiffness[0];
  EXPECT_FALSE(check_sparse_definite(floating, false));
  EXPECT_TRUE(check_sparse_definite(floating, true));
}

}  // namespace
}  // namespace rths::core
