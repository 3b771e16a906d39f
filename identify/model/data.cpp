#include "identify/model/data.h"

#include "study/text_columns.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace rths::identify {
namespace {

std::string trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r\n");
  return std::string(s.substr(first, last - first + 1));
}

std::vector<std::string> split_fields(const std::string& line, char sep) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream stream(line);
  while (std::getline(stream, field, sep)) fields.push_back(trim(field));
  if (!line.empty() && line.back() == sep) fields.emplace_back();
  return fields;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string where(const std::filesystem::path& path, std::size_t line) {
  return study::text_position(path, static_cast<int>(line));
}

double parse_number(const std::string& text, const std::filesystem::path& path, std::size_t line,
                    const std::string& column) {
  const auto value = core::parse_finite(text);
  if (!value)
    throw std::invalid_argument(where(path, line) + "column '" + column + "': '" + text +
                                "' is not a finite number");
  return *value;
}

std::size_t column_index(const std::vector<std::string>& header, const std::string& name,
                         const std::filesystem::path& path, std::size_t line) {
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (lower(header[i]) == lower(name)) return i;
  }
  std::string names;
  for (const auto& h : header) names += (names.empty() ? "" : ", ") + h;
  throw std::invalid_argument(where(path, line) + "missing column '" + name +
                              "' (header has: " + names + ")");
}

std::optional<std::size_t> find_column(const std::vector<std::string>& header,
                                       const std::string& name) {
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (lower(header[i]) == lower(name)) return i;
  }
  return std::nullopt;
}

void check_sample_rate(double sample_rate, const std::filesystem::path& path) {
  if (sample_rate < 0.0 || !std::isfinite(sample_rate)) {
    throw std::invalid_argument(path.string() +
                                ": --sample-rate must be a positive number of Hz, got " +
                                std::to_string(sample_rate));
  }
}

// The file's own rate against the given one: one time base, not two that disagree.
void check_same_rate(double file_rate, double sample_rate, const std::string& what,
                     const std::filesystem::path& path) {
  if (sample_rate > 0.0 && std::abs(file_rate - sample_rate) > 0.01 * sample_rate) {
    throw std::invalid_argument(path.string() + ": " + what + " gives " +
                                std::to_string(file_rate) + " Hz but --sample-rate says " +
                                std::to_string(sample_rate) +
                                " Hz; drop --sample-rate or fix the file");
  }
}

}  // namespace

double time_unit_to_s(const std::string& unit) {
  if (unit == "s") return 1.0;
  if (unit == "ms") return 1.0e-3;
  throw std::invalid_argument("unknown time unit '" + unit + "' (use s or ms)");
}

double length_unit_to_m(const std::string& unit) {
  if (unit == "m") return 1.0;
  if (unit == "mm") return 1.0e-3;
  if (unit == "cm") return 1.0e-2;
  if (unit == "in") return 0.0254;
  throw std::invalid_argument("unknown length unit '" + unit + "' (use m, mm, cm or in)");
}

double force_unit_to_n(const std::string& unit) {
  if (unit == "N") return 1.0;
  if (unit == "kN") return 1.0e3;
  if (unit == "lbf") return 4.4482216152605;
  if (unit == "kip") return 4448.2216152605;
  throw std::invalid_argument("unknown force unit '" + unit + "' (use N, kN, lbf or kip)");
}

DaqColumnMap parse_column_map(const std::string& text) {
  DaqColumnMap map;
  for (const auto& entry : split_fields(text, ',')) {
    if (entry.empty()) continue;
    const auto eq = entry.find('=');
    if (eq == std::string::npos) {
      throw std::invalid_argument("column map entry '" + entry +
                                  "': expected signal=COLUMN*scale, e.g. command=CHANNEL2*10");
    }
    const std::string signal = trim(entry.substr(0, eq));
    const std::string rhs = trim(entry.substr(eq + 1));
    ChannelSource source;
    const auto star = rhs.find('*');
    source.column = trim(rhs.substr(0, star));
    if (star != std::string::npos) {
      const std::string scale = trim(rhs.substr(star + 1));
      source.scale = core::parse_finite(scale).value_or(0.0);
      if (source.scale == 0.0) {
        throw std::invalid_argument("column map entry '" + entry + "': scale '" + scale +
                                    "' is not a non-zero number");
      }
    }
    if (source.column.empty()) {
      throw std::invalid_argument("column map entry '" + entry + "': no column name");
    }
    if (signal == "command") {
      map.command = source;
    } else if (signal == "measured") {
      map.measured = source;
    } else if (signal == "force") {
      map.force = source;
    } else {
      throw std::invalid_argument("column map entry '" + entry + "': unknown signal '" + signal +
                                  "' (use command, measured or force)");
    }
  }
  return map;
}

