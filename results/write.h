#pragma once
// Writes a Table (results/table.h) as CSV, MATLAB or HDF5, always complete or absent (written to
// "<name>.partial" and renamed, util/atomic_file.h).
//
//   csv  a header line of the column names, then one line per row; numbers with 17 significant
//        digits (round-trip exact), NaN as an empty field, text quoted only when it holds a comma
//        or a quote. Units and attributes are not written (the names carry them where needed).
//   mat  MATLAB 5 (zlib-compressed, readable by MATLAB, Octave and scipy.io.loadmat): one
//        rows x 1 double (or cell of char) variable per column, a struct `units` with one char
//        field per column, and a struct `attributes` when the table has any (a char field per
//        text attribute, a 1 x 1 double per number: scipy.io.loadmat(f, simplify_cells=True)
//        ["attributes"]["dt_s"] is a float).
//   h5   HDF5: one 1-D dataset per column at the root (float64, gzip; text as variable-length
//        UTF-8 strings), each with a string attribute `units`; the root has the table's
//        attributes (text as variable-length UTF-8 strings, numbers as float64 scalars) and
//        `columns`, the column names comma-separated in table order.

#include <cstddef>
#include <filesystem>
#include <string>

#include "results/table.h"

namespace rths::results {

enum class Format { kCsv, kMat, kH5 };

// "csv" | "mat" | "h5"; throws std::invalid_argument naming the text otherwise.
Format parse_format(const std::string& text);
// ".csv" | ".mat" | ".h5"
std::string extension(Format format);

// What a spreadsheet opens (Excel, LibreOffice Calc): 1,048,576 rows, the header one of them, and
// 16,384 columns. CSV is written for spreadsheets; a larger table belongs in h5 or mat.
inline constexpr std::size_t kSpreadsheetRows = 1048576, kSpreadsheetColumns = 16384;
// Throws std::invalid_argument when a CSV table of `rows` data rows and `columns` columns would
// not open in a spreadsheet: "WHAT: a CSV of R rows x C columns is past a spreadsheet's ...".
void require_spreadsheet_size(std::size_t rows, std::size_t columns, const std::string& what);

// Throws std::invalid_argument when the table cannot be expressed in the format (a column named
// `units` or `attributes` in MATLAB), std::runtime_error naming the file when it cannot be written.
void write_table(const Table& table, const std::filesystem::path& path, Format format);

}  // namespace rths::results
