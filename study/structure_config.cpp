#include "study/structure_config.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>

#include "core/number_text.h"
#include "core/sparse_structure.h"
#include "study/ranges.h"
#include "study/restoring_force_config.h"
#include "study/structure_io.h"
#include "study/text_columns.h"

namespace rths::study {
namespace {

// Above this many DOFs the warning of a grounded specimen that means a storey leaves out the
// fractions (they need the dense modal analysis).
constexpr int kMaxDofsForFractionHint = 500;

[[noreturn]] void fail(const std::string& field, const std::string& problem) {
  throw std::invalid_argument(field + ": " + problem);
}

void apply_damping(core::StructuralModel& model, const config::Damping& damping, bool has_matrix) {
  const bool ratio = damping.has_rayleigh() || damping.modal_zeta() > 0;
  if (has_matrix && ratio)
    fail("structure.damping",
         "structure.matrices.damping is given: give the matrix or the ratios, not both");
  if (damping.has_rayleigh() && model.is_sparse()) {
    const auto& r = damping.rayleigh();
    core::sparse_rayleigh_damping(model, r.zeta(), r.mode_i() == 0 ? 1 : r.mode_i(),
                                  r.mode_j() == 0 ? 2 : r.mode_j());
  } else if (damping.has_rayleigh()) {
    const auto& r = damping.rayleigh();
    model.damping =
        core::rayleigh_damping(model.mass, model.stiffness, r.zeta(),
                               r.mode_i() == 0 ? 1 : r.mode_i(), r.mode_j() == 0 ? 2 : r.mode_j());
  } else if (!has_matrix && model.is_sparse() && damping.modal_zeta() == 0) {
    model.damping.setZero();  // no modes needed for C = 0
    model.sparse_damping.setZero();
  } else if (!has_matrix && model.is_sparse()) {
    // Through the lowest modes, kept as factors: a full C would make the model dense (seconds
    // of set-up and n^2 a step at 1,000 DOFs); the choice is stated in the model's statement.
    core::sparse_modal_damping(model, damping.modal_zeta());
  } else if (!has_matrix) {
    model.damping = core::modal_damping(model.mass, model.stiffness, damping.modal_zeta());
  }
}

// The specimen of experimental_dofs[i] and the mass and damping it takes from the numerical part.
struct Specimen {
  double mass = 0.0, damping = 0.0;
  std::unique_ptr<core::RestoringForceModel> model;
};

// The row of an element (empty: grounded at `dof`), checked: DOFs in 1..n, |angle| < 90 degrees,
// an influence row of n finite entries with nothing else set.
core::ElementRow element_row(const config::ExperimentalDof& spec, int n, const std::string& field) {
  core::ElementRow row;
  if (!spec.influence().empty()) {
    if (spec.dof() != 0 || spec.from_dof() != 0 || spec.angle_degrees() != 0)
      fail(field + ".influence", "give the influence row or dof/from_dof/angle_degrees, not both");
    if (spec.influence_size() != n)
      fail(field + ".influence",
           std::to_string(spec.influence_size()) + " entries for " + std::to_string(n) + " DOFs");
    for (int j = 0; j < n; ++j) {
      if (!std::isfinite(spec.influence(j)))
        fail(field + ".influence", "entry " + std::to_string(j + 1) + " is not finite");
      if (spec.influence(j) != 0) row.terms.emplace_back(j, spec.influence(j));
    }
    if (row.terms.empty()) fail(field + ".influence", "every entry is 0");
    return row;
  }
  if (spec.dof() < 1 || spec.dof() > n)
    fail(field + ".dof", std::to_string(spec.dof()) + " is outside 1.." + std::to_string(n));
  const double angle = spec.angle_degrees();
  if (!(std::isfinite(angle) && std::abs(angle) < 90))
    fail(field + ".angle_degrees", core::format_number(angle) + " must be in (-90, 90)");
  if (spec.from_dof() != 0 && (spec.from_dof() < 1 || spec.from_dof() > n))
    fail(field + ".from_dof", std::to_string(spec.from_dof()) + " is outside 1.." +
                                  std::to_string(n) + " (0 = the ground)");
  if (spec.from_dof() == spec.dof())
    fail(field + ".from_dof",
         "an element joins two different DOFs (both are " + std::to_string(spec.dof()) + ")");
  if (spec.from_dof() == 0 && angle == 0) return row;  // grounded
  const double c = std::cos(angle * std::numbers::pi / 180.0);
  row.terms.emplace_back(spec.dof() - 1, c);
  if (spec.from_dof() != 0) row.terms.emplace_back(spec.from_dof() - 1, -c);
  return row;
}

// Entry (i, j) of a matrix from whichever form the model holds (dense, or sparse only).
double entry(const core::Mat& dense, const core::SparseMat& sparse, int i, int j) {
  return dense.rows() > std::max(i, j) ? dense(i, j) : sparse.coeff(i, j);
}

Specimen make_specimen(const config::ExperimentalDof& spec, const core::StructuralModel& model,
                       const core::ElementRow& row, const std::string& field, double servo_period) {
  if (row.terms.empty()) {
    const int d = spec.dof() - 1;
    const double k_dd = entry(model.stiffness, model.sparse_stiffness, d, d);
    const double m_dd = entry(model.mass, model.sparse_mass, d, d);
    if (!(spec.stiffness() > 0 && spec.stiffness() <= k_dd))
      fail(field + ".stiffness", core::format_number(spec.stiffness()) + " N/m must be in (0, K(" +
                                     std::to_string(d + 1) + ", " + std::to_string(d + 1) +
                                     ") = " + core::format_number(k_dd) + "]");
    if (!(spec.mass() >= 0 && spec.mass() < m_dd))
      fail(field + ".mass", core::format_number(spec.mass()) + " kg must be in [0, M(" +
                                std::to_string(d + 1) + ", " + std::to_string(d + 1) +
                                ") = " + core::format_number(m_dd) + ")");
  } else {
    if (!(spec.stiffness() > 0 && std::isfinite(spec.stiffness())))
      fail(field + ".stiffness", core::format_number(spec.stiffness()) + " N/m must be > 0");
    if (!(spec.mass() >= 0 && std::isfinite(spec.mass())))
      fail(field + ".mass", core::format_number(spec.mass()) + " kg must be >= 0");
  }
  Specimen out;
  out.mass = spec.mass();
  if (spec.has_zeta()) {
    if (!(spec.zeta() >= 0 && range_of(Quantity::kDampingRatio).contains(spec.zeta()) &&
          spec.mass() > 0))
      fail(field + ".zeta",
           core::format_number(spec.zeta()) + " must be in [0, 1] with a mass > 0");
    out.damping = 2.0 * spec.zeta() * spec.mass() * std::sqrt(spec.stiffness() / spec.mass());
  } else {
    if (!(spec.damping() >= 0 && std::isfinite(spec.damping())))
      fail(field + ".damping", core::format_number(spec.damping()) + " N s/m must be >= 0");
    out.damping = spec.damping();
  }
  out.model = make_storey_factory(spec.model())(spec.stiffness());
  if (out.mass > 0 || out.damping > 0)
    out.model = std::make_unique<core::InertialSpecimen>(std::move(out.model), out.mass,
                                                         out.damping, servo_period);
  return out;
}

// The row's terms, b (b = e_dof for a grounded specimen).
std::vector<std::pair<int, double>> row_terms(const core::ElementRow& row, int dof) {
  if (row.terms.empty()) return {{dof, 1.0}};
  return row.terms;
}

// The specimens' masses and dashpots taken out of M and C (value b b^T each): from the dense
// copies where the model holds them, else gathered and subtracted from the sparse forms at once
// (apply), so that a model held sparse only never forms an n x n matrix.
class TakenOut {
 public:
  explicit TakenOut(const core::StructuralModel& model)
      : dense_(model.mass.rows() == model.dofs()), mass_(model.mass), damping_(model.damping) {}
  void take(const core::ElementRow& row, int dof, double mass, double damping) {
    for (const auto& [i, ci] : row_terms(row, dof))
      for (const auto& [j, cj] : row_terms(row, dof)) {
        if (dense_) {
          mass_(i, j) -= mass * ci * cj;
          damping_(i, j) -= damping * ci * cj;
          continue;
        }
        mass_taken_.emplace_back(i, j, mass * ci * cj);
        damping_taken_.emplace_back(i, j, damping * ci * cj);
      }
  }
  // M - sum m b b^T positive definite (judged as the model is held).
  bool mass_definite(const core::StructuralModel& model) const {
    if (dense_)
      return Eigen::SelfAdjointEigenSolver<core::Mat>(mass_, Eigen::EigenvaluesOnly)
                 .eigenvalues()[0] > 0;
    return !core::check_sparse_definite(model.sparse_mass - taken(mass_taken_, model.dofs()), true);
  }
  // The model's M and C less what was taken (both forms it holds); returns M iota before.
  core::Vec apply(core::StructuralModel& model) const {
    const core::Vec load = core::mass_times(model, model.influence);
    if (dense_) {
      model.mass = mass_;
      model.damping = damping_;
      if (!model.is_sparse()) return load;
      model.sparse_mass = mass_.sparseView();
      model.sparse_damping = damping_.sparseView();
      return load;
    }
    model.sparse_mass -= taken(mass_taken_, model.dofs());
    model.sparse_damping -= taken(damping_taken_, model.dofs());
    model.sparse_mass.prune(0.0);
    model.sparse_damping.prune(0.0);
    return load;
  }