void validate(MeasuredData& data, std::size_t min_samples) {
  const std::size_t n = data.time.size();
  if (data.command.size() != n || data.measured.size() != n ||
      (data.has_force() && data.force.size() != n)) {
    throw std::invalid_argument(data.source + ": columns have different lengths");
  }
  if (n < std::max<std::size_t>(min_samples, 3)) {
    throw std::invalid_argument(data.source + ": only " + std::to_string(n) +
                                " samples; the model needs at least " +
                                std::to_string(std::max<std::size_t>(min_samples, 3)));
  }
  for (std::size_t i = 0; i < n; ++i) {
    for (const auto* column : {&data.time, &data.command, &data.measured, &data.force}) {
      if (!column->empty() && !std::isfinite((*column)[i])) {
        throw std::invalid_argument(data.source + ": sample " + std::to_string(i + 1) +
                                    " is NaN or infinite");
      }
    }
  }
  for (std::size_t i = 1; i < n; ++i) {
    if (!(data.time[i] > data.time[i - 1])) {
      throw std::invalid_argument(data.source + ": time does not increase at sample " +
                                  std::to_string(i + 1) + " (t = " + std::to_string(data.time[i]) +
                                  " s after " + std::to_string(data.time[i - 1]) + " s)");
    }
  }
  const double mean_dt = (data.time.back() - data.time.front()) / static_cast<double>(n - 1);
  for (std::size_t i = 1; i < n; ++i) {
    const double step = data.time[i] - data.time[i - 1];
    if (std::abs(step - mean_dt) > 0.01 * mean_dt) {
      throw std::invalid_argument(data.source + ": time step is not uniform at sample " +
                                  std::to_string(i + 1) + " (" + std::to_string(step) +
                                  " s vs mean " + std::to_string(mean_dt) + " s)");
    }
  }
  data.dt = mean_dt;
}

MeasuredData read_csv(const std::filesystem::path& path, const CsvUnits& units,
                      std::size_t min_samples, double sample_rate, ForceColumn force) {
  check_sample_rate(sample_rate, path);
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path.string() + ": cannot open");
  MeasuredData data;
  data.source = path.string();
  std::string line;
  std::size_t line_number = 0;
  std::vector<std::string> header;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string t = trim(line);
    if (t.empty() || t.front() == '#') continue;
    header = split_fields(t, ',');
    break;
  }
  if (header.empty()) throw std::invalid_argument(path.string() + ": empty file, no header");
  const std::size_t header_line = line_number;
  const std::optional<std::size_t> it = find_column(header, "time");
  if (!it && !(sample_rate > 0.0)) {
    std::string names;
    for (const auto& h : header) names += (names.empty() ? "" : ", ") + h;
    throw std::invalid_argument(where(path, header_line) + "no 'time' column (header has: " +
                                names + "); give the sampling rate with --sample-rate HZ");
  }
  const std::size_t ic = column_index(header, "command", path, header_line);
  const std::size_t im = column_index(header, "measured", path, header_line);
  const std::optional<std::size_t> iforce = force == ForceColumn::kRequired
                                                ? column_index(header, "force", path, header_line)
                                                : find_column(header, "force");
  const std::size_t needed = std::max({it.value_or(0), ic, im, iforce.value_or(0)}) + 1;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string t = trim(line);
    if (t.empty() || t.front() == '#') continue;
    const auto fields = split_fields(t, ',');
    if (fields.size() < needed) {
      throw std::invalid_argument(where(path, line_number) + "has " +
                                  std::to_string(fields.size()) + " columns, expected " +
                                  std::to_string(header.size()));
    }
    data.time.push_back(it ? units.time_to_s * parse_number(fields[*it], path, line_number, "time")
                           : static_cast<double>(data.time.size()) / sample_rate);
    data.command.push_back(units.length_to_m *
                           parse_number(fields[ic], path, line_number, "command"));
    data.measured.push_back(units.length_to_m *
                            parse_number(fields[im], path, line_number, "measured"));
    if (iforce) {
      data.force.push_back(units.force_to_n *
                           parse_number(fields[*iforce], path, line_number, "force"));
    }
  }
  validate(data, min_samples);
  if (it) check_same_rate(1.0 / data.dt, sample_rate, "the time column", path);
  return data;
}

