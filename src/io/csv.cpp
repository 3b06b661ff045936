// CSV parsing/writing with quoted fields and line-numbered errors.
#include "io/csv.h"

#include <cmath>

#include "core/error.h"
#include "core/parse.h"
#include "io/atomic_file.h"

namespace isplat {

int CsvTable::column(const std::string& name) const {
  for (size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<int>(i);
  return -1;
}

int CsvTable::require_column(const std::string& name) const {
  const int c = column(name);
  if (c < 0) fail(source, ": missing column '", name, "'");
  return c;
}

const std::string& CsvTable::cell(size_t row, const std::string& name) const {
  ISPLAT_CHECK(row < rows.size(), source, ": row ", row, " out of range");
  return rows[row][require_column(name)];
}

double CsvTable::number(size_t row, const std::string& name) const {
  const std::string& s = cell(row, name);
  const auto v = parse_double(s);
  // NaN and infinity parse too, but no column we read may hold them (sizes, matrices, depths).
  if (!v || !std::isfinite(*v))
    fail(source, ": data row ", row + 1, ", column '", name, "': expected a finite number, got '", s, "'");
  return *v;
}

bool CsvTable::boolean(size_t row, const std::string& name) const {
  const std::string& s = cell(row, name);
  if (s == "True" || s == "true" || s == "1" || s == "TRUE") return true;
  if (s == "False" || s == "false" || s == "0" || s == "FALSE") return false;
  fail(source, ": data row ", row + 1, ", column '", name, "': expected True/False, got '", s, "'");
}

CsvTable parse_csv(const std::string& text, const std::string& source) {
  CsvTable table;
  table.source = source;
  std::vector<std::vector<std::string>> records;
  std::vector<std::string> record;
  std::string field;
  bool in_quotes = false, field_started = false;
  size_t line = 1, record_line = 1;
  auto end_field = [&] {
    record.push_back(field);
    field.clear();
    field_started = false;
  };
  auto end_record = [&] {
    end_field();
    if (!(record.size() == 1 && record[0].empty())) {  // skip blank lines
      if (!records.empty() && record.size() != records[0].size())
        fail(source, ": line ", record_line, " has ", record.size(), " fields, header has ", records[0].size());
      records.push_back(record);
    }
    record.clear();
    record_line = line;
  };
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_quotes) {
      if (c == '"') {
        if (i + 1 < text.size() && text[i + 1] == '"') {
          field += '"';
          ++i;
        } else {
          in_quotes = false;
        }
      } else {
        if (c == '\n') ++line;
        field += c;
      }
      continue;
    }
    if (c == '"' && !field_started) {
      in_quotes = true;
      field_started = true;
    } else if (c == ',') {
      end_field();
    } else if (c == '\n' || c == '\r') {
      if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      ++line;
      end_record();
    } else {
      field += c;
      field_started = true;
    }
  }
  if (in_quotes) fail(source, ": unterminated quoted field starting near line ", record_line);
  if (!field.empty() || !record.empty()) end_record();
  if (records.empty()) fail(source, ": empty CSV (no header)");
  table.header = records[0];
  table.rows.assign(records.begin() + 1, records.end());
  return table;
}

CsvTable read_csv(const std::string& path) {
  return parse_csv(read_file_bytes(path), path);
}

static std::string quote(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string format_csv(const CsvTable& table) {
  std::string out;
  auto emit = [&](const std::vector<std::string>& r) {
    for (size_t i = 0; i < r.size(); ++i) out += (i ? "," : "") + quote(r[i]);
    out += "\n";
  };
  emit(table.header);
  for (const auto& r : table.rows) {
    ISPLAT_CHECK(r.size() == table.header.size(), "format_csv: row has ", r.size(), " fields, header ",
                 table.header.size());
    emit(r);
  }
  return out;
}

void write_csv(const std::string& path, const CsvTable& table) {
  write_file_atomic(path, format_csv(table));
}

}  // namespace isplat
