// What a launcher hands its coordinator's view through the environment reads back as written,
// and a variable that does not parse is refused naming it.
#include "view/hand_down.h"

#include <gtest/gtest.h>

#include <cstdlib>

namespace rths::view {
namespace {

void clear() {
  for (const char* name : {"RTHS_VIEW_FD", "RTHS_VIEW_SITES", "RTHS_VIEW_CREW"}) ::unsetenv(name);
}

TEST(HandDown, ReadsBackWhatWasHandedDown) {
  clear();
  EXPECT_EQ(handed_down().listen_fd, -1);
  EXPECT_FALSE(handed_down().crew);
  HandDown down;
  down.listen_fd = 7;
  down.sites = {{"site_a", {0, 1}, {}}, {"lab_b", {2, 3}, {2, 3}}, {"lab_c", {4}, {4}}};
  down.crew = Crew::make({"lab_b", "lab_c"});
  set_hand_down(down);
  const HandDown read = handed_down();
  EXPECT_EQ(read.listen_fd, 7);
  ASSERT_EQ(read.sites.size(), 3u);
  EXPECT_EQ(read.sites[1].name, "lab_b");
  EXPECT_EQ(read.sites[1].lab_nodes, (std::vector<int>{2, 3}));
  EXPECT_EQ(read.labs(),
            (std::map<std::string, std::vector<int>>{{"lab_b", {2, 3}}, {"lab_c", {4}}}));
  ASSERT_TRUE(read.crew);
  EXPECT_EQ(read.crew->identify(down.crew->operators.at("lab_c"))->lab, "lab_c");
  clear();
}

TEST(HandDown, RefusesAVariableThatDoesNotParseNamingIt) {
  const auto message = [] {
    try {
      handed_down();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  clear();
  ::setenv("RTHS_VIEW_FD", "3x", 1);
  EXPECT_NE(message().find("RTHS_VIEW_FD '3x' is not a file descriptor"), std::string::npos);
  clear();
  ::setenv("RTHS_VIEW_SITES", "[{\"name\": \"a\"}]", 1);
  EXPECT_NE(message().find("RTHS_VIEW_SITES is not a list of {name, nodes, lab_nodes}"),
            std::string::npos);
  clear();
  ::setenv("RTHS_VIEW_CREW", "{", 1);
  EXPECT_NE(message().find("RTHS_VIEW_CREW is not JSON"), std::string::npos);
  clear();
}

}  // namespace
}  // namespace rths::view
