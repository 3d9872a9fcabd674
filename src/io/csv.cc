#include "impactdic/io/csv.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <system_error>

#include "impactdic/core/error.h"
#include "impactdic/core/strings.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/input_file.h"

namespace impactdic {
namespace {

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\"");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r\"");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> SplitCells(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) cells.push_back(Trim(cell));
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

// Parses a cell as a double; returns false when it is not a number at all.
bool ParseNumber(const std::string& cell, double* value) {
  if (cell.empty()) {
    *value = std::nan("");
    return true;
  }
  const std::string lower = ToLower(cell);
  if (lower == "nan" || lower == "-nan") {
    *value = std::nan("");
    return true;
  }
  if (lower == "inf" || lower == "+inf" || lower == "infinity") {
    *value = HUGE_VAL;
    return true;
  }
  if (lower == "-inf" || lower == "-infinity") {
    *value = -HUGE_VAL;
    return true;
  }
  const char* begin = cell.data();
  if (*begin == '+') ++begin;
  const char* end = cell.data() + cell.size();
  auto [ptr, ec] = std::from_chars(begin, end, *value);
  return ec == std::errc() && ptr == end;
}

constexpr const char* kCsvWhat = "a CSV file (comma-separated, '.' as decimal point)";
// Excel's "CSV UTF-8" starts with this byte order mark: skipped.
const std::string kUtf8Bom = "\xEF\xBB\xBF";

// Refuses what is not UTF-8/ASCII text before it is parsed line by line: binary files (an image
// given as the sensor record) and UTF-16 text (Excel's "Unicode text"). Leaves `in` at the start.
void CheckCsvEncoding(std::ifstream* in, const std::string& path) {
  std::string head(4096, '\0');
  in->read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in->gcount()));
  in->clear();
  in->seekg(0);
  if (head.rfind("\xFF\xFE", 0) == 0 || head.rfind("\xFE\xFF", 0) == 0) {
    throw Error(ErrorKind::kFileFormat, "", "UTF-16 text",
                std::string(kCsvWhat) + " in UTF-8 or ASCII (save it as \"CSV UTF-8\")")
        .WithFile(path);
  }
  const std::string binary = BinaryFileKind(head);
  if (!binary.empty()) throw Error(ErrorKind::kFileFormat, "", binary, kCsvWhat).WithFile(path);
}

// The header row decides the separator: a single "column" holding ';' or tabs is a file written
// with another separator (Excel in many locales writes "1,5;2,5"). We read only commas: with ';'
// the decimal separator is often ',' too, and guessing would silently misread numbers.
void CheckSeparator(const std::vector<std::string>& header_cells, const std::string& line,
                    const std::string& path, int line_no) {
  if (header_cells.size() != 1) return;
  const char* name = line.find(';') != std::string::npos    ? "semicolons (';')"
                     : line.find('\t') != std::string::npos ? "tabs"
                                                            : nullptr;
  if (name == nullptr) return;
  throw Error(ErrorKind::kFileFormat, "header",
              fmt::format("'{}', columns separated by {}", line, name),
              "comma-separated columns with '.' as decimal point (e.g. time_s,accel_g); "
              "re-export the file with ',' as the list separator")
      .WithFile(path, line_no);
}

}  // namespace

bool CsvTable::Has(const std::string& name) const {
  for (const auto& n : names)
    if (n == name) return true;
  return false;
}

const std::vector<double>& CsvTable::Column(const std::string& name) const {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return columns[i];
  throw Error(ErrorKind::kFileFormat, "column '" + name + "'",
              "missing; columns are " + Join(names), "a header with a '" + name + "' column")
      .WithFile(path);
}

const std::vector<std::string>& CsvTable::TextColumn(const std::string& name) const {
  for (std::size_t i = 0; i < text_names.size(); ++i)
    if (text_names[i] == name) return text_columns[i];
  throw Error(ErrorKind::kFileFormat, "column '" + name + "'", "missing",
              "a header with a '" + name + "' column")
      .WithFile(path);
}

