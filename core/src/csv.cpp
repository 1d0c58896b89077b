#include "isochor/core/csv.hpp"

#include <sstream>

#include "isochor/base/error.hpp"
#include "isochor/core/input_file.hpp"

namespace isochor {

const std::vector<double>* CsvTable::column(const std::string& name) const {
  for (std::size_t k = 0; k < names.size(); ++k)
    if (names[k] == name) return &columns[k];
  return nullptr;
}

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> f;
  std::string cell;
  std::istringstream s(line);
  while (std::getline(s, cell, ',')) {
    const auto a = cell.find_first_not_of(" \t\r"), b = cell.find_last_not_of(" \t\r");
    f.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
  }
  return f;
}

CsvTable read_csv_table(const std::string& path, const std::string& what) {
  std::istringstream in(read_input_file(path, what, input_limits::kPaint));
  std::string line;
  long line_no = 1;
  if (!std::getline(in, line)) throw Error(path + ":1: empty (expected " + what + " with a header row)");
  CsvTable out;
  out.path = path;
  out.names = split_csv(line);
  out.columns.resize(out.names.size());
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto f = split_csv(line);
    if (f.size() != out.names.size())
      throw Error(path + ":" + std::to_string(line_no) + ": expected " + std::to_string(out.names.size()) +
                  " columns, got " + std::to_string(f.size()));
    for (std::size_t k = 0; k < f.size(); ++k) {
      double v;
      try {
        std::size_t used;
        v = std::stod(f[k], &used);
        if (used != f[k].size()) throw 0;
      } catch (...) {
        throw Error(path + ":" + std::to_string(line_no) + ": " + out.names[k] + ": \"" + f[k] + "\" is not a number");
      }
      out.columns[k].push_back(v);
    }
  }
  return out;
}

}  // namespace isochor
