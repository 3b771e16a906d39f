#include "study/motion_files.h"

#include "study/memory_budget.h"
#include "study/text_columns.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace rths::study {
namespace {

// getline that also drops the '\r' of CRLF files (PEER NGA files are CRLF).
bool read_line(std::istream& in, std::string& line) {
  if (!std::getline(in, line)) return false;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return true;
}

std::string upper(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return text;
}

// Parses one number at `p` (after optional spaces); returns false if none is there.
bool parse_number(const char*& p, double& value) {
  char* end = nullptr;
  value = std::strtod(p, &end);
  if (end == p) return false;
  p = end;
  return true;
}

// Every number on a line. strtod stops at the sign of the next value, so fixed-width fields that
// touch ("-0.12345-0.23456", as 8F10.5 prints large values) split correctly. Fortran 'D'
// exponents are read as 'E'. Anything else is an error naming file, line and text.
void parse_values(std::string line, const std::filesystem::path& path, int line_number,
                  std::vector<double>& out) {
  for (char& c : line) {
    if (c == 'D' || c == 'd') c = 'E';
  }
  const char* p = line.c_str();
  while (true) {
    while (*p != '\0' && std::isspace(static_cast<unsigned char>(*p))) ++p;
    if (*p == '\0') return;
    const char* start = p;
    double value = 0.0;
    if (!parse_number(p, value) || !std::isfinite(value)) {
      std::string token(start);
      token = token.substr(0, token.find_first_of(" \t"));
      throw std::invalid_argument(text_position(path, line_number) + "'" + token +
                                  "' is not a finite number");
    }
    out.push_back(value);
  }
}

// Far above any real record (1e8 samples = 5.8 days at 5 ms), and small enough that the count
// converts to long and the header alone cannot make the reader reserve gigabytes.
constexpr long kMaxAt2Points = 100'000'000;
// Samples reserved up front; a record with more grows the vector as values actually arrive.
constexpr std::size_t kAt2Reserve = 1 << 20;

struct At2Header {
  long npts = 0;
  double dt = 0.0;
};

// "NPTS=  1559, DT=   .0200 SEC" (PEER classic and NGA) or "7814    0.0050    NPTS, DT"
// (NGA-West2 new format).
At2Header parse_at2_header(const std::string& line, const std::filesystem::path& path) {
  const std::string text = upper(line);
  At2Header header;
  const auto fail = [&](const std::string& why) {
    return std::invalid_argument(text_position(path, 4) + why + " in AT2 header line '" + line +
                                 "' (expected 'NPTS= n, DT= dt SEC' or 'n dt NPTS, DT')");
  };
  const std::size_t npts_at = text.find("NPTS");
  if (npts_at == std::string::npos) throw fail("no NPTS");
  std::size_t after = text.find_first_not_of(' ', npts_at + 4);
  if (after != std::string::npos && text[after] == '=') {
    const char* p = text.c_str() + after + 1;
    double npts = 0.0;
    if (!parse_number(p, npts)) throw fail("no number after NPTS=");
    const std::size_t dt_at = text.find("DT", static_cast<std::size_t>(p - text.c_str()));
    if (dt_at == std::string::npos) throw fail("no DT");
    const std::size_t equals = text.find_first_not_of(' ', dt_at + 2);
    if (equals == std::string::npos || text[equals] != '=') throw fail("no '=' after DT");
    const char* q = text.c_str() + equals + 1;
    if (!parse_number(q, header.dt)) throw fail("no number after DT=");
    if (npts != std::floor(npts)) throw fail("NPTS is not a whole number");
    if (!(npts <= kMaxAt2Points)) throw fail("NPTS above " + std::to_string(kMaxAt2Points));
    header.npts = static_cast<long>(npts);
  } else {
    const char* p = text.c_str();
    double npts = 0.0;
    if (!parse_number(p, npts) || !parse_number(p, header.dt)) {
      throw fail("no 'NPTS=' and no two leading numbers");
    }
    if (npts != std::floor(npts)) throw fail("NPTS is not a whole number");
    if (!(npts <= kMaxAt2Points)) throw fail("NPTS above " + std::to_string(kMaxAt2Points));
    header.npts = static_cast<long>(npts);
  }
  if (header.npts <= 0) throw fail("NPTS must be > 0");
  if (!(header.dt > 0.0) || !std::isfinite(header.dt)) throw fail("DT must be > 0");
  return header;
}

// Reads the 4 header lines of an AT2 file from `in` and parses the 4th (parse_at2_header).
At2Header read_at2_header(std::istream& in, const std::filesystem::path& path) {
  std::string line;
  for (int i = 1; i <= 3; ++i) {
    if (!read_line(in, line)) {
      throw std::invalid_argument(path.string() + ": AT2 header ends at line " + std::to_string(i) +
                                  " (expected 4 header lines)");
    }
  }
  if (!read_line(in, line)) {
    throw std::invalid_argument(path.string() + ": AT2 header has no 4th line with NPTS and DT");
  }
  return parse_at2_header(line, path);
}

// The lines of a text file holding anything but field separators (is_field_separator) whose
// first such character is not '#': what for_each_text_row takes as a title or a row. Scans bytes
// only.
std::uint64_t count_data_lines(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path.string() + ": cannot open ground-motion file");
  std::vector<char> block(1 << 20);
  std::uint64_t lines = 0;
  bool at_line_start = true;  // no character but blanks seen yet on this line
  while (in) {
    in.read(block.data(), static_cast<std::streamsize>(block.size()));
    const std::streamsize got = in.gcount();
    for (std::streamsize i = 0; i < got; ++i) {
      const char c = block[static_cast<std::size_t>(i)];
      if (c == '\n') {
        at_line_start = true;
      } else if (at_line_start && !is_field_separator(c)) {
        at_line_start = false;
        if (c != '#') ++lines;
      }
    }
  }
  return lines;
}

}  // namespace

