#include "util/distinct_paths.h"

#include <stdexcept>
#include <system_error>

namespace rths::util {

bool same_file(const std::filesystem::path& a, const std::filesystem::path& b) {
  std::error_code error;
  if (std::filesystem::exists(a, error) && std::filesystem::exists(b, error)) {
    const bool same = std::filesystem::equivalent(a, b, error);
    if (!error) return same;
  }
  const auto normal = [](const std::filesystem::path& p) {
    std::error_code ignored;
    return std::filesystem::weakly_canonical(std::filesystem::absolute(p), ignored)
        .lexically_normal();
  };
  return normal(a) == normal(b);
}

void refuse_output_over_input(const NamedPath& output, const std::vector<NamedPath>& inputs) {
  if (output.path.empty()) return;
  for (const NamedPath& input : inputs) {
    if (input.path.empty() || !same_file(output.path, input.path)) continue;
    throw std::invalid_argument(output.name + " '" + output.path.string() + "' is the input " +
                                input.name + " '" + input.path.string() +
                                "': an output never overwrites an input; write it elsewhere");
  }
}

}  // namespace rths::util
