// CSV tables (RFC 4180 quoting) for Hypersim metadata and our reports.
#pragma once
#include <string>
#include <vector>

namespace isplat {

class CsvTable {
 public:
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::string source;  // file path, for error messages

  int column(const std::string& name) const;          // -1 if absent
  int require_column(const std::string& name) const;  // throws Error naming file and column
  const std::string& cell(size_t row, const std::string& name) const;
  double number(size_t row, const std::string& name) const;  // throws Error naming file, line, column
  bool boolean(size_t row, const std::string& name) const;   // True/False/true/false/1/0
  size_t size() const { return rows.size(); }
};

// Parses CSV text; the first record is the header. Ragged rows throw Error with the line number.
CsvTable parse_csv(const std::string& text, const std::string& source);
CsvTable read_csv(const std::string& path);
std::string format_csv(const CsvTable& table);
void write_csv(const std::string& path, const CsvTable& table);  // atomic

}  // namespace isplat
