// A CSV table of numbers with a header row (paint per point or node, fibres per tet).
#pragma once
#include <string>
#include <vector>

namespace isochor {

struct CsvTable {
  std::string path;
  std::vector<std::string> names;            // the header's columns
  std::vector<std::vector<double>> columns;  // one per name, a number per row
  // The column of this name, or null.
  const std::vector<double>* column(const std::string& name) const;
};

// Reads a CSV file whose first row names the columns and whose other rows are numbers (blank
// lines skipped). Throws Error "PATH:LINE: ..." naming the row and column of a bad cell.
// `what` says what the file was expected to be.
CsvTable read_csv_table(const std::string& path, const std::string& what);

// A line's comma-separated cells, trimmed.
std::vector<std::string> split_csv(const std::string& line);

}  // namespace isochor
