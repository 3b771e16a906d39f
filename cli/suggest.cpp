#include "cli/suggest.h"

#include <algorithm>

namespace rths::cli {
namespace {

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> previous(b.size() + 1), current(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) previous[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t substitution = previous[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, substitution});
    }
    std::swap(previous, current);
  }
  return previous[b.size()];
}

}  // namespace

std::optional<std::string> closest(const std::string& word,
                                   const std::vector<std::string>& candidates) {
  std::optional<std::string> best;
  std::size_t best_distance = std::max<std::size_t>(1, word.size() / 3) + 1;
  for (const std::string& candidate : candidates) {
    const std::size_t d = edit_distance(word, candidate);
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  return best;
}

namespace {

std::vector<std::string> subcommand_names(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    names.push_back(sub->get_name());
  return names;
}

std::vector<std::string> flag_names(const CLI::App& app) {
  std::vector<std::string> flags;
  for (const CLI::Option* option : app.get_options()) {
    for (const std::string& name : option->get_lnames()) flags.push_back("--" + name);
  }
  return flags;
}

std::string unknown_command(const std::string& word, const std::string& path,
                            const std::vector<std::string>& names) {
  std::string message =
      "unknown command '" + word + "'" + (path == "rths" ? "" : " for `" + path + "`");
  if (const auto near = closest(word, names))
    return message + "; did you mean `" + path + " " + *near + "`?";
  message += "; commands:";
  for (const std::string& n : names) message += " " + n;
  return message;
}

std::string unknown_flag(const std::string& word, const std::string& path,
                         const std::vector<std::string>& flags) {
  std::string message = "unknown option '" + word + "' for `" + path + "`";
  if (const auto near = closest(word, flags)) return message + "; did you mean '" + *near + "'?";
  return message + " (see `" + path + " --help`)";
}

}  // namespace

std::string suggest_for_unknown(const CLI::App& app, int argc, const char* const* argv) {
  // Walks the words level by level: a subcommand name descends into it; a --flag is checked
  // against the flags of the level it appears at, so a nested command's slip is suggested from
  // its own flags; a bare word where a level needs a subcommand must be one of its names.
  const CLI::App* level = &app;
  std::string path = "rths";
  bool chose = false;
  for (int i = 1; i < argc; ++i) {
    std::string word = argv[i];
    if (word == "--") break;
    if (word.rfind("--", 0) == 0) {
      if (level == &app) continue;  // --help, --version: CLI11's own
      word = word.substr(0, word.find('='));
      const std::vector<std::string> flags = flag_names(*level);
      if (std::find(flags.begin(), flags.end(), word) == flags.end())
        return unknown_flag(word, path, flags);
      continue;
    }
    if (word.empty() || word[0] == '-') continue;
    const std::vector<std::string> names = subcommand_names(*level);
    if (std::find(names.begin(), names.end(), word) != names.end()) {
      level = level->get_subcommand(word);
      path += " " + word;
      chose = false;
      continue;
    }
    const bool needs_subcommand = level->get_require_subcommand_min() > 0 && !chose;
    if (needs_subcommand && !names.empty()) return unknown_command(word, path, names);
    chose = true;
  }
  return "";
}

}  // namespace rths::cli
