#include "runtime/record/record.h"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "runtime/node/schema.h"
#include "runtime/record/frame_scan.h"
#include "util/crc32c.h"

namespace rths::runtime {
namespace {

constexpr char kPreamble[kRecordPreambleBytes] = {'R', 'T', 'H', 'S', 'R', 'E', 'C', '\x02'};

std::uint32_t load_le32(const char* at) {
  std::uint32_t value = 0;
  for (int i = 3; i >= 0; --i) value = (value << 8) | static_cast<std::uint8_t>(at[i]);
  return value;
}

void store_le32(char* at, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) at[i] = static_cast<char>((value >> (8 * i)) & 0xFFu);
}

// Serialises the entry's payload into `out` after room for the frame header, then seals it.
void frame_into(const RecordEntry& entry, std::string& out) {
  const std::size_t start = out.size();
  const std::size_t size = entry.ByteSizeLong();
  out.resize(start + kRecordFrameHeaderBytes + size);
  entry.SerializeWithCachedSizesToArray(
      reinterpret_cast<std::uint8_t*>(out.data() + start + kRecordFrameHeaderBytes));
  seal_record_frame(out.data() + start, static_cast<std::uint32_t>(size));
}

}  // namespace

std::string_view record_preamble() { return {kPreamble, sizeof kPreamble}; }

void seal_record_frame(char* frame, std::uint32_t payload_size) {
  std::memcpy(frame, kRecordFrameSync, sizeof kRecordFrameSync);
  store_le32(frame + 4, payload_size);
  store_le32(frame + 8, util::crc32c(frame + kRecordFrameHeaderBytes, payload_size));
  store_le32(frame + 12, util::crc32c(frame, 12));
}

void append_record_frame(const RecordEntry& entry, std::string& out) { frame_into(entry, out); }

std::string_view HeaderRepeat::copy_before(RecordEntry::EntryCase kind) const {
  if (kind != RecordEntry::kStep || header_frame_.empty()) return {};
  return copies_ == 1 || steps_since_ >= kHeaderRepeatSteps ? std::string_view(header_frame_)
                                                            : std::string_view();
}

void HeaderRepeat::written(std::string_view frame, RecordEntry::EntryCase kind) {
  if (kind == RecordEntry::kHeader) {
    if (frame.data() != header_frame_.data()) header_frame_.assign(frame);
    ++copies_;
    steps_since_ = 0;
  } else if (kind == RecordEntry::kStep) {
    ++steps_since_;
  }
}

RecordWriter::RecordWriter(const std::filesystem::path& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_)
    throw std::runtime_error("cannot create run record " + path.string() + ": " +
                             std::strerror(errno));
  if (std::fwrite(kPreamble, 1, sizeof kPreamble, file_) != sizeof kPreamble ||
      std::fflush(file_) != 0)
    throw std::runtime_error("cannot write run record " + path_.string() + ": " +
                             std::strerror(errno));
}

RecordWriter::~RecordWriter() {
  if (file_) std::fclose(file_);
}

void RecordWriter::write(const RecordEntry& entry) {
  buffer_.clear();
  frame_into(entry, buffer_);
  const auto put = [this](std::string_view frame, RecordEntry::EntryCase kind) {
    if (std::fwrite(frame.data(), 1, frame.size(), file_) != frame.size())
      throw std::runtime_error("cannot write run record " + path_.string() + ": " +
                               std::strerror(errno));
    repeat_.written(frame, kind);
  };
  if (const std::string_view copy = repeat_.copy_before(entry.entry_case()); !copy.empty())
    put(copy, RecordEntry::kHeader);
  put(buffer_, entry.entry_case());
  if (std::fflush(file_) != 0)
    throw std::runtime_error("cannot write run record " + path_.string() + ": " +
                             std::strerror(errno));
}

