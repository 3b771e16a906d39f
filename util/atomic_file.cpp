#include "util/atomic_file.h"

#include <stdexcept>
#include <system_error>

namespace rths::util {

AtomicFile::AtomicFile(std::filesystem::path target)
    : target_(std::move(target)), partial_(target_.string() + ".partial") {
  if (target_.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(target_.parent_path(), ec);
    if (ec)
      throw std::runtime_error("cannot create folder " + target_.parent_path().string() + ": " +
                               ec.message());
  }
  out_.open(partial_, std::ios::out | std::ios::trunc);
  if (!out_) throw std::runtime_error("cannot write " + partial_.string());
  out_.precision(17);
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    out_.close();
    std::error_code ignored;
    std::filesystem::remove(partial_, ignored);
  }
}

void AtomicFile::commit() {
  out_.flush();
  if (!out_) throw std::runtime_error("failed while writing " + partial_.string());
  out_.close();
  std::error_code ec;
  std::filesystem::rename(partial_, target_, ec);
  if (ec)
    throw std::runtime_error("cannot rename " + partial_.string() + " to " + target_.string() +
                             ": " + ec.message());
  committed_ = true;
}

}  // namespace rths::util
