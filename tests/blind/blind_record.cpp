// blind_record: the framing, motion, record and truth.json shared by the blind record writers
// (blind_record.h states the contracts).

#include "blind_record.h"

#include <google/protobuf/text_format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>
#include <stdexcept>

#include "rths/proto/config.pb.h"

namespace blind {

namespace fs = std::filesystem;

namespace {

constexpr double kG = 9.80665;  // m/s^2 per g (AT2 files are in g)

std::array<std::uint32_t, 256> crc_table() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int bit = 0; bit < 8; ++bit) c = (c & 1U) ? (c >> 1) ^ 0x82F63B78U : c >> 1;
    table[i] = c;
  }
  return table;
}

void put_u32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFFU));
}

// The paper's frame as configs/paper_frame.textproto states it, the case run declaring the
// 14 ms shift, lockstep over a substructure node (1) and an actuator emulator (2).
DeclaredStudy paper_frame() {
  const std::string text = R"pb(
    name: "paper_frame"
    structure {
      sdof { period: 0.5 mass: 1000 }
      damping { modal_zeta: 0.05 }
    }
    integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }
    substructuring {
      experimental_fraction: 0.3333333333333333
      model { linear {} }
    }
    cases { name: "reference" }
    cases {
      name: "lag_shift_14ms"
      delay { shift { delay: 0.014 } }
    }
    deployment {
      clock: LOCKSTEP
      case_name: "lag_shift_14ms"
      nodes { id: 1 kind: SUBSTRUCTURE }
      nodes { id: 2 kind: ACTUATOR_EMULATOR }
    }
  )pb";
  return {text, "lag_shift_14ms"};
}

rths::config::Study study_as_run(const RunToRecord& run, const DeclaredStudy& declared) {
  rths::config::Study study;
  if (!google::protobuf::TextFormat::ParseFromString(declared.study_text, &study))
    throw std::runtime_error("the study text does not parse");
  if (study.deployment().case_name() != declared.case_name)
    throw std::runtime_error("the study's deployment runs case \"" +
                             study.deployment().case_name() + "\", the run declares \"" +
                             declared.case_name + "\"");
  study.mutable_integrator()->set_dt(run.dt);
  study.mutable_deployment()->set_run_id(run.run_id);
  auto* m = study.mutable_motion();
  m->set_path(run.motion->path);
  m->set_sha256(run.motion->file_sha256);
  m->set_duration(run.duration);
  return study;
}

std::string quoted(const std::string& s) {
  std::string q = "\"";
  for (char ch : s) {
    if (ch == '"' || ch == '\\') q.push_back('\\');
    q.push_back(ch);
  }
  q.push_back('"');
  return q;
}

}  // namespace

std::uint32_t crc32c(const std::string& bytes) {
  static const std::array<std::uint32_t, 256> table = crc_table();
  std::uint32_t c = 0xFFFFFFFFU;
  for (unsigned char b : bytes) c = table[(c ^ b) & 0xFFU] ^ (c >> 8);
  return c ^ 0xFFFFFFFFU;
}

std::string frame(const std::string& payload) {
  std::string head = "\xF3\x7A\x1C\xB5";
  put_u32(head, static_cast<std::uint32_t>(payload.size()));
  put_u32(head, crc32c(payload));
  put_u32(head, crc32c(head));
  return head + payload;
}
std::string serialise(const rths::runtime::RecordEntry& entry) {
  std::string bytes;
  if (!entry.SerializeToString(&bytes)) throw std::runtime_error("cannot serialise an entry");
  return bytes;
}

Motion read_motion(const fs::path& data_dir, double dt, int steps, const std::string& file) {
  const fs::path path = fs::absolute(data_dir / "ground_motions" / file);
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  std::string line;
  std::vector<double> g;
  double file_dt = 0.0;
  for (int i = 0; i < 4 && std::getline(in, line); ++i) {
    const auto at = line.find("DT=");
    if (at != std::string::npos) file_dt = std::stod(line.substr(at + 3));
  }
  double value = 0.0;
  while (in >> value) g.push_back(value);
  if (file_dt <= 0.0 || g.empty()) throw std::runtime_error("no DT or samples in " + path.string());
  if ((steps - 1) * dt > (static_cast<double>(g.size()) - 1.0) * file_dt)
    throw std::runtime_error(path.string() + " is shorter than the run");
  Motion motion;
  motion.name = path.stem().string();
  motion.path = path.string();
  std::ifstream sums(data_dir / "SHA256SUMS");
  while (std::getline(sums, line)) {
    if (line.size() > 66 && line.find(file) != std::string::npos)
      motion.file_sha256 = line.substr(0, 64);
  }
  if (motion.file_sha256.empty()) throw std::runtime_error("no checksum for " + file);
  for (int k = 0; k < steps; ++k) {
    const double s = k * dt / file_dt;
    const auto i = static_cast<std::size_t>(s);
    const double w = s - static_cast<double>(i);
    const double a = i + 1 < g.size() ? (1.0 - w) * g[i] + w * g[i + 1] : g.back();
    motion.accel.push_back(a * kG);
  }
  return motion;
}