std::optional<MotionFileExtent> motion_file_extent(const std::filesystem::path& path, bool at2,
                                                   double column_dt) {
  require_motion_file_size(path);
  if (at2) {
    std::ifstream in(path);
    if (!in) throw std::invalid_argument(path.string() + ": cannot open AT2 file");
    const At2Header header = read_at2_header(in, path);
    return MotionFileExtent{static_cast<std::uint64_t>(header.npts), header.dt};
  }
  if (column_dt == 0.0) return std::nullopt;  // not given: the file's time column states it
  const std::uint64_t lines = column_dt > 0.0 ? count_data_lines(path) : 0;
  const MotionFileExtent extent{lines > 0 ? lines - 1 : 0, column_dt};
  if (!(column_dt > 0.0) || !std::isfinite(extent.seconds())) {
    throw std::invalid_argument(
        path.string() + ": motion.column_dt = " + core::format_number(column_dt) + " s over " +
        std::to_string(extent.samples) +
        " samples: the step must be > 0 (or 0: the file's time column) and the record finite");
  }
  return extent;
}

std::uintmax_t motion_file_limit_bytes() {
  return std::min<std::uintmax_t>(kMaxMotionFileBytes,
                                  memory_limit_bytes() / kMotionReadBytesPerFileByte);
}

void require_motion_file_size(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return;
  const std::uintmax_t bytes = std::filesystem::file_size(path, error);
  const std::uintmax_t limit = motion_file_limit_bytes();
  if (error || bytes <= limit) return;
  const auto mib = [](std::uintmax_t b) {
    std::ostringstream text;
    text.precision(1);
    text << std::fixed << static_cast<double>(b) / (1024.0 * 1024.0) << " MiB";
    return text.str();
  };
  std::ostringstream message;
  message << "motion '" << path.string() << "': " << bytes << " bytes (" << mib(bytes)
          << "), more than the " << limit << " bytes (" << mib(limit)
          << ") a motion file may have: at most " << mib(kMaxMotionFileBytes)
          << ", and reading one holds up to " << kMotionReadBytesPerFileByte
          << " bytes of memory per byte of it, within the memory limit of "
          << mib(memory_limit_bytes())
          << " (half this machine's memory, or RLIMIT_AS / RLIMIT_DATA when lower, or "
             "RTHS_MEMORY_LIMIT); refused before reading it";
  throw std::invalid_argument(message.str());
}

