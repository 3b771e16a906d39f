// rths export RECORD --csv OUT | --mat OUT | --h5 OUT: a run record (length-delimited protobuf)
// to CSV, MATLAB or HDF5 (results/results.h names the variables and units); several at once.
// A record whose controller nodes held gets their hold, frame by frame (results::hold_table),
// beside each output in its format, as <stem>_hold<ext>; --json lists them in "hold_tables" and
// node_health holds the same table per node.
// Every entry's checksum is verified (runtime::read_record). A damaged record is exported with
// every intact entry (the reader resynchronises after each damaged region); what was lost (bytes,
// step numbers) goes to stderr and to the outputs' attributes (integrity, lost_steps), and the
// exit is 1. A truncated record (the writer crashed or its disk filled), or one that stops
// between two entries without its footer, is exported up to its last complete entry with a
// warning on stderr; exit 0. An old record without checksums is exported with a warning; exit 0.
// A record whose checksums hold but whose meaning does not (runtime/record/record_checks.h: schema
// version, dt, step order and gaps, time against step x dt, entry sizes against the header's
// dofs, values not finite or beyond the deployment's limits or plausible bounds, link samples and
// timings out of range, header copies that disagree, no intact header, a missing inputs entry,
// steps the footer counts that are absent) is exported as read, "ok" false in --json, each problem named with its entries and
// steps on stderr, exit 1; one whose header cannot size a table (dofs -1 or 100000) writes
// nothing, exit 1. --strict: any warning is exit 1 too (a truncated record, one cut between two
// entries, one without checksums). A missing file, or one that is no record, is exit 2.
#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>

#include "cli/commands.h"
#include "results/results.h"
#include "results/write.h"
#include "runtime/record/node_health.h"
#include "runtime/record/record_checks.h"
#include "util/distinct_paths.h"

