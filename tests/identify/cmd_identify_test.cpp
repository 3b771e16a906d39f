// `rths identify` end to end: the declared model from a file (--model), its refusals (exit 2
// naming file and field), the identified model written back (--out) and read again, the study
// built from it run by `rths run`, --sample-rate for files without a time column, a DAQ export
// without force, and a distributed run's record written back as a study that `rths run` re-runs.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include "tests/support/run_command_line.h"

#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "core/metrics.h"
#include "identify/lab/generator.h"
#include "identify/model/data.h"
#include "runtime/record/measurements.h"
#include "study/study.h"
#include "study/text_columns.h"
#include "tests/identify/undeclared_run.h"

namespace rths::identify {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;

const std::string kRths = RTHS_EXECUTABLE;
const fs::path kData = RTHS_DATA_DIR;

using Outcome = test::CommandOutcome;

Outcome run(const std::string& arguments) {
  return test::run_command_line(kRths + " " + arguments);
}

nlohmann::json json_of(const Outcome& o) {
  const auto start = o.output.find('{');
  return nlohmann::json::parse(o.output.substr(start == std::string::npos ? 0 : start));
}

void write_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

class CmdIdentifyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rths_cmd_identify_test_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    GeneratorSpec spec;
    spec.duration = 12.0;
    spec.delay = 0.012;
    spec.first_order_time_constant = 0.005;
    spec.stiffness = 2.0e5;
    write_csv(generate_measured(spec), data_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string data() const { return data_.string(); }

  fs::path dir_;
  fs::path data_ =
      fs::temp_directory_path() / ("rths_cmd_identify_test_" + std::to_string(getpid()) + ".csv");
};

TEST_F(CmdIdentifyTest, TheModelFileDeclaresTheActuatorWithAFixedParameter) {
  write_file(dir_ / "lab.textproto", R"(
      actuator {
        stages: "delay"
        stages: "first_order"
        parameters { name: "delay" initial: 0.011 fixed: true }
        parameters { name: "time_constant" initial: 0.004 min: 0.001 max: 0.02 }
      })");
  const Outcome o =
      run("identify " + data() + " --channels measured --folds 0 --max-steps 0 --json --model " +
          (dir_ / "lab.textproto").string());
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const auto channel = json_of(o)["channels"][0];
  EXPECT_EQ(channel["declared_effects"], nlohmann::json({"delay", "first_order"}));
  const auto params = channel["declared"]["params"];
  EXPECT_EQ(params["delay"]["value"].get<double>(), 0.011);  // held, not fitted
  EXPECT_EQ(params["delay"]["std_error"].get<double>(), 0.0);
  EXPECT_NEAR(params["time_constant"]["value"].get<double>(), 0.005, 0.002);
}

TEST_F(CmdIdentifyTest, AFileAndAFlagForTheSameChannelConflict) {
  write_file(dir_ / "lab.textproto", "actuator { stages: \"delay\" }");
  const Outcome o = run("identify " + data() + " --declared-actuator delay,first_order --model " +
                        (dir_ / "lab.textproto").string());
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_THAT(o.output, HasSubstr("--declared-actuator conflicts with --model"));
}

TEST_F(CmdIdentifyTest, ABadModelFileExitsTwoNamingFileAndField) {
  const auto bad = (dir_ / "bad.textproto").string();
  write_file(bad,
             "actuator { stages: \"delay\" parameters { name: \"delay\" min: 0.05 max: 0.01 } }");
  Outcome o = run("identify " + data() + " --model " + bad);
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_THAT(o.output, AllOf(HasSubstr(bad + ": actuator.parameters[0] (delay)"),
                              HasSubstr("min 0.05 > max 0.01")));
  write_file(bad,
             "specimen { kind: \"linear_spring\" parameters { name: \"stiffness\" min: -1 } }");
  o = run("identify " + data() + " --model " + bad);
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_THAT(o.output, AllOf(HasSubstr(bad + ": specimen.parameters[0] (stiffness)"),
                              HasSubstr("a negative stiffness")));
  o = run("identify " + data() + " --model " + (dir_ / "missing.textproto").string());
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_THAT(o.output, HasSubstr("cannot open declared model"));
}

// --out writes the identified model, which --model reads back as the declared model, and a study
// built from the identified model, which `rths run` runs.
TEST_F(CmdIdentifyTest, TheIdentifiedModelReadsBackAndItsStudyRuns) {
  fs::copy_file(kData / "ground_motions/RSN175_IMPVALL.H_H-E12140.AT2", dir_ / "motion.AT2");
  write_file(dir_ / "frame.textproto", R"(
      name: "frame"
      structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }
      motion { path: "motion.AT2" duration: 5 }
      integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }
      substructuring { experimental_fraction: 0.3 model { linear {} } }
      cases { name: "reference" })");
  const fs::path out = dir_ / "out";
  const Outcome first = run("identify " + data() + " --folds 0 --json --out " + out.string() +
                            " --predict " + (dir_ / "frame.textproto").string());
  ASSERT_EQ(first.exit_code, 0) << first.output;
  const auto first_json = json_of(first);
  EXPECT_EQ(first_json["configs_written"].size(), 3u);
  // The identified lag is judged as `rths stability` judges the same structure: one verdict.
  const auto& stability = first_json["prediction"]["stability"];
  ASSERT_TRUE(stability.is_object()) << first_json["prediction"].dump();
  EXPECT_DOUBLE_EQ(stability["lag_s"].get<double>(),
                   first_json["prediction"]["identified"]["nominal_delay_s"].get<double>());
  const Outcome planned =
      run("stability --period 0.5 --zeta 0.05 --exp-fraction 0.3 --dt 0.001 --json");
  ASSERT_EQ(planned.exit_code, 0) << planned.output;
  const auto planned_json = json_of(planned);
  const double critical =
      std::min(planned_json["continuous"]["critical_delay_s"].get<double>(),
               planned_json["discrete"]["first_unstable_delay_s"].get<double>());
  EXPECT_NEAR(stability["critical_delay_s"].get<double>(), critical, 1e-9);
  EXPECT_NEAR(stability["margin"].get<double>(),
              (critical - stability["lag_s"].get<double>()) / critical, 1e-9);
  EXPECT_EQ(stability["past"].get<bool>(), stability["lag_s"].get<double>() >= critical);
  EXPECT_THAT(stability["verdict"].get<std::string>(), HasSubstr("the test could take up to"));
  for (const char* file : {"identified_model.textproto", "identified_study_fragment.textproto",
                           "identified_study.textproto"}) {
    EXPECT_TRUE(fs::exists(out / file)) << file;
  }

  const Outcome again = run("identify " + data() + " --folds 0 --json --model " +
                            (out / "identified_model.textproto").string());
  ASSERT_EQ(again.exit_code, 0) << again.output;
  const auto again_json = json_of(again);
  for (std::size_t k = 0; k < 2; ++k) {
    const auto& before = first_json["channels"][k];
    const auto& after = again_json["channels"][k];
    auto declared = after["declared"]["effects"].get<std::vector<std::string>>();
    auto identified = before["final"]["effects"].get<std::vector<std::string>>();
    std::sort(declared.begin(), declared.end());  // a specimen kind lists its effects first
    std::sort(identified.begin(), identified.end());
    EXPECT_EQ(declared, identified) << k;
    EXPECT_NEAR(after["declared"]["heldout_error"].get<double>(),
                before["final"]["heldout_error"].get<double>(),
                0.02 * before["final"]["heldout_error"].get<double>())
        << k;
  }

  // The study written beside it is the base with the identified parts; `rths run` runs it from
  // another folder (the motion's relative path was made absolute).
  fs::create_directories(dir_ / "elsewhere");
  fs::rename(out / "identified_study.textproto", dir_ / "elsewhere/study.textproto");
  const Outcome ran = run("run " + (dir_ / "elsewhere/study.textproto").string() +
                          " --no-plots --out " + (dir_ / "run").string());
  ASSERT_EQ(ran.exit_code, 0) << ran.output;
  EXPECT_THAT(ran.output, HasSubstr("identified_actuator"));
}

