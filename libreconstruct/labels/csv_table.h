#pragma once
// The CSV conventions of netlab's DLTdv8-style files (xypts.csv, xyzpts.csv, xyzres.csv): a header
// row, then rows of numbers; "NaN", "nan" or an empty cell for no value; numbers written with 17
// significant digits (they read back as the same double) and independent of the locale.

#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace netlab::recon {

// 17 significant digits, or "NaN" for anything not finite.
std::string Number(double value);

// A cell: NaN for "NaN", "nan" or empty, a finite number, or nullopt if neither.
std::optional<double> ParseCell(const std::string& cell);

// The comma-separated cells of a line, trimmed of blanks.
std::vector<std::string> SplitCells(const std::string& line);

// A CSV file of numbers under a header row (blank lines at the end ignored; CRLF accepted). Row i
// of `rows` is line i + 2 of the file. Throws netlab::InputError naming the file, line and
// column of anything that is not a number, and rows of the wrong length.
struct CsvTable {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
};
CsvTable ReadCsvTable(const std::string& path);

// Writes through "<path>.partial" and a rename, so a failed write never leaves half a file at
// path. Throws std::runtime_error.
void WriteTextFile(const std::string& path, const std::function<void(std::ostream&)>& write);

}  // namespace netlab::recon
