#pragma once
// Run record: a stream of rths.runtime.RecordEntry, each written length-delimited (varint size,
// then the bytes) and flushed to the OS at once, so a crash of the writer loses at most the entry
// being written. A record is one header, then steps and events, then a footer when the run ended
// in an orderly way (a record without a footer was cut short).

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "rths/proto/runtime.pb.h"

namespace rths::runtime {

class RecordWriter {
 public:
  // Creates (truncates) the file; throws std::runtime_error naming it when it cannot.
  explicit RecordWriter(const std::filesystem::path& path);
  ~RecordWriter();
  RecordWriter(const RecordWriter&) = delete;
  RecordWriter& operator=(const RecordWriter&) = delete;
  // Appends and flushes one entry. Throws on a write error.
  void write(const RecordEntry& entry);
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::string buffer_;
};

struct RecordContents {
  std::vector<RecordEntry> entries;
  bool truncated = false;  // the file ends inside an entry; everything before it was read
  std::string warning;     // says where, when truncated
  const RunHeader* header() const;
  const RunFooter* footer() const;
  std::vector<const StepRecord*> steps() const;
};

// Reads every complete entry. Throws std::runtime_error naming the file when it cannot be opened
// or an entry is corrupt (not merely cut off).
RecordContents read_record(const std::filesystem::path& path);

}  // namespace rths::runtime
