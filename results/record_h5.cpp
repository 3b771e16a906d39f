#include "results/record_h5.h"

#include <deque>
#include <stdexcept>
#include <utility>

#include "results/column_names.h"
#include "results/h5_handle.h"

namespace rths::results {

namespace {

struct ColumnSpec {
  std::string name, unit;
};

// The record_table step columns of a record with this header (record_h5.h, Output).
std::vector<ColumnSpec> step_columns(const runtime::RunHeader& header) {
  std::vector<ColumnSpec> out{
      {"step", ""}, {"time_s", "s"}, {"ground_acceleration_m_per_s2", "m/s^2"}};
  const std::vector<int> dofs = runtime::recorded_dofs(header);
  for (const auto& [name, unit] :
       {std::pair{&displacement_column, "m"}, std::pair{&velocity_column, "m/s"},
        std::pair{&acceleration_column, "m/s^2"}})
    for (const int dof : dofs) out.push_back({name(static_cast<std::size_t>(dof) + 1), unit});
  for (const auto& [name, unit] : {std::pair{&command_column, "m"},
                                   std::pair{&measured_column, "m"}, std::pair{&force_column, "N"}})
    for (int a = 1; a <= header.actuators(); ++a)
      out.push_back({name(static_cast<std::size_t>(a)), unit});
  out.push_back({"lateness_s", "s"});
  out.push_back({"overrun", ""});
  return out;
}

// Appends `values` (at most `count`, zero past what the step carries) to `row`.
template <class Values>
void add_values(const Values& values, int count, std::vector<double>& row) {
  for (int i = 0; i < count; ++i) row.push_back(i < values.size() ? values.Get(i) : 0.0);
}

}  // namespace

// The open file: its datasets in column order, and the string type of its text attributes.
struct RecordH5Writer::File {
  explicit File(const std::filesystem::path& path)
      : file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose),
        text(H5Tcopy(H5T_C_S1), H5Tclose) {}
  H5Handle file, text;
  std::deque<H5Handle> datasets;