TEST_F(CmdIdentifyTest, AFileWithoutTimeNeedsTheSampleRate) {
  const MeasuredData record = read_csv(data_);
  {
    std::ofstream csv(dir_ / "untimed.csv");
    csv << "command,measured,force\n";
    csv.precision(10);
    for (std::size_t i = 0; i < record.size(); ++i) {
      csv << record.command[i] * 1e3 << "," << record.measured[i] * 1e3 << "," << record.force[i]
          << "\n";
    }
  }
  const std::string untimed = (dir_ / "untimed.csv").string();
  Outcome o = run("identify " + untimed + " --channels measured --folds 0");
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_THAT(o.output, AllOf(HasSubstr(untimed), HasSubstr("no 'time' column"),
                              HasSubstr("--sample-rate HZ")));
  o = run("identify " + untimed + " --channels measured --folds 0 --json --sample-rate 500");
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NEAR(json_of(o)["dt"].get<double>(), 0.002, 1e-12);
  // A rate that contradicts the file's own time column is refused.
  o = run("identify " + data() + " --channels measured --folds 0 --sample-rate 1000");
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_THAT(o.output,
              AllOf(HasSubstr("the time column gives 500"), HasSubstr("--sample-rate says 1000")));
}

TEST_F(CmdIdentifyTest, ADaqExportWithoutForceIdentifiesTheActuatorAlone) {
  // A raw DAQ export that logged only the command and the measured displacement.
  const MeasuredData record = read_csv(data_);
  const fs::path daq = dir_ / "no_force.txt";
  {
    std::ofstream out(daq);
    out << "Header Size: 4\nSampling Interval: " << record.dt << "\nTest: actuator only\n"
        << "Sample Number, CHANNEL0, CHANNEL2\n";
    out.precision(10);
    for (std::size_t i = 0; i < record.size(); ++i) {
      out << i << ", " << record.measured[i] * 1e2 << ", " << record.command[i] * 1e2 << "\n";
    }
  }
  Outcome o = run("identify " + daq.string() + " --channels measured --folds 0 --json");
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const auto report = json_of(o);
  ASSERT_EQ(report["channels"].size(), 1u);
  EXPECT_EQ(report["channels"][0]["channel"], "measured");
  // The force channel asked for still needs the column, and the message names it.
  o = run("identify " + daq.string() + " --channels measured,force --folds 0");
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_THAT(o.output, AllOf(HasSubstr(daq.string()), HasSubstr("missing column 'CHANNEL1'")));
}

