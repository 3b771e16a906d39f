#pragma once
// Numeric text columns, as labs and their tools write them: the one reader of plain-text numbers
// in rths (ground-motion columns, delay traces; AT2 has its own fixed-width format but the same
// number rule).
//   One row per line; '#' starts a comment to the end of the line; fields are separated by
//   spaces, tabs or commas; blank and comment-only lines are skipped; CRLF line ends accepted.
//   With `title_allowed`, the first non-blank line may be a title ("time,accel"): it is kept in
//   `title` (its fields) when any of its fields is not a number.
//   Every field must be a whole finite number (parse_finite).
// Errors throw std::invalid_argument naming "PATH:LINE:" and the field, or the file that cannot
// be opened (with `what` saying what it was meant to be: "delay trace", "ground-motion file").

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/number_text.h"

namespace rths::study {

struct TextRow {
  int line = 0;  // 1-based line number in the file
  std::vector<double> values;
};

struct TextColumns {
  std::vector<std::string> title;  // empty when the file has no title line
  std::vector<TextRow> rows;
};

TextColumns read_text_columns(const std::filesystem::path& path, const std::string& what,
                              bool title_allowed = false);

// What separates fields on a line: space, tab, comma, CR. A line holding only these (once its
// comment is cut) has no row; every counter of rows (motion_file_extent) uses this one rule.
inline constexpr std::string_view kFieldSeparators = " \t,\r";
constexpr bool is_field_separator(char c) {
  return kFieldSeparators.find(c) != std::string_view::npos;
}

// The same rows, one at a time, none kept: visit(line, values) for each (values valid during the
// call only), the title's fields into `title` when given. A reader that keeps only what it needs
// of each row holds its samples, not an object per line (read_text_columns' TextRow: about 78
// bytes a one-column sample, where the sample is 8).
using TextRowVisitor = std::function<void(int line, const std::vector<double>& values)>;
void for_each_text_row(const std::filesystem::path& path, const std::string& what,
                       bool title_allowed, const TextRowVisitor& visit,
                       std::vector<std::string>* title = nullptr);

// Why `path` cannot be a text file of numbers, or empty when it may be: it does not exist, is a
// directory (not a regular file), is empty, or holds binary bytes (a NUL or a control character
// other than tab, CR, LF, FF in its first 4096 bytes). `what` names it: "ground-motion file".
std::string not_a_text_file(const std::filesystem::path& path, const std::string& what);

// "PATH:LINE: ", how every error about a place in a text file starts.
std::string text_position(const std::filesystem::path& path, int line);

}  // namespace rths::study
