#include "results/table.h"

#include <algorithm>
#include <cctype>
#include <limits>
#include <stdexcept>

namespace rths::results {
namespace {
constexpr std::size_t kMaxIdentifier = 63;  // MATLAB's namelengthmax
}

bool is_identifier(const std::string& name) {
  if (name.empty() || name.size() > kMaxIdentifier) return false;
  if (!std::isalpha(static_cast<unsigned char>(name.front()))) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

std::string identifier(const std::string& text) {
  std::string out;
  for (char c : text) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  if (out.empty() || !std::isalpha(static_cast<unsigned char>(out.front()))) out = "x" + out;
  if (out.size() > kMaxIdentifier) out.resize(kMaxIdentifier);
  return out;
}

void pad_with_nan(std::vector<std::vector<double>*> columns) {
  std::size_t longest = 0;
  for (const auto* c : columns) longest = std::max(longest, c->size());
  for (auto* c : columns) c->resize(longest, std::numeric_limits<double>::quiet_NaN());
}

void Table::add(Column column) {
  if (!is_identifier(column.name)) {
    throw std::invalid_argument("table column '" + column.name +
                                "' is not a valid variable name (a letter, then letters, digits or "
                                "'_', at most 63 characters)");
  }
  if (!column.unit.empty()) {
    std::string tail = "_";  // appended: GCC 12 misreads `"_" + std::string` here (-Wrestrict)
    tail += unit_suffix(column.unit);
    if (column.name.size() <= tail.size() ||
        column.name.compare(column.name.size() - tail.size(), tail.size(), tail) != 0)
      throw std::invalid_argument("table column '" + column.name + "' (unit " + column.unit +
                                  ") must end in '" + tail +
                                  "': [<case>_]<quantity><index>_<unit>");
  }
  for (const Column& c : columns_) {
    if (c.name == column.name)
      throw std::invalid_argument("table column '" + column.name + "' appears twice");
  }
  if (!columns_.empty() && column.size() != rows()) {
    throw std::invalid_argument("table column '" + column.name + "' has " +
                                std::to_string(column.size()) + " rows, the columns before it " +
                                std::to_string(rows()));
  }
  columns_.push_back(std::move(column));
}

std::string unit_suffix(const std::string& unit) {
  std::string out;
  for (char c : unit) {
    if (c == '/')
      out += "_per_";
    else if (c == '%')
      out += "pct";
    else if (c != '^')
      out += c;
  }
  return out;
}

void Table::add_numbers(const std::string& name, const std::string& unit,
                        std::vector<double> values) {
  Column c;
  c.name = name;
  c.unit = unit;
  c.numbers = std::move(values);
  add(std::move(c));
}

void Table::add_texts(const std::string& name, const std::string& unit,
                      std::vector<std::string> values) {
  Column c;
  c.name = name;
  c.unit = unit;
  c.is_text = true;
  c.texts = std::move(values);
  add(std::move(c));
}

void Table::set_attribute(const std::string& key, const std::string& value) {
  number_attributes_.erase(key);
  attributes_[key] = value;
}

void Table::set_number_attribute(const std::string& key, double value) {
  attributes_.erase(key);
  number_attributes_[key] = value;
}

const Column& Table::column(const std::string& name) const {
  for (const Column& c : columns_) {
    if (c.name == name) return c;
  }
  throw std::out_of_range("no column '" + name + "' in the table");
}

}  // namespace rths::results
