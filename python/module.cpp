// The compiled part of the `rths` Python package (rths._rths; python/rths/ adds sdof(), Study
// built in code and __version__ over it): the library, not the CLI, for researchers in Python.
//
//   load_study(path) / parse_study(text, base_dir=".")  -> Study (name, cases, text)
//   run(study, cases=None)      every case in process        -> {"summary", "series", "units",
//                               "benchmark"}: benchmark is benchmark.json's content (J1-J9 of
//                               each case as {name, value, unit, definition}) for a study with a
//                               benchmark section, else None
//   benchmark_criteria()        [{name, unit, definition}] of J1-J9
//   sweep(study, shard="0/1", threads=0, general=False)      -> {"series", "units", "grid_hash",
//                                                                "grid_points", "shard", "trends"
//                                                                (E_rms), "paper_trends" (NRMSE)}
//   stability(period_s, zeta, experimental_fraction=1, dt_s=0.001, integrator=..., ...) -> dict
//   identify(path, channels=..., ...)                         -> {"report", "series", "units"}
//   read_record(path, allow_loss=False)  a run record (.rthsrec) -> {"series", "units",
//                               "attributes", "truncated", "warning", "checksummed", "losses"}
//                               Every entry's checksum is verified (runtime::read_record, as
//                               `rths export`); a record that lost entries raises rths.Error
//                               naming the lost steps, unless allow_loss=True, which returns the
//                               intact entries and "losses" (one description per damaged
//                               region); attributes (study, dt_s, the motion, status, ok,
//                               integrity, lost_steps, ...) as results/results.h.
//
// "series" maps a name with its unit (time_s, u_floor1_m, force_act1_N, node2_round_trip_s)
// to a 1-D NumPy float64 array (text columns: a list of str); the names and units are those of
// results/results.h, the same the CSV, MATLAB and HDF5 files carry (one naming rule,
// results/table.h). "units" maps the same names to the unit.
// Summaries are plain dicts with the keys of the CLI's --json output.
//
// Errors: bad input (a malformed config, an unknown effect, a truncated data file) raises
// rths.BadInputError (a ValueError), anything else rths.Error (a RuntimeError); the message is
// the one the CLI prints after "rths: ". Long work (run, sweep, identify, read_record) releases
// the GIL, so other Python threads run meanwhile.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <google/protobuf/text_format.h>
#include <nlohmann/json.hpp>

#include <optional>

#include "analysis/benchmark/benchmark_evaluation.h"
#include "analysis/study_run/study_run.h"
#include "analysis/sweep/sweep_grid.h"
#include "analysis/sweep/sweep_report.h"
#include "analysis/sweep/sweep_run.h"
#include "analysis/tables/result_tables.h"
#include "core/benchmark_criteria.h"
#include "core/stability.h"
#include "identify/fit/identify.h"
#include "identify/fit/request.h"
#include "identify/lab/report.h"
#include "identify/model/data.h"
#include "results/results.h"
#include "runtime/record/record.h"
#include "study/ranges.h"
#include "study/study.h"

namespace py = pybind11;

namespace rths::python {
namespace {

// A study config and the folder its relative paths (motions) are resolved against.
struct Study {
  config::Study config;
  std::filesystem::path base_dir;
  std::string source;