AsyncRecordWriter::AsyncRecordWriter(const std::filesystem::path& path, std::size_t capacity,
                                     std::size_t slot_bytes)
    : path_(path), slots_(capacity), kinds_(capacity, RecordEntry::ENTRY_NOT_SET) {
  if (capacity == 0) throw std::invalid_argument("record queue capacity must be >= 1");
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_)
    throw std::runtime_error("cannot create run record " + path.string() + ": " +
                             std::strerror(errno));
  for (std::string& slot : slots_) slot.reserve(slot_bytes);
  if (std::fwrite(kPreamble, 1, sizeof kPreamble, file_) != sizeof kPreamble) fail(errno);
  sem_init(&wake_, 0, 0);
  writer_ = std::thread([this] {
    for (;;) {
      while (sem_wait(&wake_) != 0 && errno == EINTR) {}
      drain();
      if (stopping_.load(std::memory_order_acquire)) {
        drain();
        return;
      }
    }
  });
}

AsyncRecordWriter::~AsyncRecordWriter() {
  try {
    close();
  } catch (const std::exception&) {
    // A destructor cannot report; close() is where a caller learns of a write error.
  }
}

bool AsyncRecordWriter::append(const RecordEntry& entry) {
  const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
  if (tail - head_.load(std::memory_order_acquire) >= slots_.size()) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  // The payload only: the writer thread seals the frame (checksums) off the loop.
  std::string& slot = slots_[tail % slots_.size()];
  slot.resize(kRecordFrameHeaderBytes + entry.ByteSizeLong());
  entry.SerializeWithCachedSizesToArray(
      reinterpret_cast<std::uint8_t*>(slot.data() + kRecordFrameHeaderBytes));
  kinds_[tail % slots_.size()] = entry.entry_case();
  tail_.store(tail + 1, std::memory_order_release);
  sem_post(&wake_);
  return true;
}

void AsyncRecordWriter::drain() {
  std::uint64_t head = head_.load(std::memory_order_relaxed);
  const std::uint64_t tail = tail_.load(std::memory_order_acquire);
  if (head == tail) return;
  for (; head < tail; ++head) {
    std::string& slot = slots_[head % slots_.size()];
    const RecordEntry::EntryCase kind = kinds_[head % slots_.size()];
    if (!failed()) {
      seal_record_frame(slot.data(),
                        static_cast<std::uint32_t>(slot.size() - kRecordFrameHeaderBytes));
      write_frame(slot, kind);
    }
    if (observer_) observer_->on_entry(slot);
    head_.store(head + 1, std::memory_order_release);
  }
  if (!failed() && std::fflush(file_) != 0) fail(errno);
}

void AsyncRecordWriter::write_frame(std::string_view frame, RecordEntry::EntryCase kind) {
  if (const std::string_view copy = repeat_.copy_before(kind); !copy.empty()) {
    if (std::fwrite(copy.data(), 1, copy.size(), file_) != copy.size()) return fail(errno);
    repeat_.written(copy, RecordEntry::kHeader);
  }
  if (std::fwrite(frame.data(), 1, frame.size(), file_) != frame.size()) return fail(errno);
  repeat_.written(frame, kind);
  written_.fetch_add(1, std::memory_order_relaxed);
}

void AsyncRecordWriter::fail(int error) {
  if (failed()) return;
  write_errno_ = error;
  failed_.store(true, std::memory_order_release);
}

std::string AsyncRecordWriter::failure() const {
  if (!failed()) return {};
  return "cannot write run record " + path_.string() + ": " + std::strerror(write_errno_);
}

void AsyncRecordWriter::close() {
  if (closed_) return;
  closed_ = true;
  stopping_.store(true, std::memory_order_release);
  sem_post(&wake_);
  writer_.join();
  sem_destroy(&wake_);
  if (file_ && std::fclose(file_) != 0) fail(errno);
  file_ = nullptr;
  if (failed()) throw std::runtime_error(failure());
}

// ---------------------------------------------------------------- reading