namespace {

// The first line of a raw DAQ export, "Header Size: N": the header's line count, column names
// included.
int read_header_size(std::istream& in, const std::filesystem::path& path) {
  std::string line;
  if (!std::getline(in, line)) throw std::invalid_argument(path.string() + ": empty file");
  const auto colon = line.find(':');
  if (colon == std::string::npos || trim(line.substr(0, colon)) != "Header Size") {
    throw std::invalid_argument(where(path, 1) + "expected 'Header Size: N' (raw DAQ export)");
  }
  // Checked as a double first: converting an out-of-range value to int is undefined behaviour.
  constexpr double kMaxHeaderSize = 10000;  // real exports have ~7 header lines
  const double header_value = parse_number(trim(line.substr(colon + 1)), path, 1, "Header Size");
  if (!(header_value >= 2) || !(header_value <= kMaxHeaderSize) ||
      header_value != std::floor(header_value))
    throw std::invalid_argument(where(path, 1) + "Header Size must be a whole number in 2.." +
                                std::to_string(static_cast<int>(kMaxHeaderSize)));
  return static_cast<int>(header_value);
}

struct DaqHeader {
  std::vector<std::string> columns;
  double interval = 0.0;  // s, 0: not given
  double rate = 0.0;      // Hz, 0: not given
};

// The header's lines after the first: sampling keys, then the column names on its last line.
DaqHeader read_daq_header(std::istream& in, const std::filesystem::path& path, int header_size,
                          std::size_t& line_number) {
  DaqHeader h;
  std::string line;
  while (line_number < static_cast<std::size_t>(header_size)) {
    if (!std::getline(in, line)) {
      throw std::invalid_argument(where(path, line_number) + "file ends inside the header");
    }
    ++line_number;
    if (line_number == static_cast<std::size_t>(header_size)) {
      h.columns = split_fields(trim(line), ',');
    } else {
      const auto c = line.find(':');
      const std::string key = c == std::string::npos ? "" : trim(line.substr(0, c));
      if (key == "Sampling Interval" || key == "Sampling Rate") {
        const double value = parse_number(trim(line.substr(c + 1)), path, line_number, key);
        if (!(value > 0.0)) {
          throw std::invalid_argument(where(path, line_number) + key + " must be > 0");
        }
        (key == "Sampling Interval" ? h.interval : h.rate) = value;
      }
    }
  }
  return h;
}

// The sample interval from the header's Sampling Interval and/or Rate, which must agree with each
// other and with --sample-rate; --sample-rate alone when the header has neither.
double daq_interval(double interval, double rate, double sample_rate,
                    const std::filesystem::path& path) {
  if (interval > 0.0 && rate > 0.0 && std::abs(interval * rate - 1.0) > 0.01) {
    throw std::invalid_argument(path.string() + ": header's Sampling Interval " +
                                std::to_string(interval) + " s and Sampling Rate " +
                                std::to_string(rate) + " Hz disagree");
  }
  if (!(interval > 0.0) && rate > 0.0) interval = 1.0 / rate;
  if (interval > 0.0) {
    check_same_rate(1.0 / interval, sample_rate, "the header's Sampling Interval/Rate", path);
  } else if (sample_rate > 0.0) {
    interval = 1.0 / sample_rate;
  } else {
    throw std::invalid_argument(path.string() +
                                ": header has no 'Sampling Interval' or 'Sampling Rate'; give the "
                                "sampling rate with --sample-rate HZ");
  }
  return interval;
}

}  // namespace

