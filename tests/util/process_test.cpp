// The one ChildProcess (start, exit code, kill, timeout, log, environment, prefix), one-shot
// commands, held stop signals, find_program, and ScopedCpuPin (the placement `rths launch` uses
// for lockstep runs).
#include "util/process.h"

#include <gtest/gtest.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <sstream>
#include <thread>

namespace rths::util {
namespace {

std::filesystem::path scratch(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("rths_process_" + name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string read(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool alive(pid_t pid) { return ::kill(pid, 0) == 0; }

TEST(ChildProcessTest, ReportsTheExitCodeAndLogsStdoutAndStderrWithTheEnvironmentOverride) {
  const auto dir = scratch("exit");
  ChildProcess child("/bin/sh", {"-c", "echo out $RTHS_PROCESS_TEST; echo err >&2; exit 3"},
                     dir / "child.log", {"shell", {}, {{"RTHS_PROCESS_TEST", "value-42"}}});
  EXPECT_EQ(child.name(), "shell");
  EXPECT_EQ(child.wait(), 3);
  EXPECT_EQ(child.poll(), 3);  // reaped once, remembered
  EXPECT_FALSE(child.running());
  const std::string log = read(dir / "child.log");
  EXPECT_NE(log.find("out value-42"), std::string::npos) << log;
  EXPECT_NE(log.find("err"), std::string::npos) << log;
  EXPECT_NE(child.log_tail(6).find("err"), std::string::npos);
}

// A log may name runs, hosts and tokens: it is its owner's alone, also one that existed before.
TEST(ChildProcessTest, TheLogIsReadableByItsOwnerAlone) {
  const auto dir = scratch("log_mode");
  std::ofstream(dir / "old.log") << "before";
  std::filesystem::permissions(dir / "old.log", std::filesystem::perms::all);
  for (const char* name : {"new.log", "old.log"}) {
    ChildProcess child("/bin/sh", {"-c", "echo hello"}, dir / name);
    EXPECT_EQ(child.wait(), 0);
    struct stat st {};
    ASSERT_EQ(::stat((dir / name).c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 0777, 0600u) << name;
  }
}

TEST(ChildProcessTest, RunsUnderAPrefixAsANamespaceLauncherWould) {
  const auto dir = scratch("prefix");
  // `env NAME=VALUE program args`: a prefix that, like `ip netns exec NS`, execs the program.
  ChildProcess child("/bin/sh", {"-c", "echo prefixed $PREFIX_SET"}, dir / "child.log",
                     {"", {"env", "PREFIX_SET=yes"}, {}});
  EXPECT_EQ(child.wait(), 0);
  EXPECT_NE(read(dir / "child.log").find("prefixed yes"), std::string::npos);
}

TEST(ChildProcessTest, WaitForTimesOutOnARunningChildAndASignalEndsIt) {
  ChildProcess child("/bin/sleep", {"30"}, "");
  const auto started = std::chrono::steady_clock::now();
  EXPECT_FALSE(child.wait_for(std::chrono::milliseconds(100)).has_value());
  EXPECT_GE(std::chrono::steady_clock::now() - started, std::chrono::milliseconds(100));
  EXPECT_TRUE(child.running());
  child.signal(SIGKILL);
  EXPECT_EQ(child.wait(), 128 + SIGKILL);
}

TEST(ChildProcessTest, TerminateSendsSigtermFirstAndKillsWhatIgnoresIt) {
  ChildProcess polite("/bin/sleep", {"30"}, "");
  EXPECT_EQ(polite.terminate(std::chrono::seconds(2)), 128 + SIGTERM);
  EXPECT_EQ(polite.terminate(), 128 + SIGTERM);  // idempotent
  const auto dir = scratch("stubborn");
  ChildProcess stubborn("/bin/sh", {"-c", "trap '' TERM; echo ready; while :; do sleep 0.05; done"},
                        dir / "stubborn.log");
  while (read(dir / "stubborn.log").find("ready") == std::string::npos)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  const auto started = std::chrono::steady_clock::now();
  EXPECT_EQ(stubborn.terminate(std::chrono::milliseconds(200)), 128 + SIGKILL);
  EXPECT_GE(std::chrono::steady_clock::now() - started, std::chrono::milliseconds(200));
}

TEST(ChildProcessTest, TheDestructorStopsAChildStillRunning) {
  pid_t pid = -1;
  {
    ChildProcess child("/bin/sleep", {"30"}, "");
    pid = child.pid();
    EXPECT_TRUE(alive(pid));
  }
  EXPECT_FALSE(alive(pid));
}

TEST(ChildProcessTest, AMovedChildIsOwnedOnce) {
  std::vector<ChildProcess> children;
  children.emplace_back("/bin/sh", std::vector<std::string>{"-c", "exit 7"}, "");
  children.emplace_back("/bin/sh", std::vector<std::string>{"-c", "exit 8"}, "");
  EXPECT_EQ(children[0].wait(), 7);
  EXPECT_EQ(children[1].wait(), 8);
}

TEST(ChildProcessTest, AMissingProgramOrLogFolderIsAnErrorNamingIt) {
  try {
    ChildProcess child("/nonexistent/rths-nothing", {}, "");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/rths-nothing"), std::string::npos)
        << e.what();
  }
  try {
    ChildProcess child("/bin/true", {}, "/nonexistent/dir/child.log");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/child.log"), std::string::npos)
        << e.what();
  }
}

TEST(RunCommandTest, CapturesOutputAndExitAndStopsAtTheTimeout) {
  const auto result = run_command({"sh", "-c", "echo hello; exit 4"});
  EXPECT_EQ(result.exit_code, 4);
  EXPECT_EQ(result.output, "hello\n");
  EXPECT_THROW(run_checked({"sh", "-c", "exit 1"}), std::runtime_error);
  EXPECT_THROW(run_command({"sleep", "5"}, std::chrono::milliseconds(100)), std::runtime_error);
  EXPECT_EQ(command_line({"ip", "netns", "a b"}), "ip netns 'a b'");
  EXPECT_TRUE(tool_available("sh"));
  EXPECT_FALSE(tool_available("rths-no-such-tool"));
}

TEST(HeldStopSignalsTest, ASignalIsHeldPolledAndConsumed) {
  {
    const HeldStopSignals held;
    EXPECT_FALSE(held.stop_requested());
    ::kill(::getpid(), SIGTERM);  // held pending: the test process lives on
    EXPECT_TRUE(held.stop_requested());
  }
  sigset_t pending;
  sigpending(&pending);
  EXPECT_EQ(sigismember(&pending, SIGTERM), 0);
}

TEST(FindProgramTest, FindsInTheGivenFolderOrItsBuildSubfolderElseNamesWhereItLooked) {
  const auto dir = scratch("find");
  std::filesystem::create_directories(dir / "coordinator");
  std::filesystem::copy_file("/bin/true", dir / "coordinator" / "rths-fake");
  EXPECT_EQ(find_program("rths-fake", "coordinator", dir), dir / "coordinator" / "rths-fake");
  try {
    find_program("rths-missing", "coordinator", dir);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "rths-missing").string()), std::string::npos)
        << e.what();
  }
}

cpu_set_t current_mask() {
  cpu_set_t set;
  CPU_ZERO(&set);
  sched_getaffinity(0, sizeof set, &set);
  return set;
}

int highest_cpu(const cpu_set_t& set) {
  int highest = -1;
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &set)) highest = c;
  return highest;
}

TEST(ScopedCpuPinTest, PinsToTheHighestAllowedCpuAndRestoresTheMask) {
  const cpu_set_t before = current_mask();
  const int highest = highest_cpu(before);
  {
    const ScopedCpuPin pin;
    EXPECT_EQ(pin.cpu(), highest);
    const cpu_set_t pinned = current_mask();
    EXPECT_EQ(CPU_COUNT(&pinned), 1);
    EXPECT_TRUE(CPU_ISSET(highest, &pinned));
    // Threads started while pinned inherit the mask: this is how the children's DDS threads
    // end up on the same CPU.
    int thread_cpus = 0;
    std::thread([&] {
      const cpu_set_t inherited = current_mask();
      thread_cpus = CPU_COUNT(&inherited);
    }).join();
    EXPECT_EQ(thread_cpus, 1);
  }
  const cpu_set_t after = current_mask();
  EXPECT_TRUE(CPU_EQUAL(&before, &after));
}

TEST(ScopedCpuPinTest, RefusesACpuOutsideTheAllowedSetNamingIt) {
  try {
    const ScopedCpuPin pin(CPU_SETSIZE - 1);
    const cpu_set_t allowed = current_mask();
    if (!CPU_ISSET(CPU_SETSIZE - 1, &allowed)) FAIL() << "expected a refusal";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(std::to_string(CPU_SETSIZE - 1)), std::string::npos)
        << e.what();
  }
}