namespace {

void add_loss(RecordContents& contents, std::uint64_t first, std::uint64_t end) {
  if (!contents.losses.empty() && contents.losses.back().end_byte == first)
    contents.losses.back().end_byte = end;  // one region, however many frames it spans
  else
    contents.losses.push_back({first, end, -1, -1});
}

// Frames from `at` to the end: intact entries kept, damaged regions skipped and recorded, a frame
// cut by the end of the file (with no frame header after it) marks the record truncated. A frame
// that does not read (damaged payload, or a size running past the end) is not trusted to say
// where the next one starts: the next frame header after its own does. The scanner finds and
// checks frames with work linear in the bytes (frame_scan.h).
void parse_frames(std::string_view bytes, std::size_t at, FrameScanner& scanner,
                  RecordContents& contents) {
  while (at < bytes.size()) {
    std::uint32_t size = 0;
    const Frame frame =
        bytes.size() - at < kRecordFrameHeaderBytes ? Frame::kCut : scanner.frame_at(at, &size);
    RecordEntry entry;
    if (frame == Frame::kIntact &&
        entry.ParseFromArray(bytes.data() + at + kRecordFrameHeaderBytes, static_cast<int>(size))) {
      if (entry.has_inputs() && contents.inputs_crc32c == 0)
        contents.inputs_crc32c = load_le32(bytes.data() + at + 8);
      contents.entries.push_back(std::move(entry));
      contents.offsets.push_back(at);
      at += kRecordFrameHeaderBytes + size;
      continue;
    }
    const std::size_t next = scanner.next_frame(at + 1);
    if (frame == Frame::kCut && next == std::string_view::npos) {
      contents.truncated = true;
      contents.truncated_at = at;
      return;
    }
    add_loss(contents, at, next == std::string_view::npos ? bytes.size() : next);
    if (next == std::string_view::npos) return;
    at = next;
  }
}

// A record from before checksums: varint size, then the entry. Must start with its header.
void parse_unchecksummed(std::string_view bytes, const std::string& source,
                         RecordContents& contents) {
  google::protobuf::io::ArrayInputStream raw(bytes.data(), static_cast<int>(bytes.size()));
  google::protobuf::io::CodedInputStream coded(&raw);
  coded.SetTotalBytesLimit(INT32_MAX);
  for (;;) {
    const int start = coded.CurrentPosition();
    if (start == static_cast<int>(bytes.size())) break;
    std::uint32_t size = 0;
    if (!coded.ReadVarint32(&size) ||
        static_cast<std::size_t>(coded.CurrentPosition()) + size > bytes.size()) {
      contents.truncated = true;
      contents.truncated_at = static_cast<std::uint64_t>(start);
      break;
    }
    const auto limit = coded.PushLimit(static_cast<int>(size));
    RecordEntry entry;
    if (!entry.ParseFromCodedStream(&coded) || !coded.ConsumedEntireMessage() ||
        (contents.entries.empty() && !entry.has_header()))
      throw std::runtime_error(source +
                               ": not a run record, or a corrupt one: no rths record "
                               "preamble, no checksummed entry, and entry " +
                               std::to_string(contents.entries.size()) + " at byte " +
                               std::to_string(start) + " does not parse as an unchecksummed one");
    coded.PopLimit(limit);
    contents.entries.push_back(std::move(entry));
    contents.offsets.push_back(static_cast<std::uint64_t>(start));
  }
  contents.checksummed = false;
}

// Each loss's intact neighbours, from the steps around it.
void locate_losses(RecordContents& contents) {
  for (RecordLoss& loss : contents.losses) {
    for (std::size_t i = 0; i < contents.entries.size(); ++i) {
      if (!contents.entries[i].has_step()) continue;
      const std::int64_t step = contents.entries[i].step().step();
      if (contents.offsets[i] < loss.first_byte) loss.last_step_before = step;
      if (contents.offsets[i] >= loss.end_byte) {
        loss.first_step_after = step;
        break;
      }
    }
  }
}

// The value most steps agree on (ties: the larger); 0 when none.
template <class Count>
int most_common(const std::vector<const StepRecord*>& steps, Count count) {
  std::map<int, std::size_t> seen;
  for (const StepRecord* s : steps) ++seen[count(*s)];
  int best = 0;
  std::size_t most = 0;
  for (const auto& [value, n] : seen)
    if (n >= most) best = value, most = n;
  return best;
}

// dt as the median of (time difference / step difference) over consecutive intact steps whose
// times rise; 0 when no two steps say.
double dt_from_step_times(const std::vector<const StepRecord*>& steps) {
  std::vector<double> dts;
  for (std::size_t i = 1; i < steps.size(); ++i) {
    const std::int64_t gap = steps[i]->step() - steps[i - 1]->step();
    const double dt = (steps[i]->time() - steps[i - 1]->time()) / static_cast<double>(gap);
    if (gap > 0 && std::isfinite(dt) && dt > 0) dts.push_back(dt);
  }
  if (dts.empty()) return 0.0;
  std::nth_element(dts.begin(), dts.begin() + static_cast<std::ptrdiff_t>(dts.size() / 2),
                   dts.end());
  return dts[dts.size() / 2];
}

// No intact header but intact steps: the header the steps imply, and what was assumed.
void assume_header(RecordContents& contents) {
  const std::vector<const StepRecord*> steps = contents.steps();
  if (contents.header() || steps.empty()) return;
  RunHeader h;
  h.set_schema_version(kSchemaVersion);
  h.set_dofs(most_common(steps, [](const StepRecord& s) { return s.displacement_size(); }));
  h.set_actuators(most_common(steps, [](const StepRecord& s) { return s.command_size(); }));
  h.set_dt(dt_from_step_times(steps));
  const StepRecord* widest = steps.front();
  for (const StepRecord* s : steps)
    if (s->links_size() > widest->links_size()) widest = s;
  std::string links;
  for (const LinkSample& link : widest->links()) {
    h.add_link_node_ids(link.node_id());
    if (!links.empty()) links += ',';  // piece by piece: GCC 12 misreads "," + ... (-Wrestrict)
    links += std::to_string(link.node_id());
  }
  const config::Study* study = contents.study_as_run();
  if (study) *h.mutable_study() = *study;
  std::ostringstream text;
  text << contents.source << ": no intact header (every copy damaged or missing): read with one "
       << "assumed from the steps: dofs " << h.dofs() << " and actuators " << h.actuators()
       << " (the step frames' sizes), dt " << h.dt() << " s (the step times), links [" << links
       << "] (the link samples), "
       << (study ? "the study from the inputs entry" : "no study (the inputs entry is lost too)")
       << "; run id, case and clock unknown";
  contents.assumed = text.str();
  contents.assumed_header = std::move(h);
}

void compose_warning(RecordContents& contents, const std::string& source, std::size_t bytes) {
  std::string& w = contents.warning;
  const auto add = [&w](const std::string& text) { w += (w.empty() ? "" : "; ") + text; };
  if (!contents.checksummed)
    add(source + " was written without checksums (a record from before rths checked them): " +
        "its entries are read unverified");
  if (contents.lost_entries()) add(contents.loss_report());
  if (!contents.assumed.empty()) add(contents.assumed);
  if (contents.truncated)
    add(source + ": truncated after " + std::to_string(contents.entries.size()) +
        " complete entries (byte " + std::to_string(contents.truncated_at) + " of " +
        std::to_string(bytes) + "); the rest was lost");
}

bool is_prefix_of_preamble(std::string_view bytes) {
  return bytes.size() < kRecordPreambleBytes && record_preamble().substr(0, bytes.size()) == bytes;
}

}  // namespace

