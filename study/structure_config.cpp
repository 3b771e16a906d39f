#include "study/structure_config.h"

#include <Eigen/SparseCholesky>

#include <cmath>
#include <stdexcept>

#include "core/sparse_structure.h"
#include "study/ranges.h"
#include "study/restoring_force_config.h"
#include "study/structure_io.h"
#include "study/text_columns.h"

namespace rths::core {
namespace {

[[noreturn]] void fail(const std::string& field, const std::string& problem) {
  throw std::invalid_argument(field + ": " + problem);
}

void apply_damping(StructuralModel& model, const config::Damping& damping, bool has_matrix) {
  const bool ratio = damping.has_rayleigh() || damping.modal_zeta() > 0;
  if (has_matrix && ratio)
    fail("structure.damping",
         "structure.matrices.damping is given: give the matrix or the ratios, not both");
  if (damping.has_rayleigh() && model.is_sparse()) {
    const auto& r = damping.rayleigh();
    sparse_rayleigh_damping(model, r.zeta(), r.mode_i() == 0 ? 1 : r.mode_i(),
                            r.mode_j() == 0 ? 2 : r.mode_j());
  } else if (damping.has_rayleigh()) {
    const auto& r = damping.rayleigh();
    model.damping =
        rayleigh_damping(model.mass, model.stiffness, r.zeta(), r.mode_i() == 0 ? 1 : r.mode_i(),
                         r.mode_j() == 0 ? 2 : r.mode_j());
  } else if (!has_matrix && model.is_sparse() && damping.modal_zeta() == 0) {
    model.damping.setZero();  // no modes needed for C = 0
    model.sparse_damping.setZero();
  } else if (!has_matrix) {
    model.damping = modal_damping(model.mass, model.stiffness, damping.modal_zeta());
  }
}

// The specimen of experimental_dofs[i] and the mass and damping it takes from the numerical part.
struct Specimen {
  double mass = 0.0, damping = 0.0;
  std::unique_ptr<RestoringForceModel> model;
};

Specimen make_specimen(const config::ExperimentalDof& spec, const StructuralModel& model,
                       const std::string& field, double servo_period) {
  const int n = model.dofs();
  if (spec.dof() < 1 || spec.dof() > n)
    fail(field + ".dof", std::to_string(spec.dof()) + " is outside 1.." + std::to_string(n));
  const int d = spec.dof() - 1;
  if (!(spec.stiffness() > 0 && spec.stiffness() <= model.stiffness(d, d)))
    fail(field + ".stiffness", format_number(spec.stiffness()) + " N/m must be in (0, K(" +
                                   std::to_string(d + 1) + ", " + std::to_string(d + 1) +
                                   ") = " + format_number(model.stiffness(d, d)) + "]");
  if (!(spec.mass() >= 0 && spec.mass() < model.mass(d, d)))
    fail(field + ".mass", format_number(spec.mass()) + " kg must be in [0, M(" +
                              std::to_string(d + 1) + ", " + std::to_string(d + 1) +
                              ") = " + format_number(model.mass(d, d)) + ")");
  Specimen out;
  out.mass = spec.mass();
  if (spec.has_zeta()) {
    if (!(spec.zeta() >= 0 && range_of(Quantity::kDampingRatio).contains(spec.zeta()) &&
          spec.mass() > 0))
      fail(field + ".zeta", format_number(spec.zeta()) + " must be in [0, 1] with a mass > 0");
    out.damping = 2.0 * spec.zeta() * spec.mass() * std::sqrt(spec.stiffness() / spec.mass());
  } else {
    if (!(spec.damping() >= 0 && std::isfinite(spec.damping())))
      fail(field + ".damping", format_number(spec.damping()) + " N s/m must be >= 0");
    out.damping = spec.damping();
  }
  out.model = make_storey_factory(spec.model())(spec.stiffness());
  if (out.mass > 0 || out.damping > 0)
    out.model = std::make_unique<InertialSpecimen>(std::move(out.model), out.mass, out.damping,
                                                   servo_period);
  return out;
}

}  // namespace

StructuralModel matrix_structure(const config::Structure& structure,
                                 const std::filesystem::path& base_dir) {
  const config::MatrixStructure& spec = structure.matrices();
  StructuralModel model = read_matrix_structure(spec, base_dir, "structure.matrices");
  apply_damping(model, structure.damping(), spec.has_damping());
  if (model.is_sparse()) hold_sparse_if_sparse(model);  // modal damping fills C: dense again
  return model;
}

HybridPartition split_at_dofs(StructuralModel& model, const config::Substructuring& substructuring,
                              double servo_period) {
  std::vector<DofSpecimen> specimens;
  Mat mass = model.mass, damping = model.damping;
  for (int i = 0; i < substructuring.experimental_dofs_size(); ++i) {
    const std::string field = "substructuring.experimental_dofs[" + std::to_string(i) + "]";
    const config::ExperimentalDof& spec = substructuring.experimental_dofs(i);
    Specimen specimen = make_specimen(spec, model, field, servo_period);
    const int d = spec.dof() - 1;
    for (const DofSpecimen& earlier : specimens)
      if (earlier.dof == d) fail(field + ".dof", std::to_string(spec.dof()) + " is listed twice");
    mass(d, d) -= specimen.mass;
    damping(d, d) -= specimen.damping;
    specimens.push_back({d, std::move(specimen.model)});
  }
  HybridPartition partition = partition_by_dofs(model.stiffness, std::move(specimens));
  // The specimen's force holds m_e x'' of the relative acceleration only, so the numerical part
  // carries the ground motion's load on the whole mass, -M iota a_g = -M_N (M_N^-1 M iota) a_g.
  if (model.is_sparse()) {  // M_N sparse: its LDL^T, not a dense one
    const Vec load = model.sparse_mass * model.influence;
    model.sparse_mass = mass.sparseView();
    model.sparse_damping = damping.sparseView();
    model.influence = Eigen::SimplicialLDLT<SparseMat>(model.sparse_mass).solve(load);
  } else {
    model.influence = mass.ldlt().solve(model.mass * model.influence);
  }
  model.mass = mass;
  model.damping = damping;
  return partition;
}

}  // namespace rths::core
