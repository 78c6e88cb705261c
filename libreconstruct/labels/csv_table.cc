#include "libreconstruct/labels/csv_table.h"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "common/errors.h"
#include "common/files.h"

namespace netlab::recon {

// 17 significant digits give back the same double (IEEE 754 binary64); to_chars, unlike printf,
// ignores the locale a GUI may have set.
std::string Number(double value) {
  if (!std::isfinite(value)) return "NaN";
  char buffer[32];
  const auto result =
      std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::general, 17);
  return std::string(buffer, result.ptr);
}

// A cell: NaN for "NaN", "nan" or empty (no value), a finite number, or nullopt if neither.
std::optional<double> ParseCell(const std::string& cell) {
  if (cell.empty() || cell == "NaN" || cell == "nan")
    return std::numeric_limits<double>::quiet_NaN();
  double value = 0.0;
  const char* end = cell.data() + cell.size();
  const auto result = std::from_chars(cell.data(), end, value);
  if (result.ec != std::errc() || result.ptr != end || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::vector<std::string> SplitCells(const std::string& line) {
  std::vector<std::string> cells;
  size_t start = 0;
  while (true) {
    const size_t end = line.find(',', start);
    const std::string cell = line.substr(start, end - start);
    const size_t first = cell.find_first_not_of(" \t"), last = cell.find_last_not_of(" \t");
    cells.push_back(first == std::string::npos ? "" : cell.substr(first, last + 1 - first));
    if (end == std::string::npos) return cells;
    start = end + 1;
  }
}

CsvTable ReadCsvTable(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open file");
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(line);
  }
  while (!lines.empty() && lines.back().empty()) lines.pop_back();
  if (lines.empty()) throw InputError(path + ": empty file (expected a header row)");
  CsvTable table;
  table.columns = SplitCells(lines[0]);
  for (size_t i = 1; i < lines.size(); ++i) {
    const std::string where = path + ":" + std::to_string(i + 1) + ": ";
    const std::vector<std::string> cells = SplitCells(lines[i]);
    if (cells.size() != table.columns.size())
      throw InputError(where + "expected " + std::to_string(table.columns.size()) +
                       " cells (one per header column), got " + std::to_string(cells.size()));
    std::vector<double>& row = table.rows.emplace_back();
    for (size_t j = 0; j < cells.size(); ++j) {
      const std::optional<double> value = ParseCell(cells[j]);
      if (!value)
        throw InputError(where + "column '" + table.columns[j] + "': cannot read '" + cells[j] +
                         "' as a number");
      row.push_back(*value);
    }
  }
  return table;
}

// Writes through "<path>.partial" and a rename, so a failed write never leaves half a file at path.
void WriteTextFile(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const std::string partial = path + ".partial";
  std::ofstream out(partial, std::ios::binary);
  write(out);
  out.close();
  if (!out) {
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);
    throw std::runtime_error(path + ": cannot write " + partial);
  }
  RenameInto(partial, path);
}

}  // namespace netlab::recon
