#pragma once
// "Did you mean": an unknown subcommand or flag named with the nearest known one.
#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

namespace rths::cli {

// The candidate closest to `word` by edit distance, when close enough to be a slip (at most a
// third of the word's length, and at least 1 edit allowed).
std::optional<std::string> closest(const std::string& word,
                                   const std::vector<std::string>& candidates);

// Before parsing, level by level (`rths pki init ...` is three levels): an unknown subcommand or
// an unknown --flag gets "did you mean" from that level's own subcommands and flags. Returns the
// message, or empty when the words are known.
std::string suggest_for_unknown(const CLI::App& app, int argc, const char* const* argv);

}  // namespace rths::cli