RecordContents parse_record(std::string_view bytes, const std::string& source) {
  RecordContents contents;
  contents.source = source;
  FrameScanner scanner(bytes);
  std::uint32_t size = 0;
  if (bytes.substr(0, kRecordPreambleBytes) == record_preamble()) {
    parse_frames(bytes, kRecordPreambleBytes, scanner, contents);
  } else if (is_prefix_of_preamble(bytes)) {
    contents.truncated = true;  // cut before its first entry
  } else if (scanner.frame_at(kRecordPreambleBytes, &size) != Frame::kNone) {
    add_loss(contents, 0, kRecordPreambleBytes);  // a damaged preamble
    parse_frames(bytes, kRecordPreambleBytes, scanner, contents);
  } else if (const std::size_t first = scanner.next_frame(0); first != std::string_view::npos) {
    add_loss(contents, 0, first);
    parse_frames(bytes, first, scanner, contents);
  } else {
    parse_unchecksummed(bytes, source, contents);
  }
  contents.examined_bytes = scanner.examined();
  locate_losses(contents);
  assume_header(contents);
  compose_warning(contents, source, bytes.size());
  return contents;
}

RecordContents read_record(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open run record " + path.string());
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_record(bytes, path.string());
}

const RunHeader* RecordContents::header() const {
  for (const auto& e : entries)
    if (e.has_header()) return &e.header();
  return nullptr;
}

