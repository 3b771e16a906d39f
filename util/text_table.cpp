#include "util/text_table.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace rths::util {

TextTable::TextTable(std::vector<Column> columns) : columns_(std::move(columns)) {}

void TextTable::add_row(std::vector<std::string> cells) {
  if (cells.size() != columns_.size()) {
    throw std::invalid_argument("text table: a row of " + std::to_string(cells.size()) +
                                " cells for " + std::to_string(columns_.size()) + " columns");
  }
  rows_.push_back(std::move(cells));
}

std::string TextTable::render() const {
  std::vector<std::string> notes;
  std::vector<std::vector<std::string>> shown = rows_;
  for (auto& row : shown)
    for (std::size_t c = 0; c < row.size(); ++c)
      if (row[c].size() > columns_[c].max_width) {
        notes.push_back(row[c]);
        // Built apart and swapped in: GCC 12 misreads a replace of row[c] here (-Wrestrict).
        std::string mark(1, '[');
        mark += std::to_string(notes.size());
        mark += ']';
        row[c].swap(mark);
      }
  std::vector<std::size_t> width(columns_.size());
  for (std::size_t c = 0; c < columns_.size(); ++c) {
    width[c] = columns_[c].header.size();
    for (const auto& row : shown) width[c] = std::max(width[c], row[c].size());
  }
  std::ostringstream out;
  const auto line = [&](const std::vector<std::string>& cells) {
    std::string text;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const std::string pad(width[c] - cells[c].size(), ' ');
      const bool right = columns_[c].align == Align::kRight;
      text += (c ? "  " : "") + (right ? pad + cells[c] : cells[c] + pad);
    }
    text.erase(text.find_last_not_of(' ') + 1);
    out << text << "\n";
  };
  std::vector<std::string> headers;
  for (const Column& c : columns_) headers.push_back(c.header);
  line(headers);
  for (const auto& row : shown) line(row);
  for (std::size_t i = 0; i < notes.size(); ++i) out << "[" << i + 1 << "] " << notes[i] << "\n";
  return out.str();
}

}  // namespace rths::util
