// Typed JSON configuration: option structs describe their keys once; the same description reads,
// validates, writes and documents them.
#pragma once
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"

namespace isplat {

// Closed/open numeric bounds for a config value.
struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false;
  bool hi_open = false;

  static Range at_least(double v) { return {v, std::numeric_limits<double>::infinity(), false, false}; }
  static Range above(double v) { return {v, std::numeric_limits<double>::infinity(), true, false}; }
  static Range between(double a, double b) { return {a, b, false, false}; }
  static Range unit() { return between(0.0, 1.0); }
  bool contains(double v) const;
  bool bounded() const;
  std::string describe() const;  // e.g. "in [0, 1]" or ">= 1"
};

// Visitor over an option struct. Each struct has `void visit(ConfigVisitor&)` that lists its fields
// with a default (the member's initial value), a one-line doc and its validation.
class ConfigVisitor {
 public:
  virtual ~ConfigVisitor() = default;
  virtual void field(const char* key, bool& value, const char* doc) = 0;
  virtual void field(const char* key, int64_t& value, const char* doc, Range range = {}) = 0;
  virtual void field(const char* key, double& value, const char* doc, Range range = {}) = 0;
  virtual void field(const char* key, std::string& value, const char* doc, std::vector<std::string> choices = {}) = 0;
  virtual void field(const char* key, std::vector<int64_t>& value, const char* doc, Range range = {}) = 0;
  virtual void field(const char* key, std::vector<double>& value, const char* doc, Range range = {}) = 0;
  virtual void field(const char* key, std::vector<std::string>& value, const char* doc) = 0;

  // Narrower numeric types, stored through the 64-bit forms above.
  void field(const char* key, int& value, const char* doc, Range range = {});
  void field(const char* key, float& value, const char* doc, Range range = {});

  template <class T>
  void section(const char* key, const char* doc, T& options) {
    enter(key, doc);
    options.visit(*this);
    leave();
  }

  // A list of sections (JSON array of objects), e.g. the datasets of an evaluation.
  template <class T>
  void list(const char* key, const char* doc, std::vector<T>& items) {
    const int64_t n = begin_list(key, doc, static_cast<int64_t>(items.size()));
    if (n < 0) return;  // absent from the document: keep the defaults
    if (rebuilds_lists()) items.assign(static_cast<size_t>(n), T{});
    for (int64_t i = 0; i < n; ++i) {
      begin_element(i);
      items[static_cast<size_t>(i)].visit(*this);
      end_element();
    }
    end_list();
  }

 protected:
  virtual void enter(const char* key, const char* doc) = 0;
  virtual void leave() = 0;
  // Lists: begin_list returns the element count to visit (-1 = skip); readers rebuild the vector.
  virtual int64_t begin_list(const char* key, const char* doc, int64_t current) = 0;
  virtual bool rebuilds_lists() const { return false; }
  virtual void begin_element(int64_t index) = 0;
  virtual void end_element() = 0;
  virtual void end_list() = 0;

 public:
  // A constraint on a field already visited that its Range cannot say (a list's length, an order).
  // Readers throw Error naming the file and key when `ok` is false; other visitors ignore it.
  virtual void require(const char* key, bool ok, const char* expect) {}
};

// A merged JSON document (base files, the config file, then --set overrides) and where each key came from.
struct ConfigDocument {
  nlohmann::json json = nlohmann::json::object();
  std::map<std::string, std::string> origin;  // dotted key -> file path or "--set k=v"
  std::string source_of(const std::string& key) const;
};

// Reads `path` (empty = defaults only), following "base": "other.json" chains, then applies
// overrides of the form "a.b=value" (value parsed as JSON, else taken as a string).
ConfigDocument merge_config(const std::string& path, const std::vector<std::string>& overrides);
// Applies "a.b=value" / "list[0].key=value" overrides to an existing document.
void apply_overrides(ConfigDocument& doc, const std::vector<std::string>& overrides);
// Parses any JSON file; a missing file, a folder or invalid JSON throws Error naming the path.
nlohmann::json read_json_file(const std::string& path);

// Deeper nesting than this is refused while parsing: no file we read needs more than a few levels, and
// recursive code (dump, merging, readers) must not exhaust the stack on a hostile file.
constexpr int kMaxJsonDepth = 512;
// Parses JSON text read from `source` (a file name or e.g. "--set k=v"). Syntax errors, nesting deeper
// than kMaxJsonDepth and numbers beyond the double range throw Error naming `source` and the byte offset.
nlohmann::json parse_json(const std::string& text, const std::string& source);

// Runs `read` over a parsed document and turns nlohmann's exceptions (a value of the wrong type, a
// missing key, a number that does not fit) into an Error naming `source`: the safety net under each
// reader's own key checks, so no malformed document escapes as an abort.
template <class F>
auto guard_json(const std::string& source, F&& read) -> decltype(read()) {
  try {
    return read();
  } catch (const nlohmann::json::exception& e) {
    fail(source, ": malformed content: ", e.what());
  }
}

// Visitor plumbing; use the templates below.
void read_options(const ConfigDocument& doc, const std::function<void(ConfigVisitor&)>& visit);
nlohmann::ordered_json write_options(const std::function<void(ConfigVisitor&)>& visit);
std::string document_options(const std::function<void(ConfigVisitor&)>& visit);

// Fill `options` from a document; unknown keys, wrong types and out-of-range values throw Error
// naming the file, the key and the expected form.
template <class T>
void apply_config(const ConfigDocument& doc, T& options) {
  read_options(doc, [&](ConfigVisitor& v) { options.visit(v); });
}

template <class T>
T load_config(const std::string& path, const std::vector<std::string>& overrides = {}) {
  T options;
  apply_config(merge_config(path, overrides), options);
  return options;
}

// The full merged configuration, every key with its value (for --print-config and checkpoints).
template <class T>
nlohmann::ordered_json config_to_json(const T& options) {
  T copy = options;
  return write_options([&](ConfigVisitor& v) { copy.visit(v); });
}

// One line per key: name, type, bounds, default and doc (for --help-config).
template <class T>
std::string config_reference(const T& options) {
  T copy = options;
  return document_options([&](ConfigVisitor& v) { copy.visit(v); });
}

// Rebuild options from a JSON written by config_to_json (e.g. stored in a checkpoint).
template <class T>
T config_from_json(const nlohmann::json& json, const std::string& source) {
  ConfigDocument doc;
  doc.json = json;
  doc.origin[""] = source;
  T options;
  apply_config(doc, options);
  return options;
}

}  // namespace isplat