TEST_F(CmdIdentifyTest, TrimIdleCutsTheRestBeforeTheTestOff) {
  const MeasuredData record = read_csv(data_);
  MeasuredData padded;
  padded.dt = record.dt;
  for (std::size_t i = 0; i < 1000 + record.size(); ++i) {  // 2 s at rest, then the record
    const std::size_t j = i < 1000 ? 0 : i - 1000;
    padded.time.push_back(static_cast<double>(i) * record.dt);
    padded.command.push_back(i < 1000 ? 0.0 : record.command[j]);
    padded.measured.push_back(i < 1000 ? 0.0 : record.measured[j]);
    padded.force.push_back(i < 1000 ? 0.0 : record.force[j]);
  }
  write_csv(padded, dir_ / "padded.csv");
  const Outcome o = run("identify " + (dir_ / "padded.csv").string() +
                        " --channels measured --folds 0 --max-steps 0 --json --trim-idle");
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const auto j = json_of(o);
  ASSERT_EQ(j["trimmed"].size(), 1u);
  EXPECT_THAT(j["trimmed"][0].get<std::string>(), HasSubstr("active part"));
  // The chirp starts at rest and leaves it within its first second: about 2 s are cut.
  const auto kept = j["samples"].get<std::size_t>();
  EXPECT_LT(kept, padded.size() - 800);
  EXPECT_GT(kept, record.size() - 600);
}