namespace {

// The header row: column names (none empty or numeric), split into numeric and text columns.
void ReadHeader(const std::vector<std::string>& cells, const std::string& line, int line_no,
                const CsvReadOptions& options, CsvTable* table, std::vector<bool>* is_text) {
  CheckSeparator(cells, line, table->path, line_no);
  for (const auto& c : cells) {
    double dummy;
    if (c.empty() || ParseNumber(c, &dummy)) {
      throw Error(ErrorKind::kFileFormat, "header", "'" + line + "'",
                  "a header row of column names")
          .WithFile(table->path, line_no);
    }
  }
  for (const auto& c : cells) {
    const bool text = std::find(options.text_columns.begin(), options.text_columns.end(), c) !=
                      options.text_columns.end();
    is_text->push_back(text);
    (text ? table->text_names : table->names).push_back(c);
  }
  table->columns.assign(table->names.size(), {});
  table->text_columns.assign(table->text_names.size(), {});
}

// One data row: as many cells as the header, numbers (finite unless allowed) in numeric columns.
void AppendRow(const std::vector<std::string>& cells, int line_no, const CsvReadOptions& options,
               const std::vector<bool>& is_text, CsvTable* table) {
  if (cells.size() != is_text.size()) {
    throw Error(ErrorKind::kFileFormat, "row", fmt::format("{} cells", cells.size()),
                fmt::format("{} cells as in the header", is_text.size()))
        .WithFile(table->path, line_no);
  }
  std::size_t numeric = 0, text = 0;
  for (std::size_t cell = 0; cell < cells.size(); ++cell) {
    if (is_text[cell]) {
      table->text_columns[text++].push_back(cells[cell]);
      continue;
    }
    const std::size_t c = numeric++;
    double value;
    if (!ParseNumber(cells[cell], &value)) {
      throw Error(ErrorKind::kFileFormat, "column '" + table->names[c] + "'",
                  "'" + cells[cell] + "'", "a number")
          .WithFile(table->path, line_no, static_cast<int>(cell + 1));
    }
    if (!std::isfinite(value) && !options.allow_non_finite) {
      throw Error(ErrorKind::kFileFormat, "column '" + table->names[c] + "'",
                  cells[cell].empty() ? "an empty cell" : "'" + cells[cell] + "'",
                  "a finite number")
          .WithFile(table->path, line_no, static_cast<int>(cell + 1));
    }
    table->columns[c].push_back(value);
  }
}

// The file line of data row `row` (0-based; data rows follow the header in order, skipping
// comments and blank lines).
int LineOfDataRow(const std::string& path, const CsvReadOptions& options, std::size_t row) {
  std::ifstream again(path);
  std::string line;
  int ln = 0, data_row = -1;
  bool header_seen = false;
  while (std::getline(again, line)) {
    ++ln;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (Trim(line).empty() || line[0] == options.comment) continue;
    if (!header_seen) {
      header_seen = true;
      continue;
    }
    if (++data_row == static_cast<int>(row)) break;
  }
  return ln;
}

// CsvReadOptions::increasing_column holds strictly increasing values; the error names the line
// and the column's position in the file (1-based, counting text columns too).
void CheckIncreasing(const CsvTable& table, const std::vector<bool>& is_text,
                     const CsvReadOptions& options) {
  const auto& t = table.Column(options.increasing_column);
  std::size_t col = 0;
  for (std::size_t i = 0, numeric = 0; i < is_text.size(); ++i) {
    if (is_text[i]) continue;
    if (table.names[numeric++] == options.increasing_column) col = i;
  }
  for (std::size_t i = 1; i < t.size(); ++i) {
    if (!(t[i] > t[i - 1])) {
      throw Error(ErrorKind::kFileFormat, "column '" + options.increasing_column + "'",
                  fmt::format("{} after {}", t[i], t[i - 1]), "strictly increasing values")
          .WithFile(table.path, LineOfDataRow(table.path, options, i), static_cast<int>(col + 1));
    }
  }
}

}  // namespace

CsvTable ReadCsv(const std::string& path, const CsvReadOptions& options) {
  CheckInputFile(path, kCsvWhat, kMaxCsvFileBytes);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::kIo, "", "cannot open it for reading", kCsvWhat).WithFile(path);
  CheckCsvEncoding(&in, path);
  CsvTable table;
  table.path = path;
  std::string line;
  int line_no = 0;
  bool have_header = false;
  std::vector<bool> is_text;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (Trim(line).empty() || line[0] == options.comment) continue;
    if (line_no == 1 && line.rfind(kUtf8Bom, 0) == 0) line.erase(0, kUtf8Bom.size());
    const std::vector<std::string> cells = SplitCells(line);
    if (have_header) {
      AppendRow(cells, line_no, options, is_text, &table);
    } else {
      ReadHeader(cells, line, line_no, options, &table, &is_text);
      have_header = true;
    }
  }
  if (!have_header) {
    throw Error(ErrorKind::kFileFormat, "", "an empty file", "a header row and data rows")
        .WithFile(path);
  }
  for (const auto& required : options.required_columns) table.Column(required);
  if (!options.increasing_column.empty()) CheckIncreasing(table, is_text, options);
  return table;
}

std::string CsvHeaderLine(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t c = 0; c < names.size(); ++c) text += (c ? "," : "") + names[c];
  return text;
}

void WriteCsv(const std::string& path, const std::vector<std::string>& names,
              const std::vector<std::vector<double>>& columns, int precision) {
  if (names.size() != columns.size()) {
    throw Error(ErrorKind::kInvalidValue, "WriteCsv",
                fmt::format("{} names for {} columns", names.size(), columns.size()),
                "one name per column");
  }
  const std::size_t rows = columns.empty() ? 0 : columns[0].size();
  for (const auto& c : columns) {
    if (c.size() != rows) {
      throw Error(ErrorKind::kInvalidValue, "WriteCsv", "columns of different lengths",
                  "equal-length columns");
    }
  }
  std::string text = CsvHeaderLine(names) + "\n";
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (c) text += ",";
      const double v = columns[c][r];
      text += std::isnan(v) ? std::string("nan") : fmt::format("{:.{}g}", v, precision);
    }
    text += "\n";
  }
  WriteTextFileAtomic(path, text);
}

void WriteCsvRows(const std::string& path, const std::vector<std::string>& names,
                  const std::vector<std::vector<std::string>>& rows) {
  CsvRowWriter out(path, names);
  for (const auto& row : rows) out.Row(row);
  out.Commit();
}

CsvRowWriter::CsvRowWriter(const std::string& path, const std::vector<std::string>& names)
    : out_(path) {
  out_.Write(CsvHeaderLine(names) + "\n");
}

void CsvRowWriter::Row(std::span<const std::string> cells) {
  line_.clear();
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (c) line_ += ',';
    line_ += cells[c];
  }
  line_ += '\n';
  out_.Write(line_);
}

}  // namespace impactdic