TEST(ScopedCpuExcludeTest, KeepsTheThreadAndItsChildrenOffTheCpuAndRestoresTheMask) {
  const cpu_set_t before = current_mask();
  if (CPU_COUNT(&before) < 2) GTEST_SKIP() << "needs two CPUs";
  const int highest = highest_cpu(before);
  {
    const ScopedCpuExclude exclude(highest);
    EXPECT_TRUE(exclude.active());
    const cpu_set_t during = current_mask();
    EXPECT_FALSE(CPU_ISSET(highest, &during));
    EXPECT_EQ(CPU_COUNT(&during), CPU_COUNT(&before) - 1);
    bool child_on_it = true;
    std::thread([&] {
      const cpu_set_t inherited = current_mask();
      child_on_it = CPU_ISSET(highest, &inherited);
    }).join();
    EXPECT_FALSE(child_on_it);
  }
  const cpu_set_t after = current_mask();
  EXPECT_TRUE(CPU_EQUAL(&before, &after));
  const ScopedCpuExclude not_allowed(CPU_SETSIZE - 1);
  EXPECT_FALSE(not_allowed.active());
}

// isolate_calling_thread_on_cpu(cpu) on a new thread: its error (empty: none) and its mask after.
struct Isolation {
  std::string error;
  cpu_set_t mask;
};
Isolation isolate_on_new_thread(int cpu) {
  Isolation result;
  CPU_ZERO(&result.mask);
  std::thread loop([&] {
    try {
      isolate_calling_thread_on_cpu(cpu);
    } catch (const std::exception& e) {
      result.error = e.what();
    }
    result.mask = current_mask();
  });
  loop.join();
  return result;
}