namespace {

// The inputs entry: the study with the motion as run embedded (what a record carries to be
// re-run anywhere).
std::string inputs_bytes_of(const rths::config::Study& study, const Motion& motion, double dt) {
  rths::runtime::RecordEntry inputs_entry;
  rths::config::Study* with_inputs = inputs_entry.mutable_inputs()->mutable_study();
  *with_inputs = study;
  auto* embedded = with_inputs->mutable_motion()->mutable_embedded();
  embedded->set_name(motion.name);
  embedded->set_dt(dt);
  for (double a : motion.accel) embedded->add_acceleration(a);
  embedded->set_source_sha256(motion.file_sha256);
  return serialise(inputs_entry);
}

std::string header_frame_of(const rths::config::Study& study, const RunToRecord& run,
                            const std::string& case_name, std::int64_t start_ns,
                            const std::string& inputs_bytes) {
  rths::runtime::RecordEntry header_entry;
  auto* h = header_entry.mutable_header();
  h->set_schema_version(1);
  h->set_run_id(run.run_id);
  *h->mutable_study() = study;
  h->set_case_name(case_name);
  h->set_clock("lockstep");
  h->set_dt(run.dt);
  h->set_dofs(1);
  h->set_actuators(1);
  h->add_link_node_ids(1);
  h->add_link_node_ids(2);
  h->set_start_realtime_ns(start_ns);
  h->set_timestamp_clock("CLOCK_REALTIME");
  h->set_inputs_crc32c(crc32c(inputs_bytes));
  return frame(serialise(header_entry));
}

// Step k's entry; the link timings (s) drawn from rng through jitter, the step's wall first.
std::string step_frame(const RunToRecord& run, int k, std::int64_t start_ns, std::mt19937_64& rng,
                       std::normal_distribution<double>& jitter) {
  rths::runtime::RecordEntry e;
  auto* s = e.mutable_step();
  const RecordedStep& r = run.steps[static_cast<std::size_t>(k)];
  s->set_step(k);
  s->set_time(k * run.dt);
  s->set_ground_acceleration(run.motion->accel[static_cast<std::size_t>(k)]);
  s->add_displacement(r.u);
  s->add_velocity(r.v);
  s->add_acceleration(r.a);
  s->add_command(r.command);
  s->add_realised(r.realised);
  s->add_measured_force(r.force);
  const double wall = 2.0e-4 + 2.0e-5 * std::abs(jitter(rng));
  for (int node = 1; node <= 2; ++node) {
    auto* l = s->add_links();
    l->set_node_id(node);
    if (k == 0) continue;  // step 0 sends nothing: no answer yet
    const double down = 6.0e-5 + 1.0e-5 * std::abs(jitter(rng));
    const double up = 7.0e-5 + 1.0e-5 * std::abs(jitter(rng));
    l->set_answered_step(k);
    l->set_round_trip(down + up + 2.0e-5);
    l->set_one_way_down(down);
    l->set_one_way_up(up);
    l->set_answers(static_cast<std::uint64_t>(k));
  }
  s->set_step_wall(wall);
  s->set_start_realtime_ns(start_ns + static_cast<std::int64_t>(k) * 250000);
  s->set_command_latency(1.0e-5);
  return frame(serialise(e));
}

std::string footer_frame(int steps) {
  rths::runtime::RecordEntry footer_entry;
  auto* ft = footer_entry.mutable_footer();
  ft->set_ok(true);
  ft->set_status("completed");
  ft->mutable_counters()->set_steps(static_cast<std::uint64_t>(steps - 1));
  ft->set_wall_seconds(steps * 2.5e-4);
  const char* labels[] = {"node 1 (substructure)", "node 2 (actuator emulator)"};
  for (int node = 1; node <= 2; ++node) {
    auto* rej = ft->add_node_rejects();
    rej->set_node_id(node);
    rej->set_label(labels[node - 1]);
    rej->mutable_rejected();
    rej->set_final(true);
  }
  return frame(serialise(footer_entry));
}

}  // namespace

void write_run_record(const fs::path& path, const RunToRecord& run) {
  write_run_record(path, run, paper_frame());
}

