// The fuzz harness, built with the normal compiler and without libFuzzer: every entry runs over
// its whole seed corpus and over a few hostile inputs, and comes back. So a harness that no longer
// builds, a corpus that went missing, or a parser that throws something other than its
// documented error (std::invalid_argument / std::runtime_error) fails here, in the normal suite.
#include "fuzz/targets.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <set>
#include <sstream>

#include "runtime/record/record.h"

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
       {std::string(), std::string(1, '\0'), std::string(1, '\x01'), noise, std::string(3000, '9'),
        std::string("\xff\xff\xff\xff\xff\xff\xff\xff\x01", 9)}) {
    EXPECT_EQ(run(GetParam(), input), 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Every, FuzzTarget, ::testing::ValuesIn(targets()),
                         [](const auto& info) { return std::string(info.param.name); });

// The target: 100 records with 1-100 random byte flips each (distinct positions, anywhere
// in the file). Every damaged entry is detected (dropped and inside a reported loss region), none
// silently; every intact entry is recovered byte for byte.
TEST(RecordFlips, EveryFlippedEntryIsDetectedAndEveryIntactOneRecovered) {
  std::mt19937 random(2026);
  FlipVerdict total;
  for (int r = 0; r < 100; ++r) {
    const int steps = 20 + static_cast<int>(random() % 600);
    const std::string original = flip_test_record(steps);
    const int flips = 1 + static_cast<int>(random() % 100);
    std::string damaged = original;
    std::set<std::size_t> positions;
    while (static_cast<int>(positions.size()) < flips) positions.insert(random() % original.size());
    for (std::size_t at : positions)
      damaged[at] = static_cast<char>(damaged[at] ^ (1 + random() % 255));
    const FlipVerdict v = check_flipped_record(original, damaged);
    EXPECT_TRUE(v.holds()) << "record " << r << " (" << steps << " steps, " << flips
                           << " flips): " << v.silent << " silent, " << v.unreported
                           << " unreported, " << v.lost_intact << " intact lost";
    total += v;
  }
  EXPECT_EQ(total.silent, 0u);
  EXPECT_EQ(total.unreported, 0u);
  EXPECT_EQ(total.detected, total.damaged);
  EXPECT_EQ(total.recovered, total.intact);
  EXPECT_GT(total.damaged, 1000u);  // the trial damaged many entries, not a few
  std::cout << "100 records, " << total.entries << " entries: " << total.damaged
            << " damaged, all detected (0 silent); " << total.intact << " intact, all recovered\n";
}

// The entry point over its own input format: a verdict that does not hold is reported (thrown),
// so the fuzzer cannot miss a silent corruption.
TEST(RecordFlips, TheEntryPointJudgesItsInputFormat) {
  EXPECT_EQ(run({"record_flips", &record_flips}, flips_input(50, {{300, 0x10}, {2000, 0x00}})), 0);
  const std::string record = flip_test_record(50);
  std::string damaged = record;
  damaged[300] = static_cast<char>(damaged[300] ^ 0x10);
  const FlipVerdict v = check_flipped_record(record, damaged);
  EXPECT_EQ(v.damaged, 1u);
  EXPECT_EQ(v.detected, 1u);
  EXPECT_EQ(v.recovered, v.entries - 1);
  // A changed entry whose checksums were recomputed passes any reader: the verdict calls it
  // silent, so a reader that stopped checking would fail this target.
  const auto offsets = runtime::parse_record(record, "record").offsets;
  const std::size_t frame = offsets[1], end = offsets[2];  // step 0
  std::string forged = record;
  forged[end - 1] = static_cast<char>(forged[end - 1] ^ 0x01);  // a byte of its last double
  runtime::seal_record_frame(
      forged.data() + frame,
      static_cast<std::uint32_t>(end - frame - runtime::kRecordFrameHeaderBytes));
  const FlipVerdict fooled = check_flipped_record(record, forged);
  EXPECT_EQ(fooled.silent, 1u);
  EXPECT_FALSE(fooled.holds());
}

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
