#pragma once
// A results table: named columns of equal length, each with its unit, plus file-level attributes.
// It is the one in-memory form every rths result takes before it is written (CSV, MATLAB, HDF5)
// or handed to Python, so the variable names and units are the same in every format.
//
// Column names are the CSV header names, the MATLAB / HDF5 variable names and the Python series
// names: they must be valid MATLAB identifiers (a letter, then letters, digits or '_', at most 63
// characters). A unit is an SI symbol ("s", "m", "m/s^2", "N") or "" for a dimensionless column or
// a count. One naming rule for every table, enforced by add_numbers / add_texts:
//   [<case>_]<quantity>[<index>]_<unit>     e.g. lag_shift_14ms_u_floor1_m, time_s, force_act1_N
// the name ends in "_" + unit_suffix(unit) ("m/s^2" -> "m_per_s2", "%" -> "pct"); a column
// without a unit has no suffix (step, alpha, diverged). A missing value
// (a run that stopped early, a link with no exchange at step 0) is NaN; CSV writes it as an empty
// field.

#include <map>
#include <string>
#include <vector>

namespace rths::results {

struct Column {
  std::string name;
  std::string unit;
  bool is_text = false;
  std::vector<double> numbers;     // when !is_text
  std::vector<std::string> texts;  // when is_text
  std::size_t size() const { return is_text ? texts.size() : numbers.size(); }
};

class Table {
 public:
  // Appends a column. Throws std::invalid_argument naming it when the name is not a valid
  // MATLAB identifier, does not end in its unit (the naming rule above), is already taken, or
  // its length differs from the columns before it.
  void add_numbers(const std::string& name, const std::string& unit, std::vector<double> values);
  void add_texts(const std::string& name, const std::string& unit, std::vector<std::string> values);
  // A file-level attribute (HDF5 root attribute, MATLAB field of `attributes`, Python's
  // "attributes"); not in CSV. Text or a number (a double in every format, e.g. dt_s); a key
  // names one attribute of either kind: setting it again replaces it, whatever its kind.
  void set_attribute(const std::string& key, const std::string& value);
  void set_number_attribute(const std::string& key, double value);

  const std::vector<Column>& columns() const { return columns_; }
  const std::map<std::string, std::string>& attributes() const { return attributes_; }
  const std::map<std::string, double>& number_attributes() const { return number_attributes_; }
  std::size_t rows() const { return columns_.empty() ? 0 : columns_.front().size(); }
  // The column called `name`; throws std::out_of_range naming it when there is none.
  const Column& column(const std::string& name) const;

 private:
  void add(Column column);
  std::vector<Column> columns_;
  std::map<std::string, std::string> attributes_;
  std::map<std::string, double> number_attributes_;
};

// A name as a MATLAB identifier: characters outside [A-Za-z0-9_] become '_', a leading digit or
// '_' gets an "x" in front, and the result is cut to 63 characters.
std::string identifier(const std::string& text);
// A unit as the tail of a column name: "m/s^2" -> "m_per_s2", "N/m" -> "N_per_m", "%" -> "pct".
std::string unit_suffix(const std::string& unit);

// True when `name` is already a valid MATLAB identifier.
bool is_identifier(const std::string& name);

// Pads every vector to the longest with NaN (columns of runs that stopped early).
void pad_with_nan(std::vector<std::vector<double>*> columns);

}  // namespace rths::results
