#include "view/record_view.h"

#include <algorithm>
#include <stdexcept>
#include <thread>

#include "runtime/record/record.h"
#include "view/context.h"
#include "view/hand_down.h"
#include "view/record_limits.h"

namespace rths::view {
namespace {

// Reads `record` (a record or a run's folder) into `feed`, finished; whether it was cut short.
bool load_run(Feed& feed, const std::filesystem::path& given,
              const std::optional<JudgedCase>& judged) {
  const std::filesystem::path record = run_record_in(given);
  runtime::RecordContents contents;
  try {
    contents = runtime::read_record(record);
  } catch (const std::exception& e) {
    throw std::invalid_argument(e.what());
  }
  if (!contents.header())
    throw std::invalid_argument(record.string() + ": no run header: not a run record");
  if (const auto why = refused_header(*contents.header()))
    throw std::invalid_argument(record.string() + ": " + *why);
  // The context (relative paths beside the record; the record's own motion when the study's file
  // is not here) before the steps, which then carry the prediction.
  describe_record(feed, contents, record.parent_path());
  const std::filesystem::path layout = record.parent_path() / kSitesLayoutFile;
  if (std::filesystem::exists(layout)) {
    nlohmann::json context = feed.context();
    context["sites"] = HandDown{-1, read_site_layouts(layout), std::nullopt}.sites_json();
    feed.set_context(context);
  }
  if (judged) feed.set_judged(*judged);
  for (const auto& entry : contents.entries) feed.add(entry);
  feed.finish();
  return contents.truncated;
}

// One run of a comparison: its record, run, case, status and, against its in-process
// prediction, E_peak and E_rms per DOF (%), as its page shows them.
nlohmann::json run_summary(const Feed& feed, const std::filesystem::path& given,
                           const std::string& run) {
  FeedCursor cursor;
  const nlohmann::json all = feed.since(cursor);
  const nlohmann::json& status = all["status"];
  const nlohmann::json prediction = status.value("prediction", nlohmann::json::object());
  return {{"run", run},
          {"page", "/?run=" + run},
          {"record", run_record_in(given).string()},
          {"run_id", all["header"]["run_id"]},
          {"case", all["header"]["case"]},
          {"clock", all["header"]["clock"]},
          {"steps", status["steps"]},
          {"status", status.contains("footer") ? status["footer"]["status"] : status["state"]},
          {"ok", status.contains("footer") && status["footer"]["ok"].get<bool>()},
          {"dof_labels", all["header"].value("dof_labels", nlohmann::json::array())},
          {"e_peak_pct", prediction.value("peak_error_pct", nlohmann::json::array())},
          {"e_rms_pct", prediction.value("rms_error_pct", nlohmann::json::array())}};
}

}  // namespace

std::filesystem::path run_record_in(const std::filesystem::path& given) {
  if (!std::filesystem::is_directory(given)) return given;
  std::vector<std::filesystem::path> records;
  for (const auto& entry : std::filesystem::directory_iterator(given))
    if (entry.path().extension() == ".rthsrec") records.push_back(entry.path());
  std::sort(records.begin(), records.end());
  if (records.size() == 1) return records.front();
  if (records.empty())
    throw std::invalid_argument(given.string() + " holds no run record (.rthsrec)");
  std::string names;
  for (const auto& r : records) names += (names.empty() ? "" : ", ") + r.filename().string();
  throw std::invalid_argument(given.string() + " holds " + std::to_string(records.size()) +
                              " run records (" + names + "): name the one to view");
}

RecordView::RecordView(const std::filesystem::path& record, const ListenAddress& address,
                       std::chrono::milliseconds bind_for,
                       const std::optional<JudgedCase>& judged) {
  truncated_ = load_run(feed_, record, judged);
  ServerOptions options;
  options.address = address;
  options.mode = "replay";
  options.bind_for = bind_for;
  server_ = std::make_unique<ViewServer>(feed_, options);
}

RecordView::RecordView(const std::filesystem::path& record, const std::filesystem::path& compare,
                       const ListenAddress& address)
    : second_(std::make_unique<Feed>()) {
  truncated_ = load_run(feed_, record, std::nullopt);
  load_run(*second_, compare, std::nullopt);
  ServerOptions options;
  options.address = address;
  options.mode = "replay";
  options.second = second_.get();
  options.comparison = {
      {"runs", {run_summary(feed_, record, "a"), run_summary(*second_, compare, "b")}}};
  server_ = std::make_unique<ViewServer>(feed_, options);
}

RecordView::~RecordView() = default;

void RecordView::serve_until(std::optional<std::chrono::steady_clock::time_point> until,
                             const std::function<bool()>& stop_requested) {
  while (!stop_requested() && (!until || std::chrono::steady_clock::now() < *until))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  server_->shutdown(std::chrono::milliseconds(0));
}

}  // namespace rths::view
