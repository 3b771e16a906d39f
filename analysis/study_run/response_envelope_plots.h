#pragma once
// Figures of a study of many DOFs and many actuators, drawn beside the study's others
// (write_study_plots, analysis/study_run/study_plots.cpp) through util/plot.h. Floors are the DOFs the
// reference case kept (core::SimulationResult::dofs: every DOF of a model of at most
// study::kAllDofsLimit, else what the recorders asked for), numbered 1.. from the ground, ascending.
//
//   response_envelope.png  (models of at least kEnvelopeFloors floors) two panels side by side,
//                          height (floor number) on y: the peak |u_i| (mm) of each recorded floor,
//                          and the peak storey drift (mm) between consecutive recorded floors i < j
//                          (the ground below the first, u = 0), averaged over the storeys between
//                          them: max_t |u_j(t) - u_i(t)| / (j - i), the inter-storey drift where
//                          every floor is recorded. Each bounded case in its colour, the reference
//                          (the lag-free in-process run, else the study's reference case) thin and
//                          dark over them; a diverged case is left out and the title says so.
//   floor_histories.png    (same models) a panel per chosen floor, two a row: every bounded
//                          case's u (mm) over time with the reference's drawn over it. Chosen: every
//                          recorded floor when there are at most kHistoryFloors, else
//                          kHistoryFloors of them evenly spaced from the first to the top.
//   actuators_<p>.png      (studies of at least two actuators) every actuator in config order,
//                          kActuatorsPerPage a page (p = 1, 2, ...), two a row, each as two panels:
//                          its tracking error x_m - x_t (mm, measured less command) over time and
//                          its measured force (kN) against its command (mm), every bounded case in
//                          its colour. A page is kActuatorColumns x 5 panels of kActuatorPanelWidth
//                          x kActuatorPanelHeight px and one legend below them all, each case
//                          once, in as many columns as the page's width holds (1800 x 2000 and
//                          the legend's rows: within an A4 page's proportions), printed at a
//                          page's width, at most kActuatorTics x intervals a panel so that no
//                          tick labels run together.
// A case's colour is its index among the drawn cases (util::series_colour), as in
// displacement.png.

#include <filesystem>
#include <string>
#include <vector>

#include "analysis/study_run/study_run.h"
#include "util/plot.h"

namespace rths::analysis {

inline constexpr int kEnvelopeFloors = 3;
inline constexpr int kHistoryFloors = 6;
inline constexpr int kActuatorsPerPage = 10;
inline constexpr int kActuatorColumns = 4;  // panels a row: two actuators, two panels each
inline constexpr int kActuatorPanelWidth = 450, kActuatorPanelHeight = 400;  // px
inline constexpr int kActuatorTics = 4;

// The recorded floors (0-based DOFs, ascending) of a run: its kept DOFs, else every DOF.
std::vector<int> recorded_floors(const core::SimulationResult& run);

// The floors floor_histories.png draws, from the recorded ones (0-based, ascending).
std::vector<int> chosen_floors(const std::vector<int>& recorded);

// The profile over height of case c (y the floor number, DOF + 1) at each floor of `floors`
// (0-based, ascending) that c kept: x = max_t |u_floor| (mm), the ground (0, 0) first; with
// `drift`, x = max_t |u_j - u_i| / (j - i) (mm), i the recorded floor below j (-1, the ground, for
// the first).
util::Series peak_over_height(const CaseOutcome& c, const std::vector<int>& floors, bool drift,
                              const std::string& label, const std::string& style);

// Actuator a's measured force (kN) against its command (mm) in case c, one point a step.
util::Series force_loop(const CaseOutcome& c, int a, const std::string& label,
                        const std::string& style);

// The figures above that `outcome` has something for, to be drawn into `directory`; `drawn`
// the cases in colour order (the lag-free reference first when the outcome has one).
std::vector<util::Figure> many_dof_figures(const StudyOutcome& outcome,
                                           const std::vector<const CaseOutcome*>& drawn,
                                           const std::filesystem::path& directory);

// Removes the figures above (PNG and SVG, every page) from `directory`, so that a stale one does
// not stay beside a study that has none of its kind.
void remove_many_dof_figures(const std::filesystem::path& directory);

// study_plot_files() and the actuators_<p>.png / .svg pages `directory` holds (by page number):
// every figure write_study_plots may have left there, for a run without plots to remove and a
// summary to list.
std::vector<std::string> study_plot_files(const std::filesystem::path& directory);

}  // namespace rths::analysis
