#pragma once
// Critical lags of a structure whose experimental parts come back late, with the coupling between
// modes that the delayed forces add (core/stability.h's modal check ignores it), with or without
// a force predictor (core/force_predictor.h) on each part.
//
// The loop. Part j (a link) is a specimen k_j, c_j, m_j (N/m, N s/m, kg) on the drift b_j' u,
// whose measured pair comes back D_j late (round trip plus actuator lag). Uncompensated the
// integrator gets its whole force late; with a predictor whose model is k^_j, c^_j it gets the
// model now and the model's error late (core/force_predictor.h: f = k^ u + c^ v + e, e the
// measured force less the model at the measured drift):
//   M_N u'' + C_N u' + K_N u + sum_j b_j b_j' [p_j(s) u + h_j(s) e^{-s D_j} u] = 0 (Laplace s)
//   p_j = k^_j + c^_j s (0 uncompensated),  h_j = (k_j - k^_j) + (c_j - c^_j) s + m_j s^2,
// K_N = K - sum k_j b_j b_j'; M_N, C_N the numerical part's (study/structure_config.h: the
// specimens' masses and dashpots are not in the model). At D = 0 this is the whole structure.
//
// The analysis. In the q lowest M_N-normalised modes Phi of (M_N, K) (q = n up to kMaxModes;
// else the lowest kMaxModes, a truncation `assumed` states), w_j = Phi' b_j, C~ the modes'
// damping (core::damping_in_modes: a sparse model's low-rank modal damping included) and
//   A(w) = Omega^2 - sum k_j w_j w_j' - w^2 I + i w C~ + sum_j w_j w_j' p_j(i w)
//          + sum_{j fixed} w_j w_j' h_j(i w) e^{-i w D_j}.
// The parts in S share one varying lag tau (the others fixed at theirs): a root crosses at
// s = i w when det(A + z W_S H_S W_S') = 0, z = e^{-i w tau}, i.e. (determinant lemma) when an
// eigenvalue lambda of G(w) = H_S W_S' A(w)^-1 W_S (|S| x |S|) has |lambda| = 1; then
// z = -1 / lambda and tau = ((-arg z) mod 2 pi) / w (first branch; later ones add 2 pi / w).
// Crossings are found where the count of |lambda| > 1 changes on a log grid of kGridPoints w from
// 1e-3 omega_1 to 10 omega_q, each refined by 60 bisections; the first crossing is the smallest
// tau over them. A grid this fine misses a crossing only where |lambda| touches 1 and turns back.
//   common lag (S = every part, none fixed): the critical lag when every link lags alike;
//   per part l (S = {l}): the lag of link l at the first crossing with the others at their own
//     lags. That start (l lag-free, the others at theirs) is judged by a staircase from the
//     whole structure (D = 0, stable: K positive definite, C_N + sum c_j b_j b_j' >= 0): each
//     other part's lag raised from 0 to its own in turn, the earlier ones at theirs, a crossing
//     before its lag meaning a root has crossed; no root crosses on the way, none is in the right
//     half-plane at the start. `stable` is the configured lags' verdict by the same staircase:
//     any lag at or past the first crossing counts as unstable, although a delayed loop may
//     regain stability at a later crossing (the lab frame with a model twice its storey
//     specimen's stiffness: first crossing 49.9 ms, growing at 52 and 60 ms, decaying again at
//     80 ms), so the verdict is conservative there.
// A specimen's mass makes the loop neutral (m_j s^2 delayed); the analysis holds while the
// delayed inertia stays below the numerical part's (|m_j w_j' w_j| < 1), as for lab specimens.
// For one DOF, or a K_e and C that the modes diagonalise, the common lag uncompensated is the
// modal check's SDOF result; with a predictor on one DOF, core::predictor_critical_delay's.

#include <optional>
#include <string>
#include <vector>

#include "core/structure.h"

