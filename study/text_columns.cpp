#include "study/text_columns.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>

namespace rths::study {

std::string not_a_text_file(const std::filesystem::path& path, const std::string& what) {
  std::error_code error;
  const auto status = std::filesystem::status(path, error);
  if (!std::filesystem::exists(status)) return path.string() + ": no such " + what;
  if (std::filesystem::is_directory(status))
    return path.string() + " is a directory, not a " + what;
  if (!std::filesystem::is_regular_file(status))
    return path.string() + " is not a regular file, not a " + what;
  std::ifstream in(path, std::ios::binary);
  if (!in) return path.string() + ": cannot open " + what;
  char head[4096];
  in.read(head, sizeof head);
  const std::streamsize n = in.gcount();
  if (n == 0) return path.string() + " is empty, not a " + what;
  for (std::streamsize i = 0; i < n; ++i) {
    const auto byte = static_cast<unsigned char>(head[i]);
    if (byte < 0x20 && byte != '\t' && byte != '\n' && byte != '\r' && byte != '\f')
      return path.string() + " holds binary data (byte " + std::to_string(i) + " is " +
             core::printable(std::string_view(head + i, 1)) + "), not a " + what + " (text)";
  }
  return "";
}

std::string text_position(const std::filesystem::path& path, int line) {
  return path.string() + ":" + std::to_string(line) + ": ";
}

void for_each_text_row(const std::filesystem::path& path, const std::string& what,
                       bool title_allowed, const TextRowVisitor& visit,
                       std::vector<std::string>* title) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path.string() + ": cannot open " + what);
  std::string line;
  int number = 0;
  bool first = true;
  std::vector<std::string> fields;
  std::vector<double> values;
  while (std::getline(in, line)) {
    ++number;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    fields.clear();
    std::size_t pos = 0;
    for (;;) {
      pos = line.find_first_not_of(kFieldSeparators, pos);
      if (pos == std::string::npos) break;
      const std::size_t end = std::min(line.find_first_of(kFieldSeparators, pos), line.size());
      fields.push_back(line.substr(pos, end - pos));
      pos = end;
    }
    if (fields.empty()) continue;
    values.clear();
    const std::string* bad = nullptr;
    for (const std::string& field : fields) {
      const auto value = core::parse_finite(field);
      if (!value) {
        bad = &field;
        break;
      }
      values.push_back(*value);
    }
    if (bad && first && title_allowed) {
      if (title) *title = fields;
      first = false;
      continue;
    }
    if (bad)
      throw std::invalid_argument(text_position(path, number) + "'" + core::printable(*bad) +
                                  "' is not a finite number");
    first = false;
    visit(number, values);
  }
}

TextColumns read_text_columns(const std::filesystem::path& path, const std::string& what,
                              bool title_allowed) {
  TextColumns out;
  for_each_text_row(
      path, what, title_allowed,
      [&out](int line, const std::vector<double>& values) {
        out.rows.push_back({line, values});
      },
      &out.title);
  return out;
}

}  // namespace rths::study
