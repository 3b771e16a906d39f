#include "view/context.h"

#include "analysis/study_run.h"
#include "runtime/plan.h"

namespace rths::view {

nlohmann::json run_context(const core::PreparedStudy& prepared, const std::string& case_name) {
  nlohmann::json critical;
  try {
    const config::Case& study_case = runtime::find_case(prepared.config, case_name);
    const auto check = analysis::check_case_critical_delay(prepared, study_case);
    if (!check || !check->critical()) {
      critical["text"] =
          check ? "stable for every delay" : "no experimental part: no critical delay";
    } else {
      critical = {{"lag_ms", check->lag * 1e3},
                  {"critical_delay_ms", *check->critical() * 1e3},
                  {"margin_pct", check->margin() * 100.0},
                  {"text", check->describe()}};
    }
  } catch (const std::exception& e) {
    critical["text"] = std::string("not known: ") + e.what();
  }
  return {{"critical_delay", critical}};
}

nlohmann::json run_context(const config::Study& study, const std::string& case_name,
                           const std::filesystem::path& base_dir) {
  try {
    return run_context(core::prepare_study(study, base_dir), case_name);
  } catch (const std::exception& e) {
    return {{"critical_delay", {{"text", std::string("not known: ") + e.what()}}}};
  }
}

}  // namespace rths::view