 private:
  static core::SparseMat taken(const std::vector<Eigen::Triplet<double>>& entries, int n) {
    core::SparseMat out(n, n);
    out.setFromTriplets(entries.begin(), entries.end());
    return out;
  }
  bool dense_;
  core::Mat mass_, damping_;
  std::vector<Eigen::Triplet<double>> mass_taken_, damping_taken_;
};

// The experimental fraction phi_1' K_e phi_1 / omega_1^2 of the first mode of (M, K) for K_e =
// k b b^T.
double first_mode_fraction(const core::Modes& modes, const core::Vec& b, double k) {
  const double along = b.dot(modes.shapes.col(0));
  return k * along * along / (modes.omega[0] * modes.omega[0]);
}

// Row d of K (N/m): its nonzeros (column, value) in column order, from either form the model
// holds (K symmetric: column d of the sparse form).
std::vector<std::pair<int, double>> stiffness_row(const core::StructuralModel& model, int d) {
  std::vector<std::pair<int, double>> row;
  if (model.stiffness.rows() == model.dofs()) {
    for (int j = 0; j < model.dofs(); ++j)
      if (model.stiffness(d, j) != 0.0) row.emplace_back(j, model.stiffness(d, j));
    return row;
  }
  for (core::SparseMat::InnerIterator it(model.sparse_stiffness, d); it; ++it)
    row.emplace_back(static_cast<int>(it.row()), it.value());
  return row;
}

// A grounded specimen stiffer than what ties its DOF to the ground ((K iota)_d, the force at d
// under a rigid translation) most likely means an element between DOFs (a storey): the warning
// names both fractions and the DOF it would join (the one K couples most strongly).
std::optional<std::string> storey_meant(const core::StructuralModel& model,
                                        const config::ExperimentalDof& spec,
                                        const std::string& field) {
  const int d = spec.dof() - 1, n = model.dofs();
  const std::vector<std::pair<int, double>> row = stiffness_row(model, d);
  double ground_tie = 0.0;
  for (const auto& [j, k] : row) ground_tie += k * model.influence[j];
  if (n < 2 || spec.stiffness() <= ground_tie * (1 + 1e-9)) return std::nullopt;
  int neighbour = d == 0 ? 1 : 0;
  double coupling = entry(model.stiffness, model.sparse_stiffness, d, neighbour);
  for (const auto& [j, k] : row)
    if (j != d && k < coupling) {
      neighbour = j;
      coupling = k;
    }
  std::string text = field + ": a specimen of " + core::format_number(spec.stiffness()) +
                     " N/m between DOF " + std::to_string(d + 1) +
                     " and the ground, but K ties DOF " + std::to_string(d + 1) +
                     " to the ground by only " + core::format_number(ground_tie) + " N/m (K iota)";
  if (n <= kMaxDofsForFractionHint) {
    const core::Vec grounded = core::Vec::Unit(n, d);
    const core::Vec storey = grounded - core::Vec::Unit(n, neighbour);
    const core::Modes modes = core::modal_analysis(model.mass, model.stiffness);
    text += ": as written it takes an experimental fraction of " +
            core::format_number(first_mode_fraction(modes, grounded, spec.stiffness()), 3) +
            " of mode 1; between DOF " + std::to_string(neighbour + 1) + " and DOF " +
            std::to_string(d + 1) + " it would take " +
            core::format_number(first_mode_fraction(modes, storey, spec.stiffness()), 3);
  }
  return text + ". If the specimen sits between two DOFs (a storey), say from_dof: " +
         std::to_string(neighbour + 1);
}

}  // namespace

core::StructuralModel matrix_structure(const config::Structure& structure,
                                       const std::filesystem::path& base_dir) {
  const config::MatrixStructure& spec = structure.matrices();
  core::StructuralModel model = read_matrix_structure(spec, base_dir, "structure.matrices");
  apply_damping(model, structure.damping(), spec.has_damping());
  // A C given as a matrix may be full: dense again (modal damping keeps its factors, sparse).
  if (model.is_sparse() && model.low_rank_damping.empty()) core::hold_sparse_if_sparse(model);
  return model;
}

core::HybridPartition split_at_dofs(core::StructuralModel& model,
                                    const config::Substructuring& substructuring,
                                    double servo_period, std::vector<std::string>* warnings) {
  std::vector<core::DofSpecimen> specimens;
  TakenOut taken(model);
  bool massive_element = false;
  for (int i = 0; i < substructuring.experimental_dofs_size(); ++i) {
    const std::string field = "substructuring.experimental_dofs[" + std::to_string(i) + "]";
    const config::ExperimentalDof& spec = substructuring.experimental_dofs(i);
    const core::ElementRow row = element_row(spec, model.dofs(), field);
    Specimen specimen = make_specimen(spec, model, row, field, servo_period);
    const int d = spec.dof() - 1;
    if (row.terms.empty()) {
      for (const core::DofSpecimen& earlier : specimens)
        if (earlier.element.terms.empty() && earlier.dof == d)
          fail(field + ".dof", std::to_string(spec.dof()) + " is listed twice");
      if (warnings)
        if (auto warning = storey_meant(model, spec, field)) warnings->push_back(*warning);
    }
    massive_element = massive_element || (!row.terms.empty() && specimen.mass > 0);
    taken.take(row, d, specimen.mass, specimen.damping);
    specimens.push_back({d, std::move(specimen.model), row});
  }
  if (massive_element && !taken.mass_definite(model))
    fail("substructuring.experimental_dofs",
         "the elements' masses leave the numerical part without positive mass (M - m b b^T is "
         "not positive definite)");
  core::HybridPartition partition =
      model.stiffness.rows() == model.dofs()
          ? core::partition_by_dofs(model.stiffness, std::move(specimens))
          : core::partition_by_dofs(model.sparse_stiffness, std::move(specimens));
  // The specimen's force holds m_e x'' of the relative acceleration only, so the numerical part
  // carries the ground motion's load on the whole mass, -M iota a_g = -M_N (M_N^-1 M iota) a_g.
  const core::Vec load = taken.apply(model);
  model.influence =
      model.is_sparse()  // M_N sparse: its LDL^T, not a dense one
          ? core::Vec(Eigen::SimplicialLDLT<core::SparseMat>(model.sparse_mass).solve(load))
          : core::Vec(model.mass.ldlt().solve(load));
  core::remember_max_omega(model);  // M_N final: one estimate for every simulation of the study
  return partition;
}

}  // namespace rths::study
