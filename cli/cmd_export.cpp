// rths export RECORD --csv OUT: a run record (length-delimited protobuf) to CSV.
// A truncated record (the writer crashed) is exported up to its last complete entry with a
// warning on stderr; exit 0. A missing or corrupt record is exit 2.
#include <nlohmann/json.hpp>

#include <iostream>

#include "cli/commands.h"
#include "runtime/export.h"

namespace rths::cli {

void add_export_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("export", "Turn a run record into CSV");
  auto record = std::make_shared<std::string>();
  auto csv = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("record", *record, "run record (.rthsrec)")->required();
  cmd->add_option("--csv", *csv, "CSV file to write")->required();
  cmd->add_flag("--json", *json, "print a JSON summary on stdout");
  cmd->callback([=] {
    runtime::RecordContents contents;
    try {
      contents = runtime::read_record(*record);
    } catch (const std::exception& e) {
      throw ExitError(kExitBadInput, e.what());
    }
    if (contents.truncated) std::cerr << "rths export: warning: " << contents.warning << "\n";
    std::size_t rows = 0;
    try {
      rows = runtime::write_csv(contents, *csv);
    } catch (const std::invalid_argument& e) {
      throw ExitError(kExitBadInput, *record + ": " + e.what());
    } catch (const std::exception& e) {
      throw ExitError(kExitEnvironment, e.what());
    }
    const auto* footer = contents.footer();
    const std::string status = footer ? footer->status() : "no footer: the run was cut short";
    if (*json) {
      nlohmann::json j{{"record", *record}, {"csv", *csv},         {"rows", rows},
                       {"truncated", contents.truncated}, {"status", status},
                       {"ok", footer && footer->ok()}};
      std::cout << j.dump(2) << "\n";
    } else {
      std::cout << "wrote " << rows << " steps to " << *csv << " (" << status << ")\n";
    }
  });
}

}  // namespace rths::cli