namespace rths::cli {

namespace {

// "; N messages dropped unauthenticated: coordinator C, node 1 A, ..." when any side counted any
// (forged, foreign or replayed messages a transport dropped for want of a valid MAC: the
// coordinator's in the footer's counters, each node's as of its last heartbeat), else "".
std::string unauthenticated_note(const runtime::RunFooter* footer) {
  if (!footer) return "";
  std::uint64_t total = footer->counters().unauthenticated();
  std::string sides = "coordinator " + std::to_string(total);
  for (const runtime::NodeRejects& n : footer->node_rejects()) {
    total += n.rejected().unauthenticated();
    sides += ", node " + std::to_string(n.node_id()) + " " +
             std::to_string(n.rejected().unauthenticated());
  }
  if (total == 0) return "";
  return "; " + std::to_string(total) + " messages dropped unauthenticated: " + sides;
}

// Each node's unauthenticated drops by node id (as of its last heartbeat); null without a footer.
nlohmann::json node_unauthenticated_json(const runtime::RunFooter* footer) {
  if (!footer) return nlohmann::json();
  nlohmann::json nodes = nlohmann::json::object();
  for (const runtime::NodeRejects& n : footer->node_rejects())
    nodes[std::to_string(n.node_id())] = n.rejected().unauthenticated();
  return nodes;
}

// Each node's health (runtime/record/node_health.h) by node id; null without a footer.
nlohmann::json node_health_json(const runtime::RunFooter* footer) {
  if (!footer) return nlohmann::json();
  nlohmann::json nodes = nlohmann::json::object();
  for (const runtime::NodeRejects& n : footer->node_rejects())
    nodes[std::to_string(n.node_id())] = runtime::node_health_json(n);
  return nodes;
}

// The controller links and answer ages, a line each, for the text output.
std::string node_health_text(const runtime::RunFooter* footer) {
  if (!footer) return "";
  std::string text;
  for (const runtime::NodeRejects& n : footer->node_rejects())
    text += runtime::controller_link_text(n) + runtime::answer_age_text(n);
  return text;
}

// The controllers' hold (results::hold_table) beside each output, as <stem>_hold<ext> in the
// same format; the paths written (none when no node held).
std::vector<std::string> write_hold_tables(const runtime::RunFooter* footer,
                                           const std::map<results::Format, std::string>& outputs) {
  std::vector<std::string> written;
  if (!footer) return written;
  const results::Table hold = results::hold_table(*footer);
  if (hold.rows() == 0) return written;
  for (const auto& [format, path] : outputs) {
    const std::filesystem::path p(path);
    const std::filesystem::path beside =
        p.parent_path() / (p.stem().string() + "_hold" + p.extension().string());
    try {
      results::write_table(hold, beside, format);
    } catch (const std::exception& e) {
      throw ExitError(kExitEnvironment, e.what());
    }
    written.push_back(beside.string());
  }
  return written;
}

// What --json prints: what was read and written, and whether the record is whole.
nlohmann::json export_json(const std::string& record, const runtime::RecordContents& contents,
                           const runtime::RecordChecks& checks, const results::Table& table,
                           const std::map<results::Format, std::string>& outputs,
                           const std::vector<std::string>& hold_tables) {
  const auto* footer = contents.footer();
  nlohmann::json j{
      {"record", record},
      {"rows", table.rows()},
      {"truncated", contents.truncated || checks.cut},
      {"problems", checks.problems},
      {"status", footer ? footer->status() : "no footer: the run was cut short"},
      // The run ended well and the record says so whole: no damaged region, no problem.
      {"ok", footer && footer->ok() && !contents.lost_entries() && checks.problems.empty()},
      // The coordinator's drops for want of a MAC; null without a footer.
      {"unauthenticated",
       footer ? nlohmann::json(footer->counters().unauthenticated()) : nlohmann::json()},
      {"node_unauthenticated", node_unauthenticated_json(footer)},
      {"node_health", node_health_json(footer)},
      {"checksummed", contents.checksummed},
      {"integrity", table.attributes().at("integrity")},
      {"lost_steps", table.attributes().at("lost_steps")},
      {"damaged_regions", contents.losses.size()}};
  for (const auto& [format, path] : outputs) j[results::extension(format).substr(1)] = path;
  j["hold_tables"] = hold_tables;
  return j;
}

// What the text output says: each file written, and the nodes' health.
void print_exported(const runtime::RecordContents& contents, const results::Table& table,
                    const std::map<results::Format, std::string>& outputs,
                    const std::vector<std::string>& hold_tables) {
  const auto* footer = contents.footer();
  const std::string status = footer ? footer->status() : "no footer: the run was cut short";
  for (const auto& [format, path] : outputs)
    std::cout << "wrote " << table.rows() << " steps to " << path << " (" << status
              << unauthenticated_note(footer) << ")\n";
  for (const std::string& path : hold_tables)
    std::cout << "wrote the controllers' hold, frame by frame, to " << path << "\n";
  std::cout << node_health_text(footer);
}

// Reads the record, writes every requested output and says what was written. Throws ExitError:
// kExitBadInput for a record that cannot be read or tabled, kExitEnvironment for an output that
// cannot be written, kExitRunFailed after exporting a record that lost entries.
void run_export(const std::string& record, const std::map<results::Format, std::string>& outputs,
                bool json, bool strict) {
  for (const auto& [format, path] : outputs)
    util::refuse_output_over_input({"--" + results::extension(format).substr(1), path},
                                   {{"record", record}});
  runtime::RecordContents contents;
  try {
    contents = runtime::read_record(record);
  } catch (const std::exception& e) {
    throw ExitError(kExitBadInput, e.what());
  }
  if (!contents.warning.empty()) std::cerr << "rths export: warning: " << contents.warning << "\n";
  const runtime::RecordChecks checks = runtime::check_record(contents);
  if (checks.fatal)
    throw ExitError(kExitRunFailed, std::string("export: ") + record +
                                        " is implausible, nothing written: " + checks.summary());
  if (!checks.ok()) std::cerr << "rths export: warning: " << checks.summary() << "\n";
  results::Table table;
  try {
    table = results::record_table(contents);
  } catch (const std::invalid_argument& e) {
    throw ExitError(kExitBadInput, record + ": " + e.what());
  }
  for (const auto& [format, path] : outputs) {
    try {
      results::write_table(table, path, format);
    } catch (const std::exception& e) {
      throw ExitError(kExitEnvironment, e.what());
    }
  }
  const std::vector<std::string> hold_tables = write_hold_tables(contents.footer(), outputs);
  if (json)
    std::cout << export_json(record, contents, checks, table, outputs, hold_tables).dump(2) << "\n";
  else
    print_exported(contents, table, outputs, hold_tables);
  if (contents.lost_entries())
    throw ExitError(kExitRunFailed, "export: the record lost entries (intact ones exported): " +
                                        contents.loss_report());
  if (!checks.problems.empty())
    throw ExitError(kExitRunFailed,
                    "export: the record is implausible (exported as read): " + checks.summary());
  if (strict && (!contents.warning.empty() || checks.cut))
    throw ExitError(kExitRunFailed,
                    "export: --strict: the record is not whole (exported as read): " +
                        (contents.warning.empty() ? checks.summary() : contents.warning));
}

}  // namespace

void add_export_command(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("export", "Turn a run record into CSV, MATLAB (.mat) or HDF5 (.h5)");
  auto record = std::make_shared<std::string>();
  auto outputs = std::make_shared<std::map<results::Format, std::string>>();
  auto json = std::make_shared<bool>(false);
  auto strict = std::make_shared<bool>(false);
  cmd->add_option("record", *record, "run record (.rthsrec)")->required();
  auto* csv = cmd->add_option_function<std::string>(
      "--csv", [outputs](const std::string& p) { (*outputs)[results::Format::kCsv] = p; },
      "CSV file to write");
  auto* mat = cmd->add_option_function<std::string>(
      "--mat", [outputs](const std::string& p) { (*outputs)[results::Format::kMat] = p; },
      "MATLAB 5 file to write (one variable per CSV column, units in the struct `units`, the "
      "study, dt_s, motion and verdict in the struct `attributes`)");
  auto* h5 = cmd->add_option_function<std::string>(
      "--h5", [outputs](const std::string& p) { (*outputs)[results::Format::kH5] = p; },
      "HDF5 file to write (one dataset per CSV column, each with a `units` attribute; the "
      "study, dt_s, motion and verdict as the root's attributes)");
  cmd->callback([=] {
    if (csv->count() + mat->count() + h5->count() == 0)
      throw ExitError(kExitBadInput, "export: give --csv, --mat or --h5 (or several)");
    run_export(*record, *outputs, *json, *strict);
  });
  cmd->add_flag("--json", *json, "print a JSON summary on stdout");
  cmd->add_flag("--strict", *strict,
                "exit 1 on any warning: also for a truncated record, one cut between two "
                "entries or one without checksums");
}

}  // namespace rths::cli
