#include "view/record_view.h"

#include <stdexcept>
#include <thread>

#include "runtime/record/record.h"
#include "view/context.h"

namespace rths::view {

RecordView::RecordView(const std::filesystem::path& record, const ListenAddress& address,
                       std::chrono::milliseconds bind_for,
                       const std::optional<JudgedCase>& judged) {
  runtime::RecordContents contents;
  try {
    contents = runtime::read_record(record);
  } catch (const std::exception& e) {
    throw std::invalid_argument(e.what());
  }
  if (!contents.header())
    throw std::invalid_argument(record.string() + ": no run header: not a run record");
  truncated_ = contents.truncated;
  // The context (relative paths beside the record; the record's own motion when the study's file
  // is not here) before the steps, which then carry the prediction.
  describe_record(feed_, contents, record.parent_path());
  if (judged) feed_.set_judged(*judged);
  for (const auto& entry : contents.entries) feed_.add(entry);
  feed_.finish();
  ServerOptions options;
  options.address = address;
  options.mode = "replay";
  options.bind_for = bind_for;
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