  std::vector<std::string> case_names() const {
    std::vector<std::string> out;
    for (const auto& c : config.cases()) out.push_back(c.name());
    return out;
  }
  std::string text() const {
    std::string out;
    google::protobuf::TextFormat::PrintToString(config, &out);
    return out;
  }
};

py::object to_python(const nlohmann::json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::null: return py::none();
    case nlohmann::json::value_t::boolean: return py::bool_(j.get<bool>());
    case nlohmann::json::value_t::number_integer: return py::int_(j.get<std::int64_t>());
    case nlohmann::json::value_t::number_unsigned: return py::int_(j.get<std::uint64_t>());
    case nlohmann::json::value_t::number_float: return py::float_(j.get<double>());
    case nlohmann::json::value_t::string: return py::str(j.get<std::string>());
    case nlohmann::json::value_t::array: {
      py::list list;
      for (const auto& item : j) list.append(to_python(item));
      return list;
    }
    case nlohmann::json::value_t::object: {
      py::dict dict;
      for (const auto& [key, value] : j.items()) dict[py::str(key)] = to_python(value);
      return dict;
    }
    default: return py::none();
  }
}

// {"series": {name_unit: array}, "units": {name_unit: unit}} of a table (needs the GIL).
py::dict table_dict(const results::Table& table) {
  py::dict series, units;
  for (const results::Column& c : table.columns()) {
    const py::str name(c.name);  // already ends in its unit (results/table.h)
    if (c.is_text) {
      series[name] = py::cast(c.texts);
    } else {
      series[name] =
          py::array_t<double>(static_cast<py::ssize_t>(c.numbers.size()), c.numbers.data());
    }
    units[name] = c.unit;
  }
  py::dict out;
  out["series"] = series;
  out["units"] = units;
  return out;
}

// A table's attributes, text as str and numbers (dt_s, ok) as float (needs the GIL).
py::dict attributes_dict(const results::Table& table) {
  py::dict out;
  for (const auto& [key, text] : table.attributes()) out[py::str(key)] = text;
  for (const auto& [key, number] : table.number_attributes()) out[py::str(key)] = number;
  return out;
}

Study load_study(const std::filesystem::path& path) {
  return {study::load_study(path), path.parent_path(), path.string()};
}

Study parse_study(const std::string& text, const std::filesystem::path& base_dir,
                  const std::string& source) {
  return {study::parse_study(text, source), base_dir, source};
}

py::dict run(const Study& study, const std::optional<std::vector<std::string>>& cases) {
  config::Study chosen = study.config;
  if (cases) {
    const std::string reference = chosen.reference_case().empty() && chosen.cases_size() > 0
                                      ? chosen.cases(0).name()
                                      : chosen.reference_case();
    chosen.clear_cases();
    for (const auto& c : study.config.cases()) {
      const bool wanted = std::find(cases->begin(), cases->end(), c.name()) != cases->end();
      if (wanted || c.name() == reference) *chosen.add_cases() = c;
    }
    for (const auto& name : *cases) {
      const auto names = study.case_names();
      if (std::find(names.begin(), names.end(), name) == names.end()) {
        throw std::invalid_argument(study.source + ": no case '" + name + "'");
      }
    }
  }
  analysis::StudyOutcome outcome;
  results::Table table;
  std::optional<analysis::BenchmarkEvaluation> benchmark;
  {
    py::gil_scoped_release release;
    const study::PreparedStudy prepared = study::prepare_study(chosen, study.base_dir);
    outcome = analysis::run_study(prepared);
    table = analysis::study_table(outcome);
    benchmark = analysis::evaluate_benchmark(prepared, outcome);
  }
  py::dict out = table_dict(table);
  out["summary"] = to_python(analysis::study_summary_json(outcome));
  // As `rths run` writes benchmark.json: each criterion {name, value, unit, definition}.
  out["benchmark"] =
      benchmark ? to_python(analysis::benchmark_json(*benchmark)) : py::object(py::none());
  out["attributes"] = attributes_dict(table);
  return out;
}

py::dict sweep(const Study& study, const std::string& shard, int threads, bool general) {
  analysis::SweepOptions options;
  options.shard = analysis::parse_shard(shard);
  options.threads = threads;
  options.general_path_only = general;
  results::Table table;
  nlohmann::json trends;
  std::string hash;
  std::size_t points = 0;
  {
    py::gil_scoped_release release;
    const analysis::SweepGrid grid(study.config, study.base_dir, study.source);
    const auto rows = analysis::to_table(grid, analysis::run_sweep(grid, options));
    trends = analysis::sweep_trends_json(rows);
    hash = grid.hash_hex();
    points = grid.size();
    table = analysis::sweep_table(rows, hash, points);
  }
  py::dict out = table_dict(table);
  out["grid_hash"] = hash;
  out["grid_points"] = points;
  out["shard"] = options.shard.to_string();
  out["trends"] = to_python(trends["trends"]);
  out["paper_trends"] = to_python(trends["paper_trends"]);
  out["attributes"] = attributes_dict(table);
  return out;
}

py::dict stability(double period, double zeta, double alpha, double dt,
                   const std::string& integrator, int branches, int max_steps) {
  // The same range rules as `rths stability`'s flags (study/ranges.h), named as the arguments.
  study::check_range(study::Quantity::kPeriod, period, "period_s");
  study::check_range(study::Quantity::kDampingRatio, zeta, "zeta");
  study::check_range(study::Quantity::kFraction, alpha, "experimental_fraction");
  study::check_range(study::Quantity::kStep, dt, "dt_s");
  study::check_range(study::Quantity::kCount, static_cast<long long>(branches), "branches");
  study::check_range(study::Quantity::kCount, static_cast<long long>(max_steps), "max_steps");
  const auto kind = core::integrator_from_string(integrator);
  const core::ContinuousStability continuous =
      core::continuous_critical_delay(period, zeta, alpha, branches);
  const core::DiscreteStability discrete =
      core::discrete_critical_delay(kind, period, zeta, alpha, dt, max_steps);
  py::list crossings;
  for (const auto& c : continuous.crossings) {
    py::dict d;
    d["crossing_omega_rad_per_s"] = c.omega;
    d["delay_s"] = c.delay;
    d["branch"] = c.branch;
    crossings.append(d);
  }
  py::dict cont, disc, input, out;
  input["period_s"] = period;
  input["zeta"] = zeta;
  input["experimental_fraction"] = alpha;
  input["integrator"] = core::to_string(kind);
  input["dt_s"] = dt;
  cont["stable_without_delay"] = continuous.stable_without_delay;
  cont["stable_for_all_delays"] = continuous.stable_for_all_delays;
  cont["critical_delay_s"] = continuous.critical_delay
                                 ? py::object(py::float_(*continuous.critical_delay))
                                 : py::object(py::none());
  cont["crossings"] = crossings;
  disc["first_unstable_delay_steps"] = discrete.first_unstable_steps
                                           ? py::object(py::int_(*discrete.first_unstable_steps))
                                           : py::object(py::none());
  disc["first_unstable_delay_s"] = discrete.first_unstable_delay
                                       ? py::object(py::float_(*discrete.first_unstable_delay))
                                       : py::object(py::none());
  disc["searched_up_to_steps"] = max_steps;
  disc["spectral_radius_at_first_unstable"] =
      discrete.spectral_radius.empty() ? py::object(py::none())
                                       : py::object(py::float_(discrete.spectral_radius.back()));
  out["input"] = input;
  out["continuous"] = cont;
  out["discrete"] = disc;
  return out;
}

py::dict identify_record(const std::filesystem::path& path,
                         const std::vector<std::string>& channels,
                         const std::vector<std::string>& declared_actuator,
                         const std::vector<std::string>& declared_specimen,
                         const std::optional<std::vector<std::string>>& candidates, double holdout,
                         const std::string& holdout_mode, std::size_t max_steps,
                         const std::string& length_unit, const std::string& force_unit,
                         const std::string& time_unit, const std::string& column_map) {
  identify::IdentifyRequest request;
  request.channels = channels;
  request.declared_actuator = declared_actuator;
  request.declared_specimen = declared_specimen;
  if (candidates) request.candidates = *candidates;
  request.holdout = holdout;
  request.holdout_mode = holdout_mode;
  request.max_steps = max_steps;
  const identify::IdentifyOptions options =
      identify::identify_options(request, [](const std::string& field) { return field; });
  identify::CsvUnits units;
  units.time_to_s = identify::time_unit_to_s(time_unit);
  units.length_to_m = identify::length_unit_to_m(length_unit);
  units.force_to_n = identify::force_unit_to_n(force_unit);
  const identify::DaqColumnMap map = identify::parse_column_map(column_map);
  nlohmann::json report;
  results::Table table;
  {
    py::gil_scoped_release release;
    const identify::Identification id =
        identify::identify(identify::read_measured(path, units, map, identify::kDefaultMinSamples,
                                                   0.0, identify::force_column(options.channels)),
                           options);
    report = identify::to_json(id, identify::ReportContext{holdout, options.holdout_mode});
    table = results::identify_table(id);
  }
  py::dict out = table_dict(table);
  out["report"] = to_python(report);
  return out;
}

py::dict read_record(const std::filesystem::path& path, bool allow_loss) {
  runtime::RecordContents contents;
  results::Table table;
  {
    py::gil_scoped_release release;
    try {
      contents = runtime::read_record(path);
    } catch (const std::runtime_error& e) {
      throw std::invalid_argument(
          e.what());  // a missing file or no record is bad input, as in the CLI
    }
    if (contents.lost_entries() && !allow_loss)
      throw std::runtime_error("the record lost entries: " + contents.loss_report() +
                               " (read_record(path, allow_loss=True) returns the intact ones)");
    table = results::record_table(contents);
  }
  py::dict out = table_dict(table);
  out["attributes"] = attributes_dict(table);
  out["truncated"] = contents.truncated;
  out["warning"] = contents.warning;
  out["checksummed"] = contents.checksummed;
  py::list losses;
  for (const runtime::RecordLoss& loss : contents.losses) losses.append(loss.describe());
  out["losses"] = losses;
  return out;
}

// rths.Error (a RuntimeError) and rths.BadInputError (a ValueError): std::invalid_argument is bad
// input, any other std::exception an error; Python's own exceptions pass through.
void add_errors(py::module_& m) {
  static py::exception<std::runtime_error> error(m, "Error", PyExc_RuntimeError);
  static py::exception<std::invalid_argument> bad_input(m, "BadInputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const std::invalid_argument& e) {
      bad_input(e.what());
    } catch (const py::error_already_set&) {
      throw;
    } catch (const py::builtin_exception&) {
      throw;
    } catch (const std::exception& e) {
      error(e.what());
    }
  });
}