void write_run_record(const fs::path& path, const RunToRecord& run, const DeclaredStudy& declared) {
  if (run.motion == nullptr || run.motion->accel.size() < run.steps.size())
    throw std::runtime_error("a run of " + std::to_string(run.steps.size()) +
                             " steps needs as many motion samples");
  const rths::config::Study study = study_as_run(run, declared);
  const std::string inputs_bytes = inputs_bytes_of(study, *run.motion, run.dt);
  const std::int64_t start_ns = 1796205600000000000LL + static_cast<std::int64_t>(run.seed) * 1000;
  const std::string header_frame =
      header_frame_of(study, run, declared.case_name, start_ns, inputs_bytes);

  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write " + path.string());
  out.write("RTHSREC\x02", 8);
  out << header_frame << frame(inputs_bytes);
  std::mt19937_64 rng(run.seed ^ 0x9E3779B97F4A7C15ULL);
  std::normal_distribution<double> jitter(0.0, 1.0);
  const int n = static_cast<int>(run.steps.size());
  for (int k = 0; k < n; ++k) {
    if (k % 1000 == 0) out << header_frame;  // before the first step and every 1000th
    out << step_frame(run, k, start_ns, rng, jitter);
  }
  out << header_frame << footer_frame(n);  // the header again before the footer
  if (!out.flush()) throw std::runtime_error("cannot write " + path.string());
}

namespace {

// Throws std::invalid_argument naming an unknown argument or one without its value.
WriterArgs parse_writer_args(int argc, char** argv) {
  WriterArgs args;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--set")
      args.set = value();
    else if (arg == "--out")
      args.out_dir = value();
    else if (arg == "--data")
      args.data_dir = value();
    else if (arg == "--duration")
      args.duration = std::stod(value());
    else if (arg == "--case")
      args.only = value();
    else
      throw std::invalid_argument("unknown argument " + arg);
  }
  return args;
}

}  // namespace

std::optional<WriterArgs> writer_args(int argc, char** argv, const std::string& program,
                                      const std::vector<std::string>& sets) {
  WriterArgs args;
  try {
    args = parse_writer_args(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << program << ": " << e.what() << "\n";
    return std::nullopt;
  }
  const bool known_set = std::find(sets.begin(), sets.end(), args.set) != sets.end();
  if (known_set && !args.out_dir.empty() && !args.data_dir.empty() && args.duration > 1.0 &&
      args.duration <= 39.0)
    return args;
  std::string names;
  for (const std::string& set : sets) names += (names.empty() ? "" : "|") + set;
  std::cerr << "usage: " << program << " --set " << names
            << " --out DIR --data DATA_DIR [--duration S (1-39, default 15)] [--case NAME]\n";
  return std::nullopt;
}

void write_truth(const fs::path& path, const std::vector<TruthCase>& cases, double duration) {
  std::ofstream out(path);
  out << std::setprecision(10) << "{\n  \"duration_s\": " << duration << ",\n  \"cases\": [\n";
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const TruthCase& c = cases[i];
    out << "    {\"name\": " << quoted(c.name) << ", \"set\": " << quoted(c.set)
        << ", \"seed\": " << c.seed << ", \"record\": " << quoted(c.name + ".rthsrec")
        << ",\n     \"what\": " << quoted(c.what) << ",\n     \"truth\": {\"part\": "
        << (c.part.empty() ? std::string("null") : quoted(c.part)) << ", \"kinds\": [";
    for (std::size_t j = 0; j < c.kinds.size(); ++j) out << (j ? ", " : "") << quoted(c.kinds[j]);
    out << "], \"frequency_hz\": ";
    if (c.frequency_hz > 0.0)
      out << c.frequency_hz;
    else
      out << "null";
    out << ", \"library\": [";
    for (std::size_t j = 0; j < c.library.size(); ++j)
      out << (j ? ", " : "") << "{\"part\": " << quoted(c.library[j].first)
          << ", \"effect\": " << quoted(c.library[j].second) << "}";
    out << "], \"accepted\": [";
    for (std::size_t j = 0; j < c.accepted.size(); ++j)
      out << (j ? ", " : "") << "{\"part\": " << quoted(c.accepted[j].first)
          << ", \"effect\": " << quoted(c.accepted[j].second) << "}";
    out << "]";
    if (c.window_s)
      out << ", \"window_s\": [" << c.window_s->first << ", " << c.window_s->second << "]";
    out << "}}" << (i + 1 < cases.size() ? "," : "") << "\n";
  }
  out << "  ]\n}\n";
  if (!out.flush()) throw std::runtime_error("cannot write " + path.string());
}

void write_set(const WriterArgs& args, const std::vector<std::string>& names,
               const std::function<TruthCase(std::size_t)>& write_case) {
  std::vector<TruthCase> truths;
  fs::create_directories(args.out_dir);
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (!args.only.empty() && names[i] != args.only) continue;
    truths.push_back(write_case(i));
    std::cout << "wrote " << (fs::path(args.out_dir) / (names[i] + ".rthsrec")).string() << ": "
              << truths.back().what << "\n";
  }
  if (truths.empty()) throw std::runtime_error("no case " + args.only + " in set " + args.set);
  write_truth(fs::path(args.out_dir) / "truth.json", truths, args.duration);
}

}  // namespace blind