const RunHeader* RecordContents::header_or_assumed() const {
  if (const RunHeader* h = header()) return h;
  return assumed_header ? &*assumed_header : nullptr;
}

const RunFooter* RecordContents::footer() const {
  for (const auto& e : entries)
    if (e.has_footer()) return &e.footer();
  return nullptr;
}

const config::Study* RecordContents::study_as_run() const {
  for (const RecordEntry& e : entries)
    if (e.has_inputs()) return &e.inputs().study();
  return header() ? &header()->study() : nullptr;
}

std::vector<const StepRecord*> RecordContents::steps() const {
  std::vector<const StepRecord*> out;
  for (const auto& e : entries)
    if (e.has_step()) out.push_back(&e.step());
  return out;
}

std::vector<std::pair<std::int64_t, std::int64_t>> RecordContents::missing_steps() const {
  std::vector<std::pair<std::int64_t, std::int64_t>> out;
  std::int64_t expected = 0;
  for (const StepRecord* s : steps()) {
    if (s->step() > expected) out.emplace_back(expected, s->step() - 1);
    expected = std::max(expected, s->step() + 1);
  }
  // The footer counts the exchanges; the record holds one more step (step 0).
  if (const RunFooter* f = footer(); f && f->has_counters()) {
    const auto recorded = static_cast<std::int64_t>(f->counters().steps()) + 1;
    if (recorded > expected) out.emplace_back(expected, recorded - 1);
  }
  return out;
}

std::string RecordLoss::describe() const {
  std::string out = "bytes " + std::to_string(first_byte) + "-" + std::to_string(end_byte - 1) +
                    " (" + std::to_string(end_byte - first_byte) + " bytes): ";
  const auto range = [](std::int64_t a, std::int64_t b) {
    return a == b ? "step " + std::to_string(a) + " lost"
                  : "steps " + std::to_string(a) + "-" + std::to_string(b) + " lost";
  };
  if (last_step_before < 0 && first_step_after < 0) return out + "no intact step around it";
  if (first_step_after < 0)
    return out + "after step " + std::to_string(last_step_before) + " (every later step lost)";
  if (first_step_after > last_step_before + 1)
    return out + range(last_step_before + 1, first_step_after - 1);
  if (last_step_before < 0) return out + "before step 0 (the preamble or the header)";
  return out + "no step lost (an entry between step " + std::to_string(last_step_before) +
         " and step " + std::to_string(first_step_after) + ")";
}

std::string RecordContents::loss_report() const {
  if (losses.empty()) return {};
  std::uint64_t bytes = 0;
  for (const RecordLoss& loss : losses) bytes += loss.end_byte - loss.first_byte;
  std::string out = source + ": " + std::to_string(losses.size()) + " damaged region" +
                    (losses.size() == 1 ? "" : "s") + " (" + std::to_string(bytes) +
                    " bytes) skipped: ";
  for (std::size_t i = 0; i < losses.size(); ++i) out += (i ? "; " : "") + losses[i].describe();
  return out;
}

int recorded_columns(const RunHeader& header) {
  return header.recorded_dofs_size() > 0 ? header.recorded_dofs_size() : header.dofs();
}

std::vector<int> recorded_dofs(const RunHeader& header) {
  if (header.recorded_dofs_size() > 0)
    return {header.recorded_dofs().begin(), header.recorded_dofs().end()};
  std::vector<int> every(static_cast<std::size_t>(std::max(header.dofs(), 0)));
  std::iota(every.begin(), every.end(), 0);
  return every;
}

}  // namespace rths::runtime
