#pragma once
// Outputs never overwrite inputs: every command hands its output paths and its input paths to
// refuse_output_over_input before it writes anything.
//   An output is "one of the inputs" when both name the same file: the same inode when both
//   exist (hard links, symlinks, "./a" vs "a"), else the same lexically normal absolute path.
//   A directory output is one of the inputs when an input lies inside it and `output_is_dir`.
// Throws std::invalid_argument "<output name> 'OUT' is the input <input name> 'IN': ..." (exit 2).

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace rths::util {

struct NamedPath {
  std::string name;  // the flag or argument: "--csv", "record"
  std::filesystem::path path;
};

// True when `a` and `b` name the same file (see above).
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);

void refuse_output_over_input(const NamedPath& output, const std::vector<NamedPath>& inputs);

}  // namespace rths::util
