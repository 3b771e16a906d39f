#pragma once
// A finished (or cut-short) run record served as the view's page. The record is read whole
// (runtime::read_record keeps every complete entry of a cut record and says where it was cut),
// described (view/context.h: the critical delay, the in-process prediction, the deadline
// diagnosis) and fed through the same view::Feed a running coordinator feeds, then served in
// "replay" mode: the page shows the whole run with a time slider, its badge the run's verdict.
//   `rths view RECORD`           serves one until Ctrl-C or --for;
//   `rths view OUT`              a run's output folder: the one record in it (a sites run's
//                                OUT/<case>.rthsrec), every site's nodes, links and actuators on
//                                the record's one time axis, grouped by OUT/sites.json (as the
//                                live page grouped them; without it, one site holds every node);
//   `rths view A --compare B`    two runs side by side (before and after a change of
//                                compensation): /compare shows both pages, A's (/?run=a) and B's
//                                (/?run=b), under each run's E_peak and E_rms against its
//                                in-process prediction (/api/compare: ServerOptions::comparison);
//   `rths launch ... --view`     serves the last case's once its coordinator has exited, on the
//                                address that coordinator's live view had (bind_for covers the
//                                moment the port may still be held), until Ctrl-C or --view-for,
//                                with how it judged the case on the badge (JudgedCase).
// No stop button: the run is over.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "view/feed.h"
#include "view/server.h"
#include "view/verdict.h"

namespace rths::view {

// The record `given` names: itself, or for a folder the one run record (.rthsrec) in it. Throws
// std::invalid_argument naming the folder when it holds none or several (naming them).
std::filesystem::path run_record_in(const std::filesystem::path& given);

class RecordView {
 public:
  // `record`: a record or a run's folder (run_record_in). Throws std::invalid_argument for a
  // record that cannot be read, holds no run header or one the view refuses (refused_header,
  // view/record_limits.h: the error names the field and its value), or a sites.json that is not
  // a list of sites, std::runtime_error when `address` cannot be listened on within `bind_for`.
  // `judged`: how `rths launch` judged the case, for its badge (view/verdict.h).
  RecordView(const std::filesystem::path& record, const ListenAddress& address,
             std::chrono::milliseconds bind_for = std::chrono::milliseconds(0),
             const std::optional<JudgedCase>& judged = std::nullopt);
  // Two runs side by side: `record` and `compare` (each a record or a run's folder), as above.
  RecordView(const std::filesystem::path& record, const std::filesystem::path& compare,
             const ListenAddress& address);
  ~RecordView();
  RecordView(const RecordView&) = delete;
  RecordView& operator=(const RecordView&) = delete;

  std::string url() const { return server_->url(); }
  std::uint64_t steps() const { return feed_.steps_seen(); }
  bool truncated() const { return truncated_; }
  // Serves until `until` (nothing: for ever) or until stop_requested() says so (polled every
  // 50 ms), then stops listening.
  void serve_until(std::optional<std::chrono::steady_clock::time_point> until,
                   const std::function<bool()>& stop_requested);

 private:
  Feed feed_;                     // before server_: it outlives the server that reads it
  std::unique_ptr<Feed> second_;  // the compared run (--compare), else none
  std::unique_ptr<ViewServer> server_;
  bool truncated_ = false;
};

}  // namespace rths::view