  bool text_attribute(hid_t owner, const char* key, const std::string& value) {
    H5Handle scalar(H5Screate(H5S_SCALAR), H5Sclose);
    H5Handle attr(H5Acreate2(owner, key, text.get(), scalar.get(), H5P_DEFAULT, H5P_DEFAULT),
                  H5Aclose);
    const char* chars = value.c_str();
    return attr.ok() && H5Awrite(attr.get(), text.get(), &chars) >= 0;
  }
  bool set_complete(double value) {
    const bool exists = H5Aexists(file.get(), "complete") > 0;
    H5Handle scalar(H5Screate(H5S_SCALAR), H5Sclose);
    H5Handle attr(exists ? H5Aopen(file.get(), "complete", H5P_DEFAULT)
                         : H5Acreate2(file.get(), "complete", H5T_IEEE_F64LE, scalar.get(),
                                      H5P_DEFAULT, H5P_DEFAULT),
                  H5Aclose);
    return attr.ok() && H5Awrite(attr.get(), H5T_NATIVE_DOUBLE, &value) >= 0;
  }
  // An empty extendible float64 dataset chunked by `block` rows, gzip level 4.
  bool add_dataset(const ColumnSpec& c, hsize_t block) {
    const hsize_t none = 0, unlimited = H5S_UNLIMITED;
    H5Handle space(H5Screate_simple(1, &none, &unlimited), H5Sclose);
    H5Handle properties(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    if (!space.ok() || !properties.ok() || H5Pset_chunk(properties.get(), 1, &block) < 0 ||
        H5Pset_deflate(properties.get(), 4) < 0)
      return false;
    const H5Handle& d =
        datasets.emplace_back(H5Dcreate2(file.get(), c.name.c_str(), H5T_IEEE_F64LE, space.get(),
                                         H5P_DEFAULT, properties.get(), H5P_DEFAULT),
                              H5Dclose);
    return d.ok() && text_attribute(d.get(), "units", c.unit);
  }
  // Rows [from, from + count) of dataset `d` <- values.
  static bool append(hid_t d, hsize_t from, hsize_t count, const double* values) {
    const hsize_t size = from + count;
    if (H5Dset_extent(d, &size) < 0) return false;
    H5Handle target(H5Dget_space(d), H5Sclose);
    H5Handle source(H5Screate_simple(1, &count, nullptr), H5Sclose);
    return target.ok() && source.ok() &&
           H5Sselect_hyperslab(target.get(), H5S_SELECT_SET, &from, nullptr, &count, nullptr) >=
               0 &&
           H5Dwrite(d, H5T_NATIVE_DOUBLE, source.get(), target.get(), H5P_DEFAULT, values) >= 0;
  }
};

RecordH5Writer::RecordH5Writer(std::filesystem::path path, std::size_t block)
    : path_(std::move(path)), block_(block > 0 ? block : 1) {}

RecordH5Writer::~RecordH5Writer() { close(); }

void RecordH5Writer::fail(const std::string& what) {
  if (failure_.empty()) failure_ = "HDF5 file " + path_.string() + ": " + what;
  file_.reset();
}

void RecordH5Writer::open(const runtime::RunHeader& header) {
  // Errors are reported by failure(), not by HDF5's stack dump on stderr.
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  file_ = std::make_unique<File>(path_);
  if (!file_->file.ok() || !file_->text.ok() || H5Tset_size(file_->text.get(), H5T_VARIABLE) < 0)
    return fail("cannot create the file");
  const std::vector<ColumnSpec> columns = step_columns(header);
  std::string names;
  for (const ColumnSpec& c : columns) {
    if (!file_->add_dataset(c, block_)) return fail("cannot create dataset " + c.name);
    names += (names.empty() ? "" : ",") + c.name;
  }
  if (!file_->text_attribute(file_->file.get(), "columns", names) || !file_->set_complete(0.0))
    return fail("cannot write the root attributes");
  dofs_ = runtime::recorded_columns(header);
  actuators_ = header.actuators();
  held_.assign(columns.size(), {});
  for (std::vector<double>& column : held_) column.reserve(block_);
}

void RecordH5Writer::append(const runtime::StepRecord& s) {
  std::vector<double> row{static_cast<double>(s.step()), s.time(), s.ground_acceleration()};
  add_values(s.displacement(), dofs_, row);
  add_values(s.velocity(), dofs_, row);
  add_values(s.acceleration(), dofs_, row);
  add_values(s.command(), actuators_, row);
  add_values(s.realised(), actuators_, row);
  add_values(s.measured_force(), actuators_, row);
  row.push_back(s.lateness());
  row.push_back(s.overrun() ? 1.0 : 0.0);
  for (std::size_t c = 0; c < held_.size(); ++c) held_[c].push_back(row[c]);
  if (++held_rows_ == block_) write_block();
}

void RecordH5Writer::write_block() {
  if (!file_ || held_rows_ == 0) return;
  for (std::size_t c = 0; c < held_.size(); ++c) {
    if (!File::append(file_->datasets[c].get(), rows_written_, held_rows_, held_[c].data()))
      return fail("cannot append to dataset " + std::to_string(c));
    held_[c].clear();
  }
  rows_written_ += held_rows_;
  held_rows_ = 0;
  if (H5Fflush(file_->file.get(), H5F_SCOPE_GLOBAL) < 0) fail("cannot flush");
}

void RecordH5Writer::on_entry(std::string_view frame) {
  if (closed_ || !failure_.empty()) return;
  runtime::RecordEntry entry;
  if (frame.size() < runtime::kRecordFrameHeaderBytes ||
      !entry.ParseFromArray(frame.data() + runtime::kRecordFrameHeaderBytes,
                            static_cast<int>(frame.size() - runtime::kRecordFrameHeaderBytes)))
    return fail("an entry of the record does not parse");
  if (entry.has_header() && !file_) open(entry.header());
  if (entry.has_step() && file_) append(entry.step());
  footer_ = footer_ || entry.has_footer();
}

void RecordH5Writer::close() {
  if (closed_) return;
  closed_ = true;
  write_block();
  if (file_ && footer_ && !file_->set_complete(1.0)) fail("cannot mark the file complete");
  if (file_ && H5Fflush(file_->file.get(), H5F_SCOPE_GLOBAL) < 0) fail("cannot flush");
  file_.reset();
}

}  // namespace rths::results
