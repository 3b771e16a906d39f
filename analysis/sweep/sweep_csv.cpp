#include "analysis/sweep/sweep_csv.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <set>
#include <stdexcept>

#include "analysis/sweep/sweep_internal.h"
#include "util/atomic_file.h"

namespace rths::analysis {
namespace {

using sweep_internal::format_number;
using sweep_internal::parse_index;

// The errors lead (E_peak, E_rms, max|e|); the paper's NRMSE and Eq. 2 follow, for its Fig. 4.
constexpr const char* kCsvHeader =
    "index,period_s,delay_s,alpha,stiffness_N_per_m,dt_s,motion,model,peak_ref_m,peak_delayed_m,"
    "peak_error_pct,rms_error_pct,peak_error_m,nrmse_pct,eq2_paper,diverged";
// What rths wrote before E_peak and E_rms joined the CSV: named, so that an old shard is not
// merged with a new one nor read as a broken file.
constexpr const char* kNrmseOnlyHeader =
    "index,period_s,delay_s,alpha,stiffness_N_per_m,dt_s,motion,model,peak_ref_m,peak_delayed_m,"
    "eq2_paper,nrmse_pct,peak_error_m,diverged";
constexpr const char* kSidecarFormat = "rths-sweep";

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> cells;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    cells.push_back(
        line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) return cells;
    start = comma + 1;
  }
}

double parse_double(const std::string& text, const std::string& where) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size()) {
    throw std::invalid_argument(where + ": '" + text + "' is not a number");
  }
  return value;
}

void write_csv_file(const std::filesystem::path& path, const std::string& grid_hash,
                    std::size_t points, const Shard& shard, const std::vector<std::string>& lines) {
  // The sidecar first: a CSV is never in place without the metadata that says what it holds.
  util::AtomicFile sidecar(sweep_sidecar_path(path));
  sidecar.stream() << nlohmann::json{{"format", kSidecarFormat},
                                     {"csv", path.filename().string()},
                                     {"grid", grid_hash},
                                     {"points", points},
                                     {"shard", shard.to_string()}}
                          .dump(2)
                   << "\n";
  sidecar.commit();
  util::AtomicFile file(path);
  std::ofstream& out = file.stream();
  out << kCsvHeader << "\n";
  for (const std::string& line : lines) out << line << "\n";
  file.commit();
}

}  // namespace

std::filesystem::path sweep_sidecar_path(const std::filesystem::path& csv) {
  std::filesystem::path sidecar = csv;
  sidecar.replace_extension(".meta.json");
  return sidecar;
}

void write_sweep_csv(const std::filesystem::path& path, const SweepGrid& grid, const Shard& shard,
                     const std::vector<SweepRow>& rows) {
  std::vector<std::string> lines;
  lines.reserve(rows.size());
  for (const SweepTableRow& t : to_table(grid, rows)) {
    std::string line = std::to_string(t.index);
    // Appended piece by piece: `line += "," + text` makes GCC 12 report a false -Wrestrict
    // inside std::string's operator+ (GCC bug 105329).
    const auto field = [&line](const std::string& text) {
      line += ',';
      line += text;
    };
    for (double x : {t.period, t.delay, t.alpha, t.stiffness, t.dt}) field(format_number(x));
    field(t.motion);
    field(t.model);
    for (double x : {t.peak_reference, t.peak_delayed, t.peak_error_pct, t.rms_error_pct,
                     t.peak_error, t.nrmse_pct, t.eq2_paper})
      field(format_number(x));
    line += t.diverged ? ",1" : ",0";
    lines.push_back(std::move(line));
  }
  write_csv_file(path, grid.hash_hex(), grid.size(), shard, lines);
}

SweepCsv read_sweep_csv(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path.string() + ": cannot open the sweep CSV");
  SweepCsv csv;
  std::string line;
  const std::string name = path.string();
  const std::filesystem::path sidecar_path = sweep_sidecar_path(path);
  const std::string sidecar_name = sidecar_path.string();
  std::ifstream sidecar_in(sidecar_path);
  if (!sidecar_in) {
    throw std::invalid_argument(
        name + ": its metadata " + sidecar_name +
        " is missing (grid, points, shard: written beside every sweep CSV)");
  }
  nlohmann::json sidecar;
  try {
    sidecar = nlohmann::json::parse(sidecar_in);
    if (sidecar.value("format", "") != kSidecarFormat)
      throw std::invalid_argument("not an rths-sweep sidecar");
    csv.grid_hash = sidecar.at("grid").get<std::string>();
    csv.points = sidecar.at("points").get<std::size_t>();
    csv.shard = parse_shard(sidecar.at("shard").get<std::string>());
  } catch (const std::exception& e) {
    throw std::invalid_argument(
        sidecar_name + ": not a sweep CSV's metadata (format, grid, points, shard): " + e.what());
  }
  if (csv.grid_hash.empty()) throw std::invalid_argument(sidecar_name + ": empty grid hash");
  const bool has_header = static_cast<bool>(std::getline(in, line));
  if (has_header && line == kNrmseOnlyHeader)
    throw std::invalid_argument(name +
                                ":1: a sweep CSV of an earlier rths (NRMSE only, no "
                                "peak_error_pct and rms_error_pct): run its sweep again");
  if (!has_header || line != kCsvHeader) {
    throw std::invalid_argument(name + ":1: expected the column header '" +
                                std::string(kCsvHeader) + "'");
  }
  csv.header = line;
  std::size_t line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty()) continue;
    const std::string where = name + ":" + std::to_string(line_number);
    const std::size_t comma = line.find(',');
    csv.indices.push_back(parse_index(line.substr(0, comma), where + ": index"));
    if (split_csv(line).size() != split_csv(kCsvHeader).size()) {
      throw std::invalid_argument(where + ": expected " +
                                  std::to_string(split_csv(kCsvHeader).size()) +
                                  " columns (a truncated file?)");
    }
    csv.lines.push_back(line);
  }
  return csv;
}