// Progress on stderr (cli/support.h ProgressReporter): stderr is a pipe here, not a terminal, so
// one plain line per 10 %, rising to 100 %, and no bar redrawn with carriage returns. --out also
// writes the actuator's Bode plot (PNG and SVG).
TEST_F(CmdIdentifyTest, ProgressIsPlainLinesOnAPipeAndOutWritesTheBodePlot) {
  const fs::path out = dir_ / "out";
  const Outcome o =
      run("identify " + data() + " --channels measured --folds 3 --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_EQ(o.output.find('\r'), std::string::npos);
  std::vector<int> percents;
  std::size_t at = 0;
  while ((at = o.output.find("identify: ", at)) != std::string::npos) {
    if (at == 0 || o.output[at - 1] == '\n') {
      percents.push_back(std::stoi(o.output.substr(at + 10, 4)));
      EXPECT_THAT(o.output.substr(at, o.output.find('\n', at) - at), HasSubstr(" steps, "));
    }
    at += 10;
  }
  ASSERT_FALSE(percents.empty()) << o.output;
  EXPECT_LE(percents.size(), 10u);
  EXPECT_TRUE(std::is_sorted(percents.begin(), percents.end()));
  EXPECT_EQ(std::adjacent_find(percents.begin(), percents.end()), percents.end());
  EXPECT_EQ(percents.back(), 100);
  for (const char* file : {"measured_bode.png", "measured_bode.svg"}) {
    ASSERT_TRUE(fs::exists(out / file)) << file;
    EXPECT_GT(fs::file_size(out / file), 1000u) << file;
  }
}

}  // namespace
}  // namespace rths::identify

