#pragma once
// Output files that are either complete or absent: content goes to "<name>.partial" and is
// renamed over the target only after a successful flush, so an error or a crash never leaves a
// half-written file that looks complete.

#include <filesystem>
#include <fstream>
#include <string>

namespace rths::util {

class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path target);
  ~AtomicFile();  // removes the partial file unless commit() succeeded
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::ofstream& stream() { return out_; }
  // The file being written, for writers that open it by name (HDF5, MAT); commit() then renames it.
  const std::filesystem::path& partial_path() const { return partial_; }
  // Flushes, closes and renames into place. Throws std::runtime_error naming the file on failure.
  void commit();

 private:
  std::filesystem::path target_, partial_;
  std::ofstream out_;
  bool committed_ = false;
};

}  // namespace rths::util
