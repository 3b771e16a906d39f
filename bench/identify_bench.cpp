// `rths identify`, timed per record: the wall time of the command as a user runs it (both
// channels, default options, no --trim-idle, the 5-fold validation included), the load average
// beside it (the machine is shared), and what the identification reached: per channel the final
// held-out error and the k-fold mean, from its JSON.
//
//   identify_bench [--repeat N] [--rths PATH] [--keep DIR] [RECORD ...]
// A RECORD may be a run's record (*.rthsrec): its row then gives its steps, the undeclared effects
// over every part and the re-run's worst floor NRMSE, declared -> identified.
// Default records: data/measured/mts_mrdamper_chirp_0A.txt and a one-minute record at
// 1 kHz of the same rig made by identify::generate_measured (a 15 Hz sinusoidal test with the MR
// damper energised: 4.6 ms delay and a 21.8 ms first-order lag, Bouc-Wen + viscous + friction
// force, drifting delay, gain and stiffness, play, offsets, inertia, sensor noise), and a
// one-minute run record of the paper frame made by `rths launch` (lockstep on loopback DDS, an
// emulator with a lag and a velocity limit; one_minute_run_record). Each record is run N times
// (default 1); the median time is printed.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "identify/lab/generator.h"
#include "identify/model/data.h"
#include "study/study.h"

