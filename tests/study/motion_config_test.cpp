#include "study/motion_config.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/ground_motion.h"
#include "study/motion_files.h"
#include "study/text_format.h"

namespace rths::study {
namespace {

const std::filesystem::path kConfigs = std::filesystem::path(RTHS_SOURCE_DIR) / "configs";

class MotionUnits : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        std::filesystem::temp_directory_path() / ("rths_motion_units_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
    // 0.35 g written in three units.
    std::ofstream(dir_ / "g.txt") << "0 0\n0.01 0.35\n0.02 0\n";
    std::ofstream(dir_ / "ms2.txt") << "0 0\n0.01 3.4323275\n0.02 0\n";
    std::ofstream(dir_ / "cms2.txt") << "0 0\n0.01 343.23275\n0.02 0\n";
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  core::GroundMotion load(const std::string& text) {
    config::GroundMotion motion;
    parse_text_format(text, "t", motion);
    return load_motion(motion, dir_);
  }
  std::string error(const std::string& text) {
    try {
      load(text);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  }
  std::filesystem::path dir_;
};

TEST_F(MotionUnits, EveryUnitGivesTheSameRecordInSi) {
  const double expected = 0.35 * core::kGravity;
  EXPECT_NEAR(load("path: \"g.txt\" column_units: G").peak_abs(), expected, 1e-9);
  EXPECT_NEAR(load("path: \"ms2.txt\" column_units: M_PER_S2").peak_abs(), expected, 1e-6);
  EXPECT_NEAR(load("path: \"cms2.txt\" column_units: CM_PER_S2").peak_abs(), expected, 1e-6);
}

TEST_F(MotionUnits, AColumnsFileWithoutUnitsIsRefused) {
  const std::string e = error("path: \"ms2.txt\"");
  EXPECT_NE(e.find("column_units"), std::string::npos) << e;
  EXPECT_NE(e.find("--motion-units"), std::string::npos) << e;
}

TEST_F(MotionUnits, AnImplausiblePeakNamesTheUnits) {
  // 343 cm/s^2 read as m/s^2 is 35 g.
  const std::string e = error("path: \"cms2.txt\" column_units: M_PER_S2");
  EXPECT_NE(e.find("beyond any recorded earthquake"), std::string::npos) << e;
}

TEST_F(MotionUnits, AnAt2FileIsInGAndRefusesAnotherUnit) {
  const std::filesystem::path at2 =
      kConfigs / "../data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2";
  config::GroundMotion motion;
  motion.set_path(at2.string());
  EXPECT_NEAR(load_motion(motion, dir_).peak_abs(), 0.145 * core::kGravity,
              0.01 * core::kGravity);  // El Centro #12
  motion.set_column_units(config::GroundMotion::M_PER_S2);
  EXPECT_THROW(load_motion(motion, dir_), std::invalid_argument);
  EXPECT_EQ(units_name(units_from_name("cm/s2")), "cm/s2");
  EXPECT_THROW(units_from_name("ft/s2"), std::invalid_argument);
}

// The El Centro #12 record rewritten as a lab's file in cm/s^2: header line 3 `units`, every
// value times 980.665, written to 11 significant digits.
std::filesystem::path at2_in_cm(const std::filesystem::path& dir, const std::string& units) {
  std::ifstream in(kConfigs / "../data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2");
  const std::filesystem::path out_path = dir / "elcentro12_cm.AT2";
  std::ofstream out(out_path);
  std::string line;
  for (int i = 1; std::getline(in, line); ++i) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (i == 3) line = units;
    if (i <= 4) {
      out << line << "\n";
      continue;
    }
    std::istringstream values(line);
    double g = 0.0;
    while (values >> g) out << std::setprecision(11) << g * 980.665 << " ";
    out << "\n";
  }
  return out_path;
}

TEST_F(MotionUnits, AnAt2HeaderInCmPerS2IsReadInItsUnits) {
  config::GroundMotion in_g, in_cm;
  in_g.set_path((kConfigs / "../data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2").string());
  in_cm.set_path(at2_in_cm(dir_, "ACCELERATION TIME SERIES IN UNITS OF CM/S/S").string());
  const core::GroundMotion g = load_motion(in_g, dir_), cm = load_motion(in_cm, dir_);
  ASSERT_EQ(g.acceleration.size(), cm.acceleration.size());
  for (std::size_t i = 0; i < g.acceleration.size(); ++i)
    ASSERT_NEAR(cm.acceleration[i], g.acceleration[i], 1e-9 * g.peak_abs()) << i;
  EXPECT_EQ(cm.read_units, "cm/s2");
  EXPECT_NE(cm.description.find("7814 points at dt 0.005 s"), std::string::npos) << cm.description;
  EXPECT_NE(cm.description.find("values in cm/s2 (the AT2 header"), std::string::npos)
      << cm.description;
  EXPECT_EQ(g.read_units, "g");
  // The config may say what the header says; it may not say otherwise.
  in_cm.set_column_units(config::GroundMotion::CM_PER_S2);
  EXPECT_NO_THROW(load_motion(in_cm, dir_));
  in_cm.set_column_units(config::GroundMotion::G);
  try {
    load_motion(in_cm, dir_);
    FAIL() << "a header in cm/s2 and a config in g were both accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("states cm/s2"), std::string::npos) << what;
    EXPECT_NE(what.find("says g"), std::string::npos) << what;
  }
}

TEST_F(MotionUnits, TheNgaSpellingsAreRead) {
  for (const auto& [line, name] : std::vector<std::pair<std::string, std::string>>{
           {"ACCELERATION TIME HISTORY IN UNITS OF G", "g"},
           {"UNITS: CM/SEC/SEC", "cm/s2"},
           {"ACCEL. (CM/S^2)", "cm/s2"},
           {"Acceleration in gal", "cm/s2"},
           {"ACCELERATION IN M/S/S", "m/s2"},
           {"ACCELERATION IN IN/S/S", "in/s2"}}) {
    const std::filesystem::path path = dir_ / "spelling.AT2";
    std::ofstream(path) << "PEER\nstation G\n" << line << "\nNPTS= 2, DT= 0.01 SEC\n0.1 0.2\n";
    const auto stated = at2_stated_units(path);
    ASSERT_TRUE(stated.has_value()) << line;
    EXPECT_EQ(stated->name, name) << line;
  }
  // A station named G on line 2 is no unit; a header that states none is in g by the format,
  // or in the config's units.
  const std::filesystem::path silent = dir_ / "silent.AT2";
  std::ofstream(silent) << "PEER\nstation G\nno statement\nNPTS= 2, DT= 0.01 SEC\n10 20\n";
  EXPECT_FALSE(at2_stated_units(silent).has_value());
  config::GroundMotion motion;
  motion.set_path(silent.string());
  motion.set_column_units(config::GroundMotion::CM_PER_S2);
  EXPECT_NEAR(load_motion(motion, dir_).peak_abs(), 0.2, 1e-12);
}

}  // namespace
}  // namespace rths::study