namespace {

struct UnitSpelling {
  const char* text;
  const char* name;
  double to_si;
};

// Longer spellings first, so that "CM/SEC/SEC" is not read as its tail "M/SEC/SEC".
constexpr UnitSpelling kUnitSpellings[] = {
    {"CM/SEC/SEC", "cm/s2", 0.01}, {"CM/SEC^2", "cm/s2", 0.01},     {"CM/SEC**2", "cm/s2", 0.01},
    {"CM/SEC2", "cm/s2", 0.01},    {"CM/S/S", "cm/s2", 0.01},       {"CM/S^2", "cm/s2", 0.01},
    {"CM/S**2", "cm/s2", 0.01},    {"CM/S2", "cm/s2", 0.01},        {"MM/SEC/SEC", "mm/s2", 0.001},
    {"MM/SEC^2", "mm/s2", 0.001},  {"MM/S/S", "mm/s2", 0.001},      {"MM/S^2", "mm/s2", 0.001},
    {"MM/S2", "mm/s2", 0.001},     {"IN/SEC/SEC", "in/s2", 0.0254}, {"IN/SEC^2", "in/s2", 0.0254},
    {"IN/S/S", "in/s2", 0.0254},   {"IN/S^2", "in/s2", 0.0254},     {"IN/S2", "in/s2", 0.0254},
    {"M/SEC/SEC", "m/s2", 1.0},    {"M/SEC^2", "m/s2", 1.0},        {"M/SEC**2", "m/s2", 1.0},
    {"M/SEC2", "m/s2", 1.0},       {"M/S/S", "m/s2", 1.0},          {"M/S^2", "m/s2", 1.0},
    {"M/S**2", "m/s2", 1.0},       {"M/S2", "m/s2", 1.0},
};

bool word_at(const std::string& text, std::size_t at, std::size_t length) {
  const auto letter = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0; };
  return (at == 0 || !letter(text[at - 1])) &&
         (at + length >= text.size() || !letter(text[at + length]));
}

bool has_word(const std::string& text, const std::string& word) {
  for (std::size_t at = text.find(word); at != std::string::npos; at = text.find(word, at + 1))
    if (word_at(text, at, word.size())) return true;
  return false;
}

// The unit one upper-case header line names, if any: a rate spelling anywhere, g or gal only on a
// line that speaks of units or acceleration (a station's name may hold a lone G).
std::optional<StatedUnits> units_in_line(const std::string& text, const std::string& line) {
  for (const UnitSpelling& spelling : kUnitSpellings) {
    const std::size_t at = text.find(spelling.text);
    if (at == std::string::npos) continue;
    if (at > 0 && std::isalpha(static_cast<unsigned char>(text[at - 1]))) continue;
    return StatedUnits{spelling.name, spelling.to_si, line};
  }
  const bool about_units =
      text.find("UNIT") != std::string::npos || text.find("ACCEL") != std::string::npos;
  if (!about_units) return std::nullopt;
  if (has_word(text, "GAL") || has_word(text, "GALS")) return StatedUnits{"cm/s2", 0.01, line};
  if (has_word(text, "G")) return StatedUnits{"g", core::kGravity, line};
  return std::nullopt;
}

}  // namespace

std::optional<StatedUnits> at2_stated_units(const std::filesystem::path& path) {
  require_motion_file_size(path);
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path.string() + ": cannot open AT2 file");
  std::string line;
  for (int i = 1; i <= 3 && read_line(in, line); ++i)
    if (auto units = units_in_line(upper(line), line)) return units;
  return std::nullopt;
}

core::GroundMotion read_at2(const std::filesystem::path& path, double to_si) {
  require_motion_file_size(path);
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path.string() + ": cannot open AT2 file");
  const At2Header header = read_at2_header(in, path);
  std::string line;

  core::GroundMotion motion;
  motion.name = path.stem().string();
  motion.dt = header.dt;
  motion.acceleration.reserve(std::min(static_cast<std::size_t>(header.npts), kAt2Reserve));
  int line_number = 4;
  int last_value_line = 4;
  while (read_line(in, line)) {
    ++line_number;
    const std::size_t before = motion.acceleration.size();
    parse_values(line, path, line_number, motion.acceleration);
    if (motion.acceleration.size() != before) last_value_line = line_number;
    if (motion.acceleration.size() > static_cast<std::size_t>(header.npts)) {
      throw std::invalid_argument(text_position(path, line_number) + "more values than NPTS = " +
                                  std::to_string(header.npts) + " declared on line 4");
    }
  }
  if (motion.acceleration.size() < static_cast<std::size_t>(header.npts)) {
    throw std::invalid_argument(
        path.string() + ": found " + std::to_string(motion.acceleration.size()) +
        " values but NPTS = " + std::to_string(header.npts) + " (line 4); " +
        std::to_string(header.npts - static_cast<long>(motion.acceleration.size())) +
        " missing after line " + std::to_string(last_value_line) + " — truncated file?");
  }
  for (double& a : motion.acceleration) a *= to_si;
  return motion;
}

