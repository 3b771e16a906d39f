#pragma once
// Facts about a run the record does not hold, for the view's status panel: the case's
// critical-delay check (analysis::check_case_critical_delay, the check `rths run` and `rths launch`
// make before a case runs): {"lag_ms", "critical_delay_ms", "margin_pct", "text"}, or
// {"text": why not} when the structure has no experimental part or the study cannot be prepared.

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "core/study.h"

namespace rths::view {

nlohmann::json run_context(const core::PreparedStudy& prepared, const std::string& case_name);
// The same from a record's study; `base_dir` resolves its relative paths (the motion).
nlohmann::json run_context(const config::Study& study, const std::string& case_name,
                           const std::filesystem::path& base_dir);

}  // namespace rths::view