void add_study_functions(py::module_& m) {
  py::class_<Study>(m, "Study",
                    "A study config and the folder its relative paths are resolved against")
      .def_property_readonly("name", [](const Study& s) { return s.config.name(); })
      .def_property_readonly("cases", &Study::case_names,
                             "case names, the reference first unless reference_case is set")
      .def_property_readonly("base_dir", [](const Study& s) { return s.base_dir; })
      .def_property_readonly("text", &Study::text, "the config in Protobuf text format")
      .def("__repr__", [](const Study& s) {
        return "<rths.LoadedStudy '" + s.config.name() + "' from " + s.source + ">";
      });

  m.def("load_study", &load_study, py::arg("path"),
        "Read a study config file (Protobuf text format)");
  m.def("parse_study", &parse_study, py::arg("text"),
        py::arg("base_dir") = std::filesystem::path("."), py::arg("source") = "<text>",
        "A study config from text; relative paths resolve against base_dir");
  m.def(
      "run", &run, py::arg("study"), py::arg("cases") = std::nullopt,
      "Run every case of a study (or the named cases and the reference) in process, as `rths run`");
  m.def(
      "benchmark_criteria",
      [] {
        py::list out;
        for (const rths::core::CriterionDefinition& d : rths::core::criterion_definitions()) {
          py::dict entry;
          entry["name"] = d.name;
          entry["unit"] = d.unit;
          entry["definition"] = d.definition;
          out.append(entry);
        }
        return out;
      },
      "The RTHS benchmark's criteria J1-J9: [{name, unit, definition}]");
}

