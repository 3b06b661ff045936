// The report table writer: Markdown, CSV and JSON from one declaration of the columns.
#include "io/table.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "core/error.h"
#include "io/atomic_file.h"

namespace isplat {

void Table::add(std::vector<TableCell> cells) {
  ISPLAT_CHECK(cells.size() == columns.size(), "table: a row has ", cells.size(), " cells for ", columns.size(),
               " columns");
  rows.push_back(std::move(cells));
}

std::string format_fixed(double v, int digits) {
  if (!std::isfinite(v)) return "n/a";
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << v;
  return os.str();
}

std::string format_cell(const TableCell& cell, int digits) {
  if (const auto* s = std::get_if<std::string>(&cell)) return *s;
  if (const auto* n = std::get_if<int64_t>(&cell)) return std::to_string(*n);
  if (const auto* v = std::get_if<double>(&cell)) {
    if (digits >= 0 || !std::isfinite(*v)) return format_fixed(*v, digits);
    std::ostringstream os;  // as many digits as needed, up to 6 significant ones
    os << *v;
    return os.str();
  }
  return "";
}

std::string table_markdown(const Table& table) {
  std::string out = "|", rule = "|";
  for (const auto& c : table.columns) out += " " + (c.title.empty() ? c.name : c.title) + " |", rule += "---|";
  out += "\n" + rule + "\n";
  for (const auto& row : table.rows) {
    out += "|";
    for (size_t k = 0; k < row.size(); ++k) {
      const bool nothing = std::holds_alternative<std::monostate>(row[k]);
      out += " " + (nothing ? std::string("-") : format_cell(row[k], table.columns[k].digits)) + " |";
    }
    out += "\n";
  }
  return out;
}

CsvTable table_csv(const Table& table) {
  CsvTable csv;
  for (const auto& c : table.columns) csv.header.push_back(c.name);
  for (const auto& row : table.rows) {
    std::vector<std::string> cells;
    for (size_t k = 0; k < row.size(); ++k) cells.push_back(format_cell(row[k], table.columns[k].digits));
    csv.rows.push_back(std::move(cells));
  }
  return csv;
}

nlohmann::ordered_json table_json(const Table& table) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  for (const auto& row : table.rows) {
    nlohmann::ordered_json j = nlohmann::ordered_json::object();
    for (size_t k = 0; k < row.size(); ++k) {
      nlohmann::ordered_json& v = j[table.columns[k].name];
      if (const auto* s = std::get_if<std::string>(&row[k])) v = *s;
      if (const auto* n = std::get_if<int64_t>(&row[k])) v = *n;
      if (const auto* d = std::get_if<double>(&row[k]); d && std::isfinite(*d)) v = *d;
    }
    out.push_back(std::move(j));
  }
  return out;
}

void write_table_csv(const std::string& path, const Table& table) {
  write_csv(path, table_csv(table));
}

void write_table_json(const std::string& path, const Table& table) {
  write_file_atomic(path, table_json(table).dump(2) + "\n");
}

}  // namespace isplat
