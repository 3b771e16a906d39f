#pragma once
// A plain-text table for summaries a person reads in a terminal or a .txt file: each column as
// wide as its widest cell, two spaces apart, numbers right-aligned and words left-aligned.
// A cell longer than its column's `max_width` is not allowed to push the columns apart: it is
// shown as a note marker ("[1]") and written out in full below the table ("[1] <text>"), so
// long case names, delay chains or compensator descriptions never break the columns.

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace rths::util {

class TextTable {
 public:
  enum class Align { kLeft, kRight };
  struct Column {
    Column(std::string header_text, Align alignment = Align::kLeft, std::size_t max_characters = 40)
        : header(std::move(header_text)), align(alignment), max_width(max_characters) {}
    std::string header;
    Align align;
    std::size_t max_width;  // characters; longer cells become notes
  };

  explicit TextTable(std::vector<Column> columns);
  // One row, one cell per column. Throws std::invalid_argument on a wrong count.
  void add_row(std::vector<std::string> cells);
  // The table, one line per row after the header, then the notes.
  std::string render() const;

 private:
  std::vector<Column> columns_;
  std::vector<std::vector<std::string>> rows_;
};

}  // namespace rths::util
