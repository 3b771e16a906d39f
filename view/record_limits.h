#pragma once
// What the view sizes its tables from a run header by, checked before it sizes any: a record is
// read from a file anyone may hand over (`rths view`), and a header's counts decide how much the
// view allocates (the feed's rings, runtime::recorded_dofs).
//   refused_header     why the view refuses `header`, naming the field and its value: dofs outside
//                      [0, runtime::kMaxRecordDofs], actuators or links (link_node_ids)
//                      outside [0, kMaxRecordDofs], or a
//                      recorded_dofs entry that is not a DOF of 0..dofs-1 above the one before it
//                      (each record column's DOF, ascending); nullopt for a header it may draw.
//   prediction_column  the column of model DOF `dof` in a prediction that kept `kept` (ascending
//                      DOFs, core::SimulationResult::dofs; empty: every DOF of `columns`), -1
//                      where it kept none.

#include <optional>
#include <string>
#include <vector>

#include "runtime/record/record.h"

namespace rths::view {

std::optional<std::string> refused_header(const runtime::RunHeader& header);

int prediction_column(const std::vector<int>& kept, int columns, int dof);

}  // namespace rths::view