namespace {

namespace fs = std::filesystem;
using namespace rths;

struct Run {
  double seconds = 0.0;
  int exit_code = -1;
  std::string output;
};

Run run_identify(const std::string& rths, const fs::path& record) {
  const std::string line = rths + " identify '" + record.string() + "' --json 2>/dev/null";
  const auto start = std::chrono::steady_clock::now();
  Run run;
  FILE* pipe = popen(line.c_str(), "r");
  if (pipe == nullptr) return run;
  std::array<char, 4096> buffer{};
  std::size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
    run.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

// The one-minute 15 Hz record of the MTS rig with the damper energised, as a CSV (s, mm, mm, N).
fs::path one_minute_record(const fs::path& dir) {
  identify::GeneratorSpec spec;
  spec.duration = 60.0;
  spec.dt = 0.001;
  spec.amplitude = 0.004;
  spec.chirp_start = spec.chirp_end = 15.0;  // a sine
  spec.delay = 0.0046;
  spec.first_order_time_constant = 0.0218;
  spec.stiffness = 2.0e4;
  spec.bouc_wen_yield = 5.0e-4;
  spec.bouc_wen_alpha = 0.2;
  spec.damping = 2.0e3;
  spec.coulomb_force = 300.0;
  spec.coulomb_velocity = 0.01;
  // What makes the real 15 Hz record slow to identify: drifts, play, offsets, a drifting
  // stiffness and inertia give the search many paying rounds and long fits.
  spec.delay_drift = 0.002;
  spec.gain_drift = 0.03;
  spec.backlash_width = 5.0e-5;
  spec.offset = 1.0e-5;
  spec.drift = 2.0e-5;
  spec.stiffness_drift = 0.1;
  spec.mass = 5.0;
  spec.force_offset = 20.0;
  spec.displacement_noise = 1.0e-5;
  spec.force_noise = 15.0;
  const fs::path path = dir / "mts_like_15hz_one_minute.csv";
  identify::write_csv(identify::generate_measured(spec), path);
  return path;
}

// A one-minute run record of the paper frame (a run's record, *.rthsrec): the 1979 Imperial
// Valley record played twice (78 s, cut to 60), 1 kHz, lockstep over DDS on loopback through
// `rths launch`, case lag_shift_14ms with the emulator adding a 8 ms first-order lag and a
// 0.1 m/s velocity limit of its own. Empty when the launch fails (it says why on stderr).
fs::path one_minute_run_record(const std::string& rths, const fs::path& dir) {
  const fs::path motion_source =
      fs::path(RTHS_DATA_DIR) / "ground_motions/RSN175_IMPVALL.H_H-E12140.AT2";
  const study::PreparedStudy played = study::prepare_study(
      study::parse_study("motion { path: \"" + motion_source.string() +
                             "\" }\nintegrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
                             "structure { sdof { period: 0.5 mass: 1000 } }\n",
                         "identify_bench"),
      dir);
  const fs::path motion = dir / "impvall_twice.txt";
  {
    std::ofstream out(motion);
    out.precision(17);
    for (int twice = 0; twice < 2; ++twice)
      for (double a : played.motion.acceleration) out << a << "\n";
  }
  const fs::path study = dir / "paper_frame_one_minute.textproto";
  std::ofstream(study)
      << "name: \"paper_frame_one_minute\"\n"
         "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }\n"
         "motion { path: \""
      << motion.string()
      << "\" format: COLUMNS column_dt: 0.001 column_units: M_PER_S2 duration: 60 }\n"
         "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
         "substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }\n"
         "cases { name: \"lag_shift_14ms\" delay { shift { delay: 0.014 } } }\n"
         "deployment { domain_id: 86 nodes { id: 1 kind: ACTUATOR_EMULATOR receive_delay { "
         "first_order { time_constant: 0.008 } } receive_delay { velocity_limit { max_velocity: "
         "0.1 } } } }\n";
  const fs::path out = dir / "one_minute_launch";
  const std::string line =
      rths + " launch '" + study.string() + "' --no-plots --out '" + out.string() + "' >/dev/null";
  if (std::system(line.c_str()) != 0) {
    std::cerr << "identify_bench: `" << line << "` failed; no one-minute run record\n";
    return {};
  }
  for (const auto& entry : fs::recursive_directory_iterator(out))
    if (entry.path().extension() == ".rthsrec") return entry.path();
  return {};
}

void print_row(const fs::path& record, const std::vector<Run>& runs) {
  std::vector<double> seconds;
  for (const auto& r : runs) seconds.push_back(r.seconds);
  std::sort(seconds.begin(), seconds.end());
  const Run& last = runs.back();
  std::cout << record.filename().string() << ": exit " << last.exit_code << ", median "
            << seconds[seconds.size() / 2] << " s over " << runs.size() << " run(s) (min "
            << seconds.front() << ", max " << seconds.back() << ")";
  try {
    const auto json = nlohmann::json::parse(last.output.substr(last.output.find('{')));
    if (json.contains("undeclared")) {  // a run's record (*.rthsrec)
      std::cout << "; " << json.at("steps").get<std::size_t>() << " steps, "
                << json.at("undeclared").size() << " undeclared effect(s)";
      if (json.contains("residual"))
        std::cout << ", worst floor NRMSE "
                  << 100.0 * json.at("residual").at("declared_nrmse").get<double>() << " % -> "
                  << 100.0 * json.at("residual").at("identified_nrmse").get<double>() << " %";
      std::cout << "  [load " << load_average() << "]\n";
      return;
    }
    for (const auto& c : json.at("channels")) {
      std::cout << "; " << c.at("channel").get<std::string>() << " held-out "
                << 100.0 * c.at("final").at("heldout_error").get<double>() << " %";
    }
    for (const auto& v : json.at("validation")) {
      if (v.contains("kfold")) {
        std::cout << ", " << v.at("channel").get<std::string>() << " 5-fold "
                  << 100.0 * v.at("kfold").at("mean").get<double>() << " %";
      }
    }
  } catch (const std::exception& e) {
    std::cout << "; no JSON report (" << e.what() << ")";
  }
  std::cout << "  [load " << load_average() << "]\n";
}

}  // namespace

int main(int argc, char** argv) {
  std::string rths = RTHS_EXECUTABLE;
  std::size_t repeat = 1;
  fs::path keep;
  std::vector<fs::path> records;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--repeat" && i + 1 < argc)
      repeat = std::max(1, std::stoi(argv[++i]));
    else if (arg == "--rths" && i + 1 < argc)
      rths = argv[++i];
    else if (arg == "--keep" && i + 1 < argc)
      keep = argv[++i];
    else if (!arg.empty() && arg[0] == '-') {
      std::cerr << "usage: identify_bench [--repeat N] [--rths PATH] [--keep DIR] [RECORD ...]\n";
      return 2;
    } else {
      records.emplace_back(arg);
    }
  }
  if (records.empty()) {
    const fs::path dir = keep.empty() ? fs::temp_directory_path() / "rths_identify_bench" : keep;
    fs::create_directories(dir);
    records.push_back(fs::path(RTHS_DATA_DIR) / "measured/mts_mrdamper_chirp_0A.txt");
    records.push_back(one_minute_record(dir));
    if (const fs::path run = one_minute_run_record(rths, dir); !run.empty()) records.push_back(run);
  }
  std::cout << "rths identify RECORD --json (both channels, defaults), " << rths
            << "; the time includes the 5-fold validation\n";
  for (const auto& record : records) {
    std::vector<Run> runs;
    for (std::size_t r = 0; r < repeat; ++r) runs.push_back(run_identify(rths, record));
    print_row(record, runs);
  }
  return 0;
}
