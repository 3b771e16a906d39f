// The fuzz harness, built with the normal compiler and without libFuzzer: every entry runs over
// its whole seed corpus and over a few hostile inputs, and comes back. So a harness that no longer
// builds, a corpus that went missing, or a parser that throws something other than its
// documented error (std::invalid_argument / std::runtime_error) fails here, in the normal suite.
#include "fuzz/targets.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

namespace rths::fuzz {

// gtest prints a parameter with this (test names show the target, not its bytes).
void PrintTo(const Target& target, std::ostream* out) { *out << target.name; }

namespace {

namespace fs = std::filesystem;

const fs::path kCorpus = fs::path(RTHS_SOURCE_DIR) / "fuzz" / "corpus";

std::string bytes_of(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

int run(const Target& target, const std::string& input) {
  return target.entry(reinterpret_cast<const std::uint8_t*>(input.data()), input.size());
}

class FuzzTarget : public ::testing::TestWithParam<Target> {};

TEST_P(FuzzTarget, RunsOverItsWholeSeedCorpus) {
  const fs::path dir = kCorpus / GetParam().name;
  ASSERT_TRUE(fs::is_directory(dir)) << dir;
  int seeds = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    SCOPED_TRACE(entry.path().string());
    EXPECT_EQ(run(GetParam(), bytes_of(entry.path())), 0);
    ++seeds;
  }
  EXPECT_GE(seeds, 2) << "each target keeps at least two real seeds";
}

// Every input a fuzzer once crashed on (fuzz/regressions/<target>/, each with a regression test
// of its own next to the parser's tests) keeps coming back cleanly.
TEST_P(FuzzTarget, RunsOverEveryPastFinding) {
  const fs::path dir = fs::path(RTHS_SOURCE_DIR) / "fuzz" / "regressions" / GetParam().name;
  if (!fs::is_directory(dir)) return;
  for (const auto& entry : fs::directory_iterator(dir)) {
    SCOPED_TRACE(entry.path().string());
    EXPECT_EQ(run(GetParam(), bytes_of(entry.path())), 0);
  }
}

TEST_P(FuzzTarget, SurvivesHostileInput) {
  std::mt19937 random(17);
  std::string noise(4096, '\0');
  for (char& c : noise) c = static_cast<char>(random());
  for (const std::string& input :
       {std::string(), std::string(1, '\0'), std::string(1, '\x01'), noise,
        std::string(3000, '9'), std::string("\xff\xff\xff\xff\xff\xff\xff\xff\x01", 9)}) {
    EXPECT_EQ(run(GetParam(), input), 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Every, FuzzTarget, ::testing::ValuesIn(targets()),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(EnvelopeRecord, EncodesKindStepAndSizeLittleEndian) {
  const std::string r = envelope_record(4, 0x01020304, "ab");
  ASSERT_EQ(r.size(), 9u);
  EXPECT_EQ(r[0], 4);
  EXPECT_EQ(r.substr(1, 4), std::string("\x04\x03\x02\x01", 4));
  EXPECT_EQ(r.substr(5, 2), std::string("\x02\x00", 2));
  EXPECT_EQ(r.substr(7), "ab");
}

}  // namespace
}  // namespace rths::fuzz