namespace {

// The number of columns a ground-motion text file keeps: 1 (acceleration) or 2 (time,
// acceleration), the same on every row.
struct ColumnShape {
  std::size_t columns = 0;
  int first_data_line = 0;
};

void check_row_shape(ColumnShape& shape, const std::filesystem::path& path, int line,
                     const std::vector<double>& values) {
  if (shape.columns == 0) {
    shape.columns = values.size();
    shape.first_data_line = line;
    if (shape.columns != 1 && shape.columns != 2) {
      throw std::invalid_argument(text_position(path, line) +
                                  "expected 1 column (acceleration) or "
                                  "2 (time, acceleration), found " +
                                  std::to_string(shape.columns));
    }
  } else if (values.size() != shape.columns) {
    throw std::invalid_argument(
        text_position(path, line) + "found " + std::to_string(values.size()) + " columns, line " +
        std::to_string(shape.first_data_line) + " had " + std::to_string(shape.columns));
  }
}

// A time column must increase by one step throughout; 1e-3 relative, since text files round
// their times, but a missing or doubled sample is caught.
void check_next_time(const std::vector<double>& times, double time,
                     const std::filesystem::path& path, int line_number) {
  if (times.size() >= 2) {
    const double first_step = times[1] - times[0];
    const double step = time - times.back();
    if (std::abs(step - first_step) > 1e-3 * first_step) {
      throw std::invalid_argument(text_position(path, line_number) + "time step " +
                                  std::to_string(step) + " s differs from the first step " +
                                  std::to_string(first_step) + " s (non-uniform time)");
    }
  } else if (times.size() == 1 && !(time > times[0])) {
    throw std::invalid_argument(text_position(path, line_number) + "time does not increase");
  }
}

// The sample step (s): from the time column when there is one (and `given_dt`, if > 0, must
// agree with it), else `given_dt`, which a one-column file needs.
double column_file_step(const std::vector<double>& times, std::size_t columns, double given_dt,
                        const std::filesystem::path& path) {
  if (columns != 2) {
    if (!(given_dt > 0.0) || !std::isfinite(given_dt)) {
      throw std::invalid_argument(path.string() +
                                  ": a one-column file has no time column: give its sample step, "
                                  "motion.column_dt (--motion-dt), in s");
    }
    return given_dt;
  }
  if (times.size() < 2) {
    throw std::invalid_argument(path.string() +
                                ": two-column file needs at least two samples to "
                                "define its time step");
  }
  const double dt = (times.back() - times.front()) / static_cast<double>(times.size() - 1);
  if (given_dt > 0.0 && std::abs(given_dt - dt) > 1e-3 * dt) {
    throw std::invalid_argument(path.string() + ": given dt = " + std::to_string(given_dt) +
                                " s disagrees with the file's time column (" + std::to_string(dt) +
                                " s)");
  }
  return dt;
}

}  // namespace

core::GroundMotion read_columns(const std::filesystem::path& path, double dt, double to_si) {
  if (!(to_si > 0.0) || !std::isfinite(to_si)) {
    throw std::invalid_argument(path.string() + ": unit factor to m/s^2 must be > 0, got " +
                                std::to_string(to_si));
  }
  require_motion_file_size(path);
  // Streamed: only the samples (and a two-column file's times) are kept.
  std::vector<double> times, values;
  ColumnShape shape;
  for_each_text_row(path, "ground-motion file", /*title_allowed=*/true,
                    [&](int line, const std::vector<double>& row) {
                      check_row_shape(shape, path, line, row);
                      if (shape.columns == 2) {
                        check_next_time(times, row[0], path, line);
                        times.push_back(row[0]);
                      }
                      values.push_back(row.back() * to_si);
                    });
  if (values.empty()) throw std::invalid_argument(path.string() + ": no acceleration values");
  core::GroundMotion motion;
  motion.name = path.stem().string();
  motion.dt = column_file_step(times, shape.columns, dt, path);
  motion.acceleration = std::move(values);
  return motion;
}

bool is_at2_file(const std::filesystem::path& path) {
  require_motion_file_size(path);  // its first lines may be the whole file
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path.string() + ": cannot open ground-motion file");
  std::string line;
  for (int i = 0; i < 4 && read_line(in, line); ++i) {
    if (i == 3 && upper(line).find("NPTS") != std::string::npos) return true;
  }
  return false;
}

core::GroundMotion read_ground_motion(const std::filesystem::path& path, double column_dt,
                                      double column_to_si) {
  if (!is_at2_file(path)) return read_columns(path, column_dt, column_to_si);
  const std::optional<StatedUnits> stated = at2_stated_units(path);
  return read_at2(path, stated ? stated->to_si : core::kGravity);
}

}  // namespace rths::study
