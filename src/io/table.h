// Report tables: columns declared once (name, Markdown title, decimals), rows of typed cells, written as
// Markdown, CSV and JSON by one function each. The evaluator's and the experiment's reports both use it.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/csv.h"

namespace isplat {

// A cell: nothing (a value that does not apply: "-" in Markdown, empty in CSV, null in JSON), text, a count
// or a measurement. A measurement that is not finite (NaN: not measured) is "n/a" in Markdown and CSV and
// null in JSON.
using TableCell = std::variant<std::monostate, std::string, int64_t, double>;

struct TableColumn {
  TableColumn(std::string name, int digits = 0, std::string title = "")
      : name(std::move(name)), digits(digits), title(std::move(title)) {}
  std::string name;   // CSV header and JSON key
  int digits = 0;     // decimals of a measurement in Markdown and CSV (fixed; -1 = as needed); JSON keeps every digit
  std::string title;  // Markdown header; empty = name
};

struct Table {
  std::vector<TableColumn> columns;
  std::vector<std::vector<TableCell>> rows;
  // Appends a row; throws Error when it has another number of cells than there are columns.
  void add(std::vector<TableCell> cells);
};

// `v` in fixed notation with `digits` decimals, "n/a" when it is not finite.
std::string format_fixed(double v, int digits);
// A cell as Markdown and CSV show it (nothing is "").
std::string format_cell(const TableCell& cell, int digits);

std::string table_markdown(const Table& table);  // "| a | b |\n|---|---|\n| 1 | 2 |\n"
CsvTable table_csv(const Table& table);
nlohmann::ordered_json table_json(const Table& table);               // an array of one object per row
void write_table_csv(const std::string& path, const Table& table);   // atomic
void write_table_json(const std::string& path, const Table& table);  // atomic, indented

}  // namespace isplat
