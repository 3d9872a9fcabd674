// A small numeric CSV reader/writer with clear errors.
//
// Reading: a header row of column names, then rows of numbers separated by commas, '.' as the
// decimal point, UTF-8 or ASCII; a UTF-8 byte order mark (Excel's "CSV UTF-8") is skipped.
// Errors name the file, line and column: malformed numbers, NaN/inf where not allowed, missing
// columns, ragged rows, non-monotonic time columns. Files separated by ';' or tabs are refused
// with a message saying commas are expected (';' usually comes with decimal commas, which we do
// not guess at), as are UTF-16 text, binary files, non-regular files (folders, /dev/zero) and
// files above kMaxCsvFileBytes (io/input_file.h).
//
//   CsvReadOptions opts;
//   opts.required_columns = {"time_s", "accel_g"};
//   opts.increasing_column = "time_s";
//   CsvTable t = ReadCsv("daq.csv", opts);
//   const std::vector<double>& time = t.Column("time_s");
#ifndef IMPACTDIC_IO_CSV_H_
#define IMPACTDIC_IO_CSV_H_

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "impactdic/io/atomic_file.h"

namespace impactdic {

struct CsvTable {
  std::string path;                          // Where it was read from (for messages).
  std::vector<std::string> names;            // Column names, in file order.
  std::vector<std::vector<double>> columns;  // columns[c][row].
  // Columns read as text (CsvReadOptions::text_columns), not in `names`.
  std::vector<std::string> text_names;
  std::vector<std::vector<std::string>> text_columns;

  std::size_t rows() const { return columns.empty() ? 0 : columns[0].size(); }
  bool Has(const std::string& name) const;
  // Error kFileFormat naming the file and the missing column (with the available ones).
  const std::vector<double>& Column(const std::string& name) const;
  const std::vector<std::string>& TextColumn(const std::string& name) const;
};

struct CsvReadOptions {
  // Columns that must be present (Error otherwise, listing the columns found).
  std::vector<std::string> required_columns;
  // Whether NaN / inf / empty cells are accepted (read as NaN). Off: an error names the cell.
  bool allow_non_finite = false;
  // If not empty: this column must be strictly increasing (a time axis).
  std::string increasing_column;
  // Columns kept as text (e.g. a scene name); absent ones are ignored.
  std::vector<std::string> text_columns;
  // Lines starting with this character are skipped (before and after the header).
  char comment = '#';
};

CsvTable ReadCsv(const std::string& path, const CsvReadOptions& options = {});

// Writes the columns (all the same length) with a header row, atomically. Numbers are written with
// `precision` significant digits; NaN as "nan".
void WriteCsv(const std::string& path, const std::vector<std::string>& names,
              const std::vector<std::vector<double>>& columns, int precision = 10);

// The header row WriteCsv and WriteCsvRows write for `names` ("a,b,c"), without the newline: an
// existing output whose first line is this was written by the same writer (OutputRules).
std::string CsvHeaderLine(const std::vector<std::string>& names);

// For tables with text cells (e.g. a status column): rows of already-formatted cells.
void WriteCsvRows(const std::string& path, const std::vector<std::string>& names,
                  const std::vector<std::vector<std::string>>& rows);

// WriteCsvRows one row at a time, for tables too long to hold as cells (a row per subset and
// frame): the same bytes, written atomically as they come (io/atomic_file.h AtomicStreamWriter;
// the file appears under `path` only at Commit(), a full disk throws naming `path`).
//
//   CsvRowWriter out("dic.csv", {"frame", "u_px", "status"});
//   const std::array<std::string, 3> row = {"1", "0.25", "converged"};
//   out.Row(row);
//   out.Commit();
class CsvRowWriter {
 public:
  CsvRowWriter(const std::string& path, const std::vector<std::string>& names);
  void Row(std::span<const std::string> cells);
  void Commit() { out_.Commit(); }

 private:
  AtomicStreamWriter out_;
  std::string line_;
};

}  // namespace impactdic

#endif  // IMPACTDIC_IO_CSV_H_
