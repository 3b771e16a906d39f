#include "identify/model/data.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

namespace rths::identify {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;

const fs::path kRealFile = fs::path(RTHS_DATA_DIR) / "measured/mts_mrdamper_chirp_0A.txt";

class DataTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() /
        ("rths_identify_data_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
  static std::string csv_rows(int n, double dt = 0.01) {
    std::string s;
    for (int i = 0; i < n; ++i) {
      s += std::to_string(i * dt) + "," + std::to_string(std::sin(i * 0.1)) + "," +
           std::to_string(std::sin(i * 0.1 - 0.05)) + "," +
           std::to_string(100 * std::sin(i * 0.1)) + "\n";
    }
    return s;
  }
  template <typename F>
  static std::string error_of(F&& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no error";
  }
  fs::path dir_;
};

TEST_F(DataTest, CsvConvertsUnitsToSi) {
  const auto p = write("ok.csv", "time,command,measured,force\n" + csv_rows(300));
  const MeasuredData d = read_csv(p);
  ASSERT_EQ(d.size(), 300u);
  EXPECT_NEAR(d.dt, 0.01, 1e-9);
  EXPECT_NEAR(d.command[10], 1e-3 * std::sin(1.0), 1e-9);  // mm -> m
  EXPECT_NEAR(d.force[10], 100 * std::sin(1.0), 1e-4);
  CsvUnits metres{1.0, 1.0, 1000.0};
  EXPECT_NEAR(read_csv(p, metres).force[10], 1e5 * std::sin(1.0), 0.1);
}

TEST_F(DataTest, CsvColumnsInAnyOrderAndRoundTrip) {
  const auto p = write("ok.csv", "force,measured,time,command\n1,2,0,3\n4,5,0.5,6\n7,8,1.0,9\n");
  const MeasuredData d = read_csv(p, {}, 3);
  EXPECT_DOUBLE_EQ(d.command[1], 6e-3);
  EXPECT_DOUBLE_EQ(d.force[0], 1.0);
  write_csv(d, dir_ / "back.csv");
  const MeasuredData back = read_csv(dir_ / "back.csv", {}, 3);
  EXPECT_NEAR(back.measured[1], 5e-3, 1e-12);
}

TEST_F(DataTest, MissingColumnIsNamed) {
  const auto p = write("bad.csv", "time,command,measured\n" + csv_rows(300));
  EXPECT_THAT(error_of([&] { read_csv(p); }), HasSubstr("missing column 'force'"));
}

TEST_F(DataTest, NanIsNamedWithLineAndColumn) {
  auto rows = csv_rows(300);
  const auto p =
      write("nan.csv", "time,command,measured,force\n" + rows.substr(0, rows.find('\n') + 1) +
                           "0.01,nan,1,1\n" + rows.substr(rows.find('\n') + 1));
  const auto message = error_of([&] { read_csv(p); });
  EXPECT_THAT(message, HasSubstr("nan.csv:3"));
  EXPECT_THAT(message, HasSubstr("command"));
}

TEST_F(DataTest, NonMonotonicTimeIsRejected) {
  const auto p = write("time.csv", "time,command,measured,force\n0,0,0,0\n0.2,0,0,0\n0.1,0,0,0\n");
  EXPECT_THAT(error_of([&] { read_csv(p, {}, 2); }),
              HasSubstr("time does not increase at sample 3"));
}

TEST_F(DataTest, TooShortForTheModel) {
  const auto p = write("short.csv", "time,command,measured,force\n" + csv_rows(20));
  EXPECT_THAT(error_of([&] { read_csv(p); }), HasSubstr("only 20 samples"));
}

TEST_F(DataTest, RaggedRowIsNamed) {
  const auto p = write("ragged.csv", "time,command,measured,force\n0,1,2,3\n0.1,1,2\n");
  EXPECT_THAT(error_of([&] { read_csv(p, {}, 1); }), HasSubstr("ragged.csv:3"));
}

TEST_F(DataTest, TheForceColumnIsOptionalOnlyWhenAskedSo) {
  const auto p = write("no_force.csv", "time,command,measured\n" + csv_rows(300));
  EXPECT_THAT(error_of([&] { read_csv(p); }), HasSubstr("missing column 'force'"));
  const MeasuredData d = read_csv(p, {}, kDefaultMinSamples, 0.0, ForceColumn::kOptional);
  EXPECT_EQ(d.size(), 300u);
  EXPECT_FALSE(d.has_force());
  EXPECT_EQ(slice(d, 10, 20).size(), 10u);
  EXPECT_FALSE(decimated(d, 4).has_force());
  const auto with = write("with_force.csv", "time,command,measured,force\n" + csv_rows(300));
  EXPECT_TRUE(read_csv(with, {}, kDefaultMinSamples, 0.0, ForceColumn::kOptional).has_force());
}

TEST_F(DataTest, RealDaqExportLoadsWithItsScales) {
  const MeasuredData d = read_measured(kRealFile);
  ASSERT_EQ(d.size(), 61500u);
  EXPECT_NEAR(d.dt, 0.001, 1e-12);
  // First data line: CHANNEL0 -0.0209, CHANNEL1 -0.0166, CHANNEL2 -0.0169.
  EXPECT_NEAR(d.command[0], -0.0169 * 10 * 1e-3, 1e-12);
  EXPECT_NEAR(d.measured[0], -0.0209 * 10 * 1e-3, 1e-12);
  EXPECT_NEAR(d.force[0], -0.0166 * 9806.65, 1e-9);
}

TEST_F(DataTest, ColumnMapNamingAMissingChannel) {
  const auto map = parse_column_map("command=CHANNEL7*10");
  const auto message = error_of([&] { read_daq(kRealFile, map); });
  EXPECT_THAT(message, HasSubstr("missing column 'CHANNEL7'"));
  EXPECT_THAT(message, HasSubstr("mts_mrdamper_chirp_0A.txt:7"));
}

TEST_F(DataTest, ColumnMapSyntaxErrors) {
  EXPECT_THAT(error_of([] { parse_column_map("command"); }), HasSubstr("expected signal=COLUMN"));
  EXPECT_THAT(error_of([] { parse_column_map("speed=CHANNEL1*2"); }),
              HasSubstr("unknown signal 'speed'"));
  EXPECT_THAT(error_of([] { parse_column_map("force=CHANNEL1*x"); }), HasSubstr("scale 'x'"));
  EXPECT_EQ(parse_column_map("force=CHANNEL3*2.5").force.column, "CHANNEL3");
}

TEST_F(DataTest, DaqWithoutSamplingIntervalIsRejected) {
  const auto p = write(
      "daq.txt",
      "Header Size:  3\nVersion: 2\nSample Number, CHANNEL0, CHANNEL1, CHANNEL2\n1, 0, 0, 0\n");
  EXPECT_THAT(error_of([&] { read_daq(p); }),
              AllOf(HasSubstr("Sampling Interval"), HasSubstr("--sample-rate HZ")));
}

// DAQ rows without Sample Number, `rows` of them, channels 0..2 = i, 2 i, 3 i.
std::string daq_rows(int rows) {
  std::string s;
  for (int i = 0; i < rows; ++i) {
    s += std::to_string(i) + ", " + std::to_string(2 * i) + ", " + std::to_string(3 * i) + "\n";
  }
  return s;
}

TEST_F(DataTest, DaqTimedByTheGivenRateOrTheHeadersRate) {
  const auto untimed = write(
      "untimed.txt", "Header Size: 3\nVersion: 2\nCHANNEL0, CHANNEL1, CHANNEL2\n" + daq_rows(300));
  const MeasuredData d = read_daq(untimed, {}, kDefaultMinSamples, 200.0);
  ASSERT_EQ(d.size(), 300u);
  EXPECT_NEAR(d.dt, 0.005, 1e-15);
  EXPECT_NEAR(d.time[299], 299 * 0.005, 1e-12);
  EXPECT_NEAR(d.measured[10], 10 * 10 * 1e-3, 1e-12);  // CHANNEL0 x 10 mm -> m
  // "Sampling Rate" alone is a time base too; a given rate must agree with it.
  const auto rated =
      write("rated.txt",
            "Header Size: 3\nSampling Rate: 4096\nCHANNEL0, CHANNEL1, CHANNEL2\n" + daq_rows(300));
  EXPECT_NEAR(read_daq(rated).dt, 1.0 / 4096, 1e-12);
  EXPECT_NEAR(read_daq(rated, {}, kDefaultMinSamples, 4096.0).dt, 1.0 / 4096, 1e-12);
  EXPECT_THAT(
      error_of([&] { read_daq(rated, {}, kDefaultMinSamples, 1000.0); }),
      AllOf(HasSubstr("rated.txt"), HasSubstr("gives 4096"), HasSubstr("--sample-rate says 1000")));
  const auto both = write("both.txt",
                          "Header Size: 4\nSampling Interval: 0.001\nSampling Rate: 500\n"
                          "CHANNEL0, CHANNEL1, CHANNEL2\n" +
                              daq_rows(300));
  EXPECT_THAT(error_of([&] { read_daq(both); }), HasSubstr("disagree"));
}

// 3 s at rest (offset 0.2 mm, noise-free), a 4 s sine of 2 mm, 2 s at rest at 0.3 mm.
MeasuredData idle_then_moving() {
  MeasuredData d;
  d.source = "idle";
  d.dt = 0.01;
  for (int i = 0; i < 900; ++i) {
    const double t = i * d.dt;
    const double c = t < 3.0   ? 2e-4
                     : t < 7.0 ? 2e-4 + 2e-3 * std::sin(2 * M_PI * 0.5 * (t - 3.0))
                               : 3e-4;
    d.time.push_back(t);
    d.command.push_back(c);
    d.measured.push_back(c);
    d.force.push_back(1e5 * c);
  }
  return d;
}

TEST_F(DataTest, TheActivePartLeavesTheIdleStretchesOut) {
  const MeasuredData d = idle_then_moving();
  // Leaves rest by 5 % of the 2 mm peak (0.1 mm) at asin(0.05) / pi s after 3 s; the last
  // excursion beyond 0.1 mm from 0.3 mm ends just before 7 s. Margins of 0.25 s either side.
  const ActiveRange r = active_range(d);
  const double leaves = 3.0 + std::asin(0.05) / M_PI;
  EXPECT_NEAR(d.time[r.begin], leaves - 0.25, 0.011);
  EXPECT_NEAR(d.time[r.end - 1], 7.0 + 0.25, 0.03);
  const ActiveRange tight = active_range(d, 0.05, 0.0);
  EXPECT_GT(d.time[tight.begin], 3.0);
  EXPECT_LT(d.time[tight.end - 1], 7.0);
  // A record that moves throughout is kept whole.
  MeasuredData moving = d;
  for (std::size_t i = 0; i < moving.size(); ++i) moving.command[i] = std::sin(0.05 * i);
  const ActiveRange whole = active_range(moving);
  EXPECT_EQ(whole.begin, 0u);
  EXPECT_EQ(whole.end, moving.size());
  EXPECT_THROW(active_range(d, 1.5), std::invalid_argument);
}

TEST_F(DataTest, CsvWithoutTimeNeedsTheSampleRate) {
  std::string rows;
  for (int i = 0; i < 300; ++i) rows += std::to_string(i) + "," + std::to_string(i + 1) + ",5\n";
  const auto p = write("untimed.csv", "command,measured,force\n" + rows);
  EXPECT_THAT(error_of([&] { read_csv(p); }),
              AllOf(HasSubstr("untimed.csv:1"), HasSubstr("no 'time' column"),
                    HasSubstr("--sample-rate HZ")));
  const MeasuredData d = read_measured(p, {}, {}, kDefaultMinSamples, 2048.0);
  EXPECT_NEAR(d.dt, 1.0 / 2048, 1e-15);
  EXPECT_NEAR(d.command[7], 7e-3, 1e-15);
  // A CSV with its own time column: the given rate is checked against it.
  const auto timed = write("timed.csv", "time,command,measured,force\n" + csv_rows(300));
  EXPECT_NEAR(read_csv(timed, {}, kDefaultMinSamples, 100.0).dt, 0.01, 1e-9);
  EXPECT_THAT(error_of([&] { read_csv(timed, {}, kDefaultMinSamples, 1000.0); }),
              HasSubstr("the time column gives 100"));
}

// Found by fuzz_daq_export (fuzz/regressions/daq_export/header_size_beyond_int): a Header Size of
// 8.9e65 was converted to int (undefined behaviour) before any check.
TEST_F(DataTest, DaqHeaderSizeOutOfRangeIsNamed) {
  const fs::path found =
      fs::path(RTHS_SOURCE_DIR) / "fuzz/regressions/daq_export/header_size_beyond_int";
  EXPECT_THAT(error_of([&] { read_daq(found); }),
              AllOf(HasSubstr(found.string() + ":1:"),
                    HasSubstr("Header Size must be a whole number in 2..10000")));
  for (const char* size : {"1e300", "-3", "2.5", "10001"}) {
    const auto p = write("daq.txt", std::string("Header Size: ") + size + "\nVersion: 2\n");
    EXPECT_THAT(error_of([&] { read_daq(p); }), HasSubstr("Header Size must be a whole number"))
        << size;
  }
}

TEST_F(DataTest, HoldoutSplits) {
  const Split last = holdout_split(1000, 0.3, HoldoutMode::kLast);
  EXPECT_EQ(last.train.size(), 700u);
  EXPECT_EQ(last.heldout.front(), 700u);
  const Split blocks = holdout_split(1000, 0.3, HoldoutMode::kBlocks, 10);
  EXPECT_EQ(blocks.heldout.size(), 300u);
  EXPECT_EQ(blocks.heldout.back(), 999u);   // the last block is held out
  EXPECT_LT(blocks.heldout.front(), 500u);  // and the others spread over the record
  EXPECT_THROW(holdout_split(1000, 1.5), std::invalid_argument);
  EXPECT_THROW(holdout_split(60, 0.3), std::invalid_argument);
}

TEST_F(DataTest, DecimationAveragesThenPicks) {
  const auto p = write("ok.csv", "time,command,measured,force\n" + csv_rows(300));
  const MeasuredData d = decimated(read_csv(p), 3);
  EXPECT_EQ(d.size(), 100u);
  EXPECT_NEAR(d.dt, 0.03, 1e-9);
}

TEST_F(DataTest, UnitNames) {
  EXPECT_DOUBLE_EQ(length_unit_to_m("in"), 0.0254);
  EXPECT_DOUBLE_EQ(force_unit_to_n("kN"), 1000.0);
  EXPECT_THROW(time_unit_to_s("h"), std::invalid_argument);
}

}  // namespace
}  // namespace rths::identify