namespace rths::core {

struct HybridSetup;

struct CoupledStability {
  static constexpr int kMaxModes = 24;
  static constexpr int kGridPoints = 3000;
  std::optional<double> critical_delay;  // s; empty: no crossing (stable for every delay)
  double omega = 0.0;                    // rad/s at the governing crossing
  int modes_kept = 0;                    // q
  int parts = 0;                         // m, the rank of K_e
  std::string assumed;
};

// Uncompensated, every part's stiffness k_j b_j b_j' summed in K_e (N/m, n x n, symmetric
// positive semi-definite) at one common lag, no dashpot or mass: the parts are K_e's independent
// directions. `modes`: M-normalised modes of (M, K), ascending (all n, or the lowest ones a sparse
// solver found). @pre model.mass and stiffness n x n (damping, or the sparse one); modes n x >= 1.
CoupledStability coupled_critical_delay(const StructuralModel& model, const Mat& k_experimental,
                                        const Modes& modes);
// The same with K_e held sparse (a large model: no n x n matrix).
CoupledStability coupled_critical_delay(const StructuralModel& model,
                                        const SparseMat& k_experimental, const Modes& modes);

// Whether the q lowest modes diagonalise K_e and C (to 1e-9 of their diagonals): then the modal
// check is exact and the coupled analysis adds nothing.
bool modes_decouple(const StructuralModel& model, const Mat& k_experimental, const Modes& modes);
bool modes_decouple(const StructuralModel& model, const SparseMat& k_experimental,
                    const Modes& modes);

// One experimental part of the loop (a link), in the header's symbols.
struct DelayedPart {
  Vec row;                       // b, n entries: the part's drift is b' u
  double stiffness = 0.0;        // N/m, k_j at its initial stiffness, > 0
  double damping = 0.0;          // N s/m, c_j, its dashpot
  double mass = 0.0;             // kg, m_j
  bool predicted = false;        // a force predictor holds a model of it
  double model_stiffness = 0.0;  // N/m, k^_j (predicted)
  double model_damping = 0.0;    // N s/m, c^_j (predicted)
  double lag = 0.0;              // s, D_j: the lag of its measured pair, >= 0
};

struct PartLimit {
  // s: part l's lag at the first crossing, the others at their lags; empty: none (stable for
  // every lag of this part), or `crossed_before` says the start already crossed.
  std::optional<double> critical_lag;
  double omega = 0.0;  // rad/s at that crossing
  // >= 0 when the loop has crossed with this part lag-free and the others at their lags: the
  // part (0-based) whose lag crossed on the staircase, and the lag (s) it crossed at.
  int crossed_before = -1;
  double crossed_at = 0.0;
};

struct CoupledLoopStability {
  bool stable = false;  // at the parts' own lags
  // When not stable: the part (0-based) whose lag crossed first on the staircase, and at what
  // lag (s); -1 when stable.
  int crossed = -1;
  double crossed_at = 0.0;
  std::optional<double> common_critical_lag;  // s, every part at one lag; empty: none
  double common_omega = 0.0;                  // rad/s
  std::vector<PartLimit> parts;               // one per part, in order
  int modes_kept = 0;
  std::string assumed;
};

// The header's analysis of `parts` on `model` (M_N, C_N, K). `modes`: M_N-normalised modes of
// (M_N, K) as above. Throws std::invalid_argument when a part's row is not n long or zero, its
// stiffness is not > 0, a value is not finite or a lag is negative.
CoupledLoopStability coupled_loop_stability(const StructuralModel& model,
                                            const std::vector<DelayedPart>& parts,
                                            const Modes& modes);

// The links of a hybrid setup as parts of its loop: actuator a's row (its storey's, DOF's or
// element's drift), its declared specimen's initial stiffness, dashpot and mass
// (core::InertialSpecimen), its force predictor's model as it starts (the parameters' stiffness,
// the model's initial tangent; core::ForcePredictor's damping() before any fit), and lags[a] (s). Throws std::invalid_argument when
// lags is not one per actuator or an actuator has no specimen.
std::vector<DelayedPart> setup_loop_parts(const HybridSetup& setup,
                                          const std::vector<double>& lags);
// Which model a predicted link's predictor holds in the analysis: as it starts (the parameters'
// stiffness and dashpot, before any fit), or fitted to the declared specimen (what an online fit
// reaches when the specimen behaves as declared: the model's stiffness and dashpot are the
// specimen's, so nothing of that link comes back late).
enum class PredictorModels { kAsTheyStart, kFittedToTheDeclaredSpecimen };

// coupled_loop_stability of a setup's model and its setup_loop_parts (their predictors' models
// as `models` says), in the modes core::check_modal_critical_delay takes (all n; a model held
// sparse: its lowest 20).
CoupledLoopStability setup_loop_stability(const HybridSetup& setup, const std::vector<double>& lags,
                                          PredictorModels models = PredictorModels::kAsTheyStart);

}  // namespace rths::core