namespace {

// Every point of the grid has a shard (owner: the shard holding each point, -1 for none); the
// error names the missing points and, when the grid was sharded, the shards that hold them.
void check_complete(const std::vector<int>& owner, std::size_t shard_count) {
  const std::size_t total = owner.size();
  std::vector<std::size_t> missing;
  for (std::size_t i = 0; i < total; ++i) {
    if (owner[i] < 0) missing.push_back(i);
  }
  if (!missing.empty()) {
    std::string message = "merge: " + std::to_string(missing.size()) + " of " +
                          std::to_string(total) + " points are missing (first index " +
                          std::to_string(missing.front()) + ", last " +
                          std::to_string(missing.back()) + ")";
    const std::size_t count = shard_count;
    if (count > 1) {
      std::set<std::size_t> lacking;
      for (std::size_t i : missing)
        lacking.insert(std::min(count - 1, (i * count + count - 1) / total));
      // Shard s holds [s T / N, (s+1) T / N); name the ones whose points are absent.
      std::string names;
      for (std::size_t s = 0; s < count; ++s) {
        const std::size_t lo = total * s / count, hi = total * (s + 1) / count;
        if (lo < hi && owner[lo] < 0)
          names += (names.empty() ? "" : ", ") + std::to_string(s) + "/" + std::to_string(count);
      }
      if (!names.empty()) message += "; missing shard(s) " + names;
    }
    throw std::invalid_argument(message);
  }
}

}  // namespace

SweepCsv merge_sweep_csvs(const std::vector<std::filesystem::path>& shards,
                          const std::filesystem::path& out) {
  if (shards.empty()) throw std::invalid_argument("merge: no shard CSVs given");
  std::vector<SweepCsv> parts;
  for (const auto& path : shards) parts.push_back(read_sweep_csv(path));
  const SweepCsv& first = parts.front();
  for (std::size_t i = 1; i < parts.size(); ++i) {
    if (parts[i].grid_hash != first.grid_hash || parts[i].points != first.points) {
      throw std::invalid_argument(
          "merge: " + shards[i].string() + " comes from another grid (grid=" + parts[i].grid_hash +
          ", " + std::to_string(parts[i].points) + " points) than " + shards[0].string() +
          " (grid=" + first.grid_hash + ", " + std::to_string(first.points) + " points)");
    }
  }
  const std::size_t total = first.points;
  std::vector<int> owner(total, -1);
  std::vector<const std::string*> line_of(total, nullptr);
  for (std::size_t s = 0; s < parts.size(); ++s) {
    for (std::size_t r = 0; r < parts[s].indices.size(); ++r) {
      const std::size_t index = parts[s].indices[r];
      if (index >= total) {
        throw std::invalid_argument("merge: " + shards[s].string() + " holds index " +
                                    std::to_string(index) + " beyond the grid's " +
                                    std::to_string(total) + " points");
      }
      if (owner[index] >= 0) {
        throw std::invalid_argument("merge: point " + std::to_string(index) +
                                    " appears twice (in " + shards[owner[index]].string() +
                                    " and " + shards[s].string() + "); was a shard given twice?");
      }
      owner[index] = static_cast<int>(s);
      line_of[index] = &parts[s].lines[r];
    }
  }
  check_complete(owner, first.shard.count);
  SweepCsv merged;
  merged.grid_hash = first.grid_hash;
  merged.points = total;
  merged.shard = Shard{};
  merged.header = kCsvHeader;
  merged.indices.resize(total);
  merged.lines.reserve(total);
  for (std::size_t i = 0; i < total; ++i) {
    merged.indices[i] = i;
    merged.lines.push_back(*line_of[i]);
  }
  write_csv_file(out, merged.grid_hash, total, merged.shard, merged.lines);
  return merged;
}

std::vector<SweepTableRow> parse_sweep_rows(const SweepCsv& csv, const std::string& source) {
  std::vector<SweepTableRow> rows;
  rows.reserve(csv.lines.size());
  for (std::size_t r = 0; r < csv.lines.size(); ++r) {
    const std::vector<std::string> c = split_csv(csv.lines[r]);
    const std::string where = source + " row " + std::to_string(r + 1);
    if (c.size() != 16) throw std::invalid_argument(where + ": expected 16 columns");
    SweepTableRow t;
    t.index = parse_index(c[0], where);
    t.period = parse_double(c[1], where + " period");
    t.delay = parse_double(c[2], where + " delay");
    t.alpha = parse_double(c[3], where + " alpha");
    t.stiffness = parse_double(c[4], where + " stiffness");
    t.dt = parse_double(c[5], where + " dt");
    t.motion = c[6];
    t.model = c[7];
    t.peak_reference = parse_double(c[8], where + " peak_ref");
    t.peak_delayed = parse_double(c[9], where + " peak_delayed");
    t.peak_error_pct = parse_double(c[10], where + " peak_error_pct");
    t.rms_error_pct = parse_double(c[11], where + " rms_error_pct");
    t.peak_error = parse_double(c[12], where + " peak_error");
    t.nrmse_pct = parse_double(c[13], where + " nrmse_pct");
    t.eq2_paper = parse_double(c[14], where + " eq2_paper");
    t.diverged = c[15] == "1";
    rows.push_back(std::move(t));
  }
  return rows;
}

}  // namespace rths::analysis