MeasuredData read_daq(const std::filesystem::path& path, const DaqColumnMap& map,
                      std::size_t min_samples, double sample_rate, ForceColumn force) {
  check_sample_rate(sample_rate, path);
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path.string() + ": cannot open");
  const int header_size = read_header_size(in, path);
  std::size_t line_number = 1;
  const DaqHeader daq_header = read_daq_header(in, path, header_size, line_number);
  const std::vector<std::string>& header = daq_header.columns;
  const double interval = daq_interval(daq_header.interval, daq_header.rate, sample_rate, path);
  // Without a Sample Number column, samples are timed by their row.
  const std::optional<std::size_t> isample = find_column(header, "Sample Number");
  const std::size_t ic = column_index(header, map.command.column, path, line_number);
  const std::size_t im = column_index(header, map.measured.column, path, line_number);
  const std::optional<std::size_t> iforce =
      force == ForceColumn::kRequired ? column_index(header, map.force.column, path, line_number)
                                      : find_column(header, map.force.column);
  const std::size_t needed = std::max({isample.value_or(0), ic, im, iforce.value_or(0)}) + 1;

  MeasuredData data;
  data.source = path.string();
  std::string line;
  double first_sample = 0.0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string t = trim(line);
    if (t.empty()) continue;
    const auto fields = split_fields(t, ',');
    if (fields.size() < needed) {
      throw std::invalid_argument(where(path, line_number) + "has " +
                                  std::to_string(fields.size()) + " columns, expected at least " +
                                  std::to_string(needed));
    }
    const double sample = isample
                              ? parse_number(fields[*isample], path, line_number, header[*isample])
                              : static_cast<double>(data.time.size());
    if (data.time.empty()) first_sample = sample;
    data.time.push_back((sample - first_sample) * interval);
    data.command.push_back(1.0e-3 * map.command.scale *
                           parse_number(fields[ic], path, line_number, header[ic]));
    data.measured.push_back(1.0e-3 * map.measured.scale *
                            parse_number(fields[im], path, line_number, header[im]));
    if (iforce) {
      data.force.push_back(map.force.scale *
                           parse_number(fields[*iforce], path, line_number, header[*iforce]));
    }
  }
  validate(data, min_samples);
  return data;
}

MeasuredData read_measured(const std::filesystem::path& path, const CsvUnits& units,
                           const DaqColumnMap& map, std::size_t min_samples, double sample_rate,
                           ForceColumn force) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path.string() + ": cannot open");
  std::string first;
  std::getline(in, first);
  if (first.rfind("Header Size", 0) == 0) {
    return read_daq(path, map, min_samples, sample_rate, force);
  }
  return read_csv(path, units, min_samples, sample_rate, force);
}

void write_csv(const MeasuredData& data, const std::filesystem::path& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
  out << "time,command,measured" << (data.has_force() ? ",force\n" : "\n");
  out.precision(10);
  for (std::size_t i = 0; i < data.size(); ++i) {
    out << data.time[i] << ',' << data.command[i] * 1e3 << ',' << data.measured[i] * 1e3;
    if (data.has_force()) out << ',' << data.force[i];
    out << '\n';
  }
  if (!out) throw std::runtime_error(path.string() + ": write failed");
}

MeasuredData slice(const MeasuredData& data, std::size_t begin, std::size_t end) {
  if (!(begin < end && end <= data.size())) {
    throw std::invalid_argument(data.source + ": slice [" + std::to_string(begin) + ", " +
                                std::to_string(end) + ") outside " + std::to_string(data.size()) +
                                " samples");
  }
  MeasuredData out;
  out.source = data.source + "[" + std::to_string(begin) + ":" + std::to_string(end) + "]";
  out.dt = data.dt;
  const auto part = [&](const std::vector<double>& x) {
    if (x.empty()) return std::vector<double>{};
    return std::vector<double>(x.begin() + static_cast<std::ptrdiff_t>(begin),
                               x.begin() + static_cast<std::ptrdiff_t>(end));
  };
  out.time = part(data.time);
  out.command = part(data.command);
  out.measured = part(data.measured);
  out.force = part(data.force);
  return out;
}