namespace rths::identify {
namespace {

// Column `name` of a `rths run` results.csv.
std::vector<double> results_column(const fs::path& csv, const std::string& name) {
  const study::TextColumns table = study::read_text_columns(csv, "results", true);
  const auto at = std::find(table.title.begin(), table.title.end(), name);
  if (at == table.title.end()) throw std::invalid_argument(csv.string() + ": no column " + name);
  std::vector<double> out;
  for (const auto& row : table.rows)
    out.push_back(row.values.at(static_cast<std::size_t>(at - table.title.begin())));
  return out;
}

TEST_F(CmdIdentifyTest, ARunRecordIsWrittenBackAsAStudyThatRunReproduces) {
  const fs::path record = test::run_with_undeclared(
      "written_back", "receive_delay { first_order { time_constant: 0.008 } }");
  Outcome o = run("identify " + record.string() + " --channels measured --json --out " +
                  (dir_ / "id").string());
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const auto residual = json_of(o)["residual"];
  EXPECT_GE(residual["declared_nrmse"].get<double>(), 0.20) << residual;
  EXPECT_LE(residual["identified_nrmse"].get<double>(), 0.02) << residual;
  const fs::path study = dir_ / "id" / "identified_run.textproto";
  const config::Study parsed = study::load_study(study);
  EXPECT_TRUE(std::any_of(parsed.cases().begin(), parsed.cases().end(),
                          [](const auto& c) { return c.name() == "identified_actuator"; }));
  EXPECT_TRUE(fs::exists(dir_ / "id" / "lag_node_1.csv"));
  EXPECT_TRUE(fs::exists(dir_ / "id" / "lag_node_2.csv"));
  for (const char* png : {"record_lag.png", "record_response.png", "record_shares.png"}) {
    EXPECT_TRUE(fs::exists(dir_ / "id" / png)) << png;
  }
  o = run("run " + study.string() + " --no-plots --out " + (dir_ / "rerun").string());
  ASSERT_EQ(o.exit_code, 0) << o.output;
  // The study's identified case reproduces the recorded response; the run's declared case did not.
  const auto steps = runtime::measure_run(runtime::read_record(record)).steps;
  std::vector<double> recorded(static_cast<std::size_t>(steps.displacement.rows()));
  for (std::size_t k = 0; k < recorded.size(); ++k)
    recorded[k] = steps.displacement(static_cast<Eigen::Index>(k), 0);
  const fs::path results = dir_ / "rerun" / "results.csv";
  const auto identified = results_column(results, "identified_actuator_u_floor1_m");
  const auto declared = results_column(results, "lag_shift_14ms_u_floor1_m");
  ASSERT_EQ(identified.size(), recorded.size());
  EXPECT_LE(core::nrmse(recorded, identified), 0.02);
  EXPECT_GE(core::nrmse(recorded, declared), 0.20);
}

// A rig with a velocity limit and a load cell offset that the header does not declare: the one
// verdict names both on their parts, the written study carries them as stages, and `rths run`
// of it reproduces the record.
TEST_F(CmdIdentifyTest, TheWrittenStudyCarriesTheRigsOwnEffectsAndReproducesTheRecord) {
  const fs::path record =
      test::run_with_undeclared("written_rig",
                                "receive_delay { velocity_limit { max_velocity: 0.05 } } "
                                "receive_delay { sensor_drift { force_offset: 500 } }");
  Outcome o = run("identify " + record.string() + " --json --out " + (dir_ / "rig").string());
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const auto report = json_of(o);
  std::set<std::string> parts;
  for (const auto& f : report["undeclared"]) {
    parts.insert(f["part"].get<std::string>() + ": " + f["effect"].get<std::string>());
    EXPECT_TRUE(f["rerun"].get<bool>()) << f.dump();
  }
  EXPECT_TRUE(parts.count("actuator 1: velocity_saturation")) << report["undeclared"].dump(2);
  EXPECT_TRUE(parts.count("load cell 1: offset_drift")) << report["undeclared"].dump(2);
  const fs::path study = dir_ / "rig" / "identified_run.textproto";
  const config::Study parsed = study::load_study(study);
  const auto identified =
      std::find_if(parsed.cases().begin(), parsed.cases().end(),
                   [](const auto& c) { return c.name() == "identified_actuator"; });
  ASSERT_NE(identified, parsed.cases().end());
  std::set<std::string> stages;
  for (const auto& stage : identified->delay()) {
    if (stage.has_velocity_limit()) stages.insert("velocity_limit");
    if (stage.has_sensor_drift() && stage.sensor_drift().force_offset() != 0.0)
      stages.insert("load cell");
  }
  EXPECT_EQ(stages, (std::set<std::string>{"velocity_limit", "load cell"}))
      << identified->DebugString();
  o = run("run " + study.string() + " --no-plots --out " + (dir_ / "rig_rerun").string());
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const auto steps = runtime::measure_run(runtime::read_record(record)).steps;
  std::vector<double> recorded(static_cast<std::size_t>(steps.displacement.rows()));
  for (std::size_t k = 0; k < recorded.size(); ++k)
    recorded[k] = steps.displacement(static_cast<Eigen::Index>(k), 0);
  const auto rerun =
      results_column(dir_ / "rig_rerun" / "results.csv", "identified_actuator_u_floor1_m");
  ASSERT_EQ(rerun.size(), recorded.size());
  EXPECT_LE(core::nrmse(recorded, rerun), 0.02);
}

// A record carries its inputs (the motion as run, the matrices, the traces): copied alone into an
// archive and identified from another folder, it re-runs from what it holds, and the study it
// writes back runs from any folder.
TEST_F(CmdIdentifyTest, ARecordMovedAnywhereIsIdentifiedFromTheInputsItCarries) {
  const fs::path made =
      test::run_with_undeclared("moved", "receive_delay { first_order { time_constant: 0.008 } }");
  const fs::path archive = dir_ / "archive", elsewhere = dir_ / "elsewhere";
  fs::create_directories(archive);
  fs::create_directories(elsewhere);
  const fs::path record = archive / "run.rthsrec";
  fs::copy_file(made, record);
  Outcome o = test::run_command_line("cd " + elsewhere.string() + " && " + kRths + " identify " +
                                     record.string() + " --channels measured --json --out id");
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const auto report = json_of(o);
  EXPECT_EQ(report["inputs"], "embedded in the record") << report.dump(2);
  EXPECT_LE(report["residual"]["identified_nrmse"].get<double>(), 0.02) << report["residual"];
  o = test::run_command_line("cd / && " + kRths + " run " +
                             (elsewhere / "id" / "identified_run.textproto").string() +
                             " --no-plots --out " + (dir_ / "rerun").string());
  EXPECT_EQ(o.exit_code, 0) << o.output;
  o = run("export " + record.string() + " --csv " + (dir_ / "exported.csv").string());
  EXPECT_EQ(o.exit_code, 0) << o.output;
}

TEST_F(CmdIdentifyTest, ADamagedRunRecordExitsTwoNamingRecordAndEntry) {
  const fs::path record = test::run_with_undeclared("damaged_cli", "");
  {
    std::fstream bytes(record, std::ios::in | std::ios::out | std::ios::binary);
    bytes.seekp(static_cast<std::streamoff>(fs::file_size(record) / 2));
    bytes.put('\x5a').put('\xa5').put('\x5a');
  }
  const Outcome o = run("identify " + record.string() + " --channels measured");
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_THAT(o.output, AllOf(HasSubstr(record.string()), HasSubstr("damaged entries")));
}

}  // namespace
}  // namespace rths::identify
