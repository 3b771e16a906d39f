#pragma once
// A structure given by its matrices, from a study's config, split at its experimental DOFs.
//
//   matrix_structure(structure, base_dir): M, C, K, iota read (study/structure_io.h) and checked;
//     damping the matrix, or Structure.damping (modal ratio, Rayleigh) built from M and K; on a
//     model held sparse, a modal ratio goes through the lowest modes as a low-rank term
//     (core::sparse_modal_damping: the modes kept and the others' damping stated in
//     low_rank_damping.statement), never as a dense C.
//   split_at_dofs(model, substructuring, servo_period, warnings): the experimental substructure at
//     substructuring.experimental_dofs, each specimen f = m x'' + c x' + r(x) (InertialSpecimen
//     over the restoring-force model of initial stiffness k; a bare model when m = c = 0) at its
//     DOF or an element of row b (HybridPartition::elements); the numerical substructure is the
//     rest: the model's mass and damping become M - M_e and C - C_e (M_e = sum m b b^T, C_e =
//     sum c b b^T: what the integrator carries), K stays whole (the explicit integrators' K0), the
//     partition's K_N = K - K_e, and the influence becomes (M - M_e)^-1 M iota, so the load
//     -(M - M_e) iota' a_g is the whole structure's -M iota a_g (the specimen's m_e x'' is
//     relative). A model held sparse only stays so (its M_N and C_N subtracted sparse, K_N split
//     sparse); its omega_max is estimated once here (core::remember_max_omega) for every
//     simulation of the study.
//     A grounded specimen stiffer than what ties its DOF to the ground ((K iota)_dof) most likely
//     means a storey: `warnings` (when given) gets a line naming the experimental fraction it
//     implies and the one between that DOF and its most strongly coupled neighbour.
// Errors throw std::invalid_argument naming the field (substructuring.experimental_dofs[i]...),
// the value and the allowed range.

#include <filesystem>
#include <string>
#include <vector>

#include "core/substructure.h"
#include "rths/proto/config.pb.h"

namespace rths::study {

core::StructuralModel matrix_structure(const config::Structure& structure,
                                       const std::filesystem::path& base_dir);

core::HybridPartition split_at_dofs(core::StructuralModel& model,
                                    const config::Substructuring& substructuring,
                                    double servo_period,
                                    std::vector<std::string>* warnings = nullptr);

}  // namespace rths::study