ActiveRange active_range(const MeasuredData& data, double threshold, double margin,
                         double rest_window) {
  if (!(threshold > 0.0 && threshold < 1.0) || !(margin >= 0.0) || !(rest_window > 0.0)) {
    throw std::invalid_argument(
        "active_range: threshold must be in (0, 1), margin >= 0 s, "
        "rest window > 0 s");
  }
  const std::size_t n = data.size();
  ActiveRange whole{0, n};
  if (n == 0 || !(data.dt > 0.0)) return whole;
  const auto rest_samples =
      std::clamp<std::size_t>(static_cast<std::size_t>(std::llround(rest_window / data.dt)), 1, n);
  double rest_first = 0.0, rest_last = 0.0;
  for (std::size_t i = 0; i < rest_samples; ++i) {
    rest_first += data.command[i];
    rest_last += data.command[n - 1 - i];
  }
  rest_first /= static_cast<double>(rest_samples);
  rest_last /= static_cast<double>(rest_samples);
  double peak_first = 0.0, peak_last = 0.0;
  for (double c : data.command) {
    peak_first = std::max(peak_first, std::abs(c - rest_first));
    peak_last = std::max(peak_last, std::abs(c - rest_last));
  }
  if (!(peak_first > 0.0) || !(peak_last > 0.0)) return whole;
  std::size_t first = 0, last = n - 1;
  while (first < n && std::abs(data.command[first] - rest_first) <= threshold * peak_first) ++first;
  while (last > 0 && std::abs(data.command[last] - rest_last) <= threshold * peak_last) --last;
  if (first >= last) return whole;
  const auto pad = static_cast<std::size_t>(std::llround(margin / data.dt));
  return {first > pad ? first - pad : 0, std::min(n, last + 1 + pad)};
}

MeasuredData decimated(const MeasuredData& data, std::size_t factor) {
  if (factor <= 1) return data;
  MeasuredData out;
  out.source = data.source;
  out.dt = data.dt * static_cast<double>(factor);
  const std::size_t n = data.size();
  const auto smooth = [&](const std::vector<double>& x, std::size_t centre) {
    const std::size_t half = factor / 2;
    const std::size_t lo = centre >= half ? centre - half : 0;
    const std::size_t hi = std::min(n, lo + factor);
    double sum = 0.0;
    for (std::size_t j = lo; j < hi; ++j) sum += x[j];
    return sum / static_cast<double>(hi - lo);
  };
  for (std::size_t i = 0; i < n; i += factor) {
    out.time.push_back(data.time[i]);
    out.command.push_back(smooth(data.command, i));
    out.measured.push_back(smooth(data.measured, i));
    if (data.has_force()) out.force.push_back(smooth(data.force, i));
  }
  return out;
}

HoldoutMode parse_holdout_mode(const std::string& name) {
  if (name == "last") return HoldoutMode::kLast;
  if (name == "blocks") return HoldoutMode::kBlocks;
  throw std::invalid_argument("unknown hold-out mode '" + name + "' (use last or blocks)");
}

Split holdout_split(std::size_t samples, double holdout_fraction, HoldoutMode mode,
                    std::size_t blocks, std::size_t min_part) {
  if (!(holdout_fraction > 0.0 && holdout_fraction < 1.0)) {
    throw std::invalid_argument("hold-out fraction must be in (0, 1), got " +
                                std::to_string(holdout_fraction));
  }
  Split split;
  split.size = samples;
  std::vector<bool> held(samples, false);
  if (mode == HoldoutMode::kLast) {
    const auto train_end = static_cast<std::size_t>(
        std::llround(static_cast<double>(samples) * (1.0 - holdout_fraction)));
    for (std::size_t i = train_end; i < samples; ++i) held[i] = true;
  } else {
    if (blocks < 2) throw std::invalid_argument("segment-wise hold-out needs at least 2 blocks");
    // Block b is held out when the running share floor((b + 1) f) steps up: evenly spread, and
    // the last block is always among them.
    for (std::size_t b = 0; b < blocks; ++b) {
      const double f = holdout_fraction;
      const bool is_held = std::floor(static_cast<double>(b + 1) * f + 1e-9) >
                           std::floor(static_cast<double>(b) * f + 1e-9);
      const std::size_t lo = samples * b / blocks, hi = samples * (b + 1) / blocks;
      for (std::size_t i = lo; i < hi; ++i) held[i] = is_held;
    }
  }
  for (std::size_t i = 0; i < samples; ++i) (held[i] ? split.heldout : split.train).push_back(i);
  if (split.train.size() < min_part || split.heldout.size() < min_part) {
    throw std::invalid_argument("too few samples (" + std::to_string(samples) +
                                ") for a training and a hold-out part of at least " +
                                std::to_string(min_part) + " samples each");
  }
  return split;
}

}  // namespace rths::identify