void add_analysis_functions(py::module_& m) {
  m.def("sweep", &sweep, py::arg("study"), py::arg("shard") = "0/1", py::arg("threads") = 0,
        py::arg("general") = false, "The study's sweep grid (the paper's Fig. 4), as `rths sweep`");
  m.def("stability", &stability, py::arg("period_s"), py::arg("zeta"),
        py::arg("experimental_fraction") = 1.0, py::arg("dt_s") = 0.001,
        py::arg("integrator") = "explicit-newmark", py::arg("branches") = 3,
        py::arg("max_steps") = 200,
        "Continuous and discrete critical delay, as `rths stability --json`");
  m.def(
      "identify", &identify_record, py::arg("path"),
      py::arg("channels") = std::vector<std::string>{"measured", "force"},
      py::arg("declared_actuator") = std::vector<std::string>{"delay"},
      py::arg("declared_specimen") = std::vector<std::string>{"stiffness"},
      py::arg("candidates") = std::nullopt, py::arg("holdout") = 0.3,
      py::arg("holdout_mode") = "blocks", py::arg("max_steps") = 6, py::arg("length_unit") = "mm",
      py::arg("force_unit") = "N", py::arg("time_unit") = "s", py::arg("column_map") = "",
      "Identify the effects the declared models lack in measured data, as `rths identify --json`");
  m.def("read_record", &read_record, py::arg("path"), py::arg("allow_loss") = false,
        "A run record (.rthsrec), also a truncated one; checksums verified, a damaged record "
        "raises unless allow_loss=True (then its intact entries and 'losses')");
}

}  // namespace
}  // namespace rths::python

PYBIND11_MODULE(_rths, m) {
  using namespace rths::python;
  m.doc() =
      "rths: real-time hybrid simulation with actuator and network lag (the C++ library from "
      "Python)";
  add_errors(m);
  add_study_functions(m);
  add_analysis_functions(m);
}