// The coordinator's pin_loop: the loop thread alone on its CPU, every other thread of the
// process (here: this test's main thread and a bystander) moved off it.
TEST(IsolateCallingThreadOnCpu, PinsTheCallerAndMovesEveryOtherThreadOff) {
  const cpu_set_t before = current_mask();
  if (CPU_COUNT(&before) < 2) GTEST_SKIP() << "needs two CPUs";
  const int highest = highest_cpu(before);
  std::atomic<bool> release{false}, bystander_checked{false};
  bool bystander_on_it = true;
  std::atomic<bool> isolated{false};
  std::thread bystander([&] {
    while (!isolated) std::this_thread::yield();
    const cpu_set_t mine = current_mask();
    bystander_on_it = CPU_ISSET(highest, &mine);
    bystander_checked = true;
    while (!release) std::this_thread::yield();
  });
  const Isolation isolation = isolate_on_new_thread(highest);
  const std::string& error = isolation.error;
  const cpu_set_t loop_mask = isolation.mask;
  isolated = true;
  while (!bystander_checked) std::this_thread::yield();
  release = true;
  bystander.join();
  const cpu_set_t main_mask = current_mask();
  sched_setaffinity(0, sizeof before, &before);  // give this test thread its CPUs back
  ASSERT_EQ(error, "");
  EXPECT_EQ(CPU_COUNT(&loop_mask), 1);
  EXPECT_TRUE(CPU_ISSET(highest, &loop_mask));
  EXPECT_FALSE(bystander_on_it);
  EXPECT_FALSE(CPU_ISSET(highest, &main_mask));
  EXPECT_EQ(CPU_COUNT(&main_mask), CPU_COUNT(&before) - 1);
}

// As rths launch starts the coordinator: every thread off the loop's CPU at first.
TEST(IsolateCallingThreadOnCpu, TakesACpuTheProcessWasStartedOff) {
  const cpu_set_t before = current_mask();
  if (CPU_COUNT(&before) < 2) GTEST_SKIP() << "needs two CPUs";
  const int highest = highest_cpu(before);
  Isolation isolation;
  {
    const ScopedCpuExclude started_off(highest);
    ASSERT_TRUE(started_off.active());
    isolation = isolate_on_new_thread(highest);
  }
  const std::string& error = isolation.error;
  const cpu_set_t loop_mask = isolation.mask;
  sched_setaffinity(0, sizeof before, &before);
  EXPECT_EQ(error, "");
  EXPECT_EQ(CPU_COUNT(&loop_mask), 1);
  EXPECT_TRUE(CPU_ISSET(highest, &loop_mask));
}

TEST(IsolateCallingThreadOnCpu, RefusesACpuTheProcessMayNotUseNamingIt) {
  try {
    isolate_calling_thread_on_cpu(CPU_SETSIZE + 3);
    FAIL() << "expected a refusal";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot isolate CPU " + std::to_string(CPU_SETSIZE + 3)),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace rths::util
