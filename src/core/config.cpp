// Config merging (base files, overrides), validation against the option structs, and documentation.
#include "core/config.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "core/error.h"
#include "core/parse.h"
#include "core/paths.h"
#include "core/retired_keys.h"

namespace isplat {
namespace fs = std::filesystem;
using json = nlohmann::json;

// ---------------------------------------------------------------- Range
bool Range::contains(double v) const {
  if (std::isnan(v)) return false;
  if (lo_open ? !(v > lo) : !(v >= lo)) return false;
  if (hi_open ? !(v < hi) : !(v <= hi)) return false;
  return true;
}

bool Range::bounded() const {
  return std::isfinite(lo) || std::isfinite(hi);
}

static std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string Range::describe() const {
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  if (has_lo && has_hi) return cat("in ", lo_open ? "(" : "[", num(lo), ", ", num(hi), hi_open ? ")" : "]");
  if (has_lo) return cat(lo_open ? "> " : ">= ", num(lo));
  if (has_hi) return cat(hi_open ? "< " : "<= ", num(hi));
  return "";
}

void ConfigVisitor::field(const char* key, int& value, const char* doc, Range range) {
  int64_t wide = value;
  field(key, wide, doc, range);
  value = static_cast<int>(wide);
}

void ConfigVisitor::field(const char* key, float& value, const char* doc, Range range) {
  double wide = value;
  field(key, wide, doc, range);
  value = static_cast<float>(wide);
}

// ---------------------------------------------------------------- documents
std::string ConfigDocument::source_of(const std::string& key) const {
  // The most specific recorded origin: the key itself, then its parents, then the document.
  std::string k = key;
  while (true) {
    auto it = origin.find(k);
    if (it != origin.end()) return it->second;
    if (k.empty()) return "<defaults>";
    auto dot = k.rfind('.');
    k = dot == std::string::npos ? "" : k.substr(0, dot);
  }
}

json parse_json(const std::string& text, const std::string& source) {
  const json::parser_callback_t limit_depth = [&](int depth, json::parse_event_t event, json&) {
    if (depth > kMaxJsonDepth &&
        (event == json::parse_event_t::object_start || event == json::parse_event_t::array_start))
      fail(source, ": JSON nested deeper than ", kMaxJsonDepth, " levels");
    return true;
  };
  try {
    return json::parse(text, limit_depth);
  } catch (const json::parse_error& e) {
    fail(source, ": invalid JSON at byte ", e.byte, ": ", e.what());
  } catch (const json::exception& e) {  // e.g. out_of_range: a number such as 1e400
    fail(source, ": invalid JSON: ", e.what());
  }
}

json read_json_file(const std::string& path) {
  require_regular_file(path, "JSON file");  // /dev/zero never ends, a FIFO blocks: refused before opening
  std::error_code ec;
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, fs::exists(path, ec) ? ": cannot open (permission denied)" : ": no such file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) fail(path, ": read error");
  return parse_json(text.str(), path);
}

static void record_origins(const json& node, const std::string& prefix, const std::string& source,
                           std::map<std::string, std::string>& origin) {
  if (!prefix.empty()) origin[prefix] = source;
  if (!node.is_object()) return;
  for (auto it = node.begin(); it != node.end(); ++it)
    record_origins(it.value(), prefix.empty() ? it.key() : prefix + "." + it.key(), source, origin);
}

static void merge_into(json& dst, const json& src) {
  for (auto it = src.begin(); it != src.end(); ++it) {
    if (it.value().is_object() && dst.contains(it.key()) && dst[it.key()].is_object())
      merge_into(dst[it.key()], it.value());
    else
      dst[it.key()] = it.value();
  }
}

static void merge_file(const std::string& path, ConfigDocument& doc, std::vector<std::string>& chain) {
  std::error_code ec;
  const fs::path resolved = fs::weakly_canonical(path, ec);
  const std::string canonical = ec ? path : resolved.string();
  for (const auto& seen : chain)
    if (seen == canonical) fail(path, ": \"base\" chain loops back to itself");
  chain.push_back(canonical);
  json j = read_json_file(path);
  if (!j.is_object()) fail(path, ": top level must be a JSON object");
  if (j.contains("base")) {
    if (!j["base"].is_string()) fail(path, ": key 'base' must be a string path to another config file");
    fs::path base = fs::path(path).parent_path() / j["base"].get<std::string>();
    merge_file(base.string(), doc, chain);
    j.erase("base");
  }
  record_origins(j, "", path, doc.origin);
  merge_into(doc.json, j);
}

void apply_overrides(ConfigDocument& doc, const std::vector<std::string>& overrides) {
  for (const auto& item : overrides) {
    const std::string source = "--set " + item;
    auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0) fail(source, ": expected the form key.path=value");
    const std::string key = item.substr(0, eq), text = item.substr(eq + 1);
    json value;
    try {
      value = parse_json(text, source);
    } catch (const Error&) {
      value = text;  // bare words are strings: --set sampler.mode=pixel
    }
    json* node = &doc.json;
    std::string prefix;
    std::stringstream parts(key);
    std::string part;
    std::vector<std::string> names;
    while (std::getline(parts, part, '.')) {
      if (part.empty()) fail(source, ": empty component in key '", key, "'");
      names.push_back(part);
    }
    // A component may index a list of sections: datasets[0].root=...
    auto step = [&](const std::string& name) -> json* {
      const auto br = name.find('[');
      const std::string field = name.substr(0, br);
      prefix += (prefix.empty() ? "" : ".") + field;
      json* child = &(*node)[field];
      if (br == std::string::npos) return child;
      if (name.back() != ']') fail(source, ": bad index in '", name, "'");
      const auto parsed = parse_int(name.substr(br + 1, name.size() - br - 2));
      if (!parsed || *parsed < 0) fail(source, ": bad index in '", name, "'");
      const size_t index = static_cast<size_t>(*parsed);
      if (!child->is_array() || index >= child->size())
        fail(source, ": '", prefix, "' has no element ", index,
             " (lists are extended in the config file, not by --set)");
      prefix += cat("[", index, "]");
      return &(*child)[index];
    };
    for (size_t i = 0; i + 1 < names.size(); ++i) {
      json& child = *step(names[i]);
      if (child.is_null()) child = json::object();
      if (!child.is_object()) fail(source, ": '", prefix, "' is a value, not a section");
      node = &child;
    }
    if (names.back().find('[') != std::string::npos)
      fail(source, ": the last component of '", key, "' cannot be an index");
    (*node)[names.back()] = value;
    record_origins(value, key, source, doc.origin);
  }
}

ConfigDocument merge_config(const std::string& path, const std::vector<std::string>& overrides) {
  ConfigDocument doc;
  if (!path.empty()) {
    std::vector<std::string> chain;
    merge_file(path, doc, chain);
    doc.origin[""] = path;
  }
  apply_overrides(doc, overrides);
  return doc;
}

// ---------------------------------------------------------------- reading
namespace {

size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t prev = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      size_t cur = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, prev + (a[i - 1] != b[j - 1])});
      prev = cur;
    }
  }
  return row[b.size()];
}

std::string short_json(const json& v) {
  std::string s = v.dump();
  return s.size() > 60 ? s.substr(0, 57) + "..." : s;
}

class JsonReader final : public ConfigVisitor {
 public:
  explicit JsonReader(const ConfigDocument& doc) : doc_(doc) { stack_.push_back({&doc.json, "", {}}); }

  void field(const char* key, bool& value, const char* doc) override {
    if (const json* v = find(key)) {
      if (!v->is_boolean()) bad(key, "must be true or false", doc, *v);
      value = v->get<bool>();
    }
  }
  void field(const char* key, int64_t& value, const char* doc, Range range) override {
    if (const json* v = find(key)) value = as_int(key, *v, doc, range, "must be an integer");
  }
  void field(const char* key, double& value, const char* doc, Range range) override {
    if (const json* v = find(key)) value = as_number(key, *v, doc, range, "must be a number");
  }
  void field(const char* key, std::string& value, const char* doc, std::vector<std::string> choices) override {
    if (const json* v = find(key)) {
      std::string expect = "must be a string";
      if (!choices.empty()) {
        expect = "must be one of";
        for (size_t i = 0; i < choices.size(); ++i) expect += (i ? " | " : " ") + choices[i];
      }
      if (!v->is_string()) bad(key, expect, doc, *v);
      const auto s = v->get<std::string>();
      if (!choices.empty() && std::find(choices.begin(), choices.end(), s) == choices.end()) bad(key, expect, doc, *v);
      value = s;
    }
  }
  void field(const char* key, std::vector<int64_t>& value, const char* doc, Range range) override {
    if (const json* v = find(key)) {
      if (!v->is_array()) bad(key, "must be a list of integers", doc, *v);
      std::vector<int64_t> out;
      for (const auto& e : *v) out.push_back(as_int(key, e, doc, range, "must be a list of integers"));
      value = out;
    }
  }
  void field(const char* key, std::vector<double>& value, const char* doc, Range range) override {
    if (const json* v = find(key)) {
      if (!v->is_array()) bad(key, "must be a list of numbers", doc, *v);
      std::vector<double> out;
      for (const auto& e : *v) out.push_back(as_number(key, e, doc, range, "must be a list of numbers"));
      value = out;
    }
  }
  void field(const char* key, std::vector<std::string>& value, const char* doc) override {
    if (const json* v = find(key)) {
      if (!v->is_array()) bad(key, "must be a list of strings", doc, *v);
      std::vector<std::string> out;
      for (const auto& e : *v) {
        if (!e.is_string()) bad(key, "must be a list of strings", doc, *v);
        out.push_back(e.get<std::string>());
      }
      value = out;
    }
  }

  void require(const char* key, bool ok, const char* expect) override {
    if (ok) return;
    const std::string full = path(key);
    const json* node = stack_.back().node;
    const std::string got = node && node->contains(key) ? cat("; got ", short_json((*node)[key])) : "";
    fail(doc_.source_of(full), ": key '", full, "' ", expect, got);
  }

  void finish() { check_unknown(stack_.back()); }

 protected:
  void enter(const char* key, const char* doc) override {
    Frame& top = stack_.back();
    top.known.insert(key);
    const json* child = nullptr;
    if (top.node && top.node->contains(key)) {
      child = &(*top.node)[key];
      if (!child->is_object()) bad(key, "must be a section (JSON object)", doc, *child);
    }
    stack_.push_back({child, path(key), {}});
  }
  void leave() override {
    check_unknown(stack_.back());
    stack_.pop_back();
  }
  int64_t begin_list(const char* key, const char* doc, int64_t) override {
    Frame& top = stack_.back();
    top.known.insert(key);
    if (!top.node || !top.node->contains(key)) return -1;
    const json& arr = (*top.node)[key];
    if (!arr.is_array()) bad(key, "must be a list of sections (JSON array of objects)", doc, arr);
    lists_.push_back({&arr, path(key)});
    return static_cast<int64_t>(arr.size());
  }
  bool rebuilds_lists() const override { return true; }
  void begin_element(int64_t index) override {
    const auto& l = lists_.back();
    const json& e = (*l.array)[static_cast<size_t>(index)];
    const std::string name = cat(l.prefix, "[", index, "]");
    if (!e.is_object())
      fail(doc_.source_of(l.prefix), ": '", name, "' must be a section (JSON object); got ", short_json(e));
    stack_.push_back({&e, name, {}});
  }
  void end_element() override {
    check_unknown(stack_.back());
    stack_.pop_back();
  }
  void end_list() override { lists_.pop_back(); }

 private:
  struct ListFrame {
    const json* array;
    std::string prefix;
  };
  std::vector<ListFrame> lists_;
  struct Frame {
    const json* node;
    std::string prefix;
    std::set<std::string> known;
  };

  std::string path(const std::string& key) const {
    const auto& p = stack_.back().prefix;
    return p.empty() ? key : p + "." + key;
  }

  const json* find(const char* key) {
    Frame& top = stack_.back();
    top.known.insert(key);
    if (!top.node || !top.node->contains(key)) return nullptr;
    return &(*top.node)[key];
  }

  [[noreturn]] void bad(const char* key, const std::string& expect, const char* doc, const json& got) const {
    const std::string full = path(key);
    fail(doc_.source_of(full), ": key '", full, "' ", expect, " (", doc, "); got ", short_json(got));
  }

  int64_t as_int(const char* key, const json& v, const char* doc, const Range& range, const std::string& what) {
    const std::string expect = range.bounded() ? what + " " + range.describe() : what;
    int64_t out = 0;
    if (v.is_number_integer()) {
      out = v.get<int64_t>();
    } else if (v.is_number_float() && std::isfinite(v.get<double>()) &&
               std::floor(v.get<double>()) == v.get<double>() && std::fabs(v.get<double>()) < 9.0e15) {
      out = static_cast<int64_t>(v.get<double>());  // 1.5e6 written as a float is still an integer
    } else {
      bad(key, expect, doc, v);
    }
    if (!range.contains(static_cast<double>(out))) bad(key, expect, doc, v);
    return out;
  }

  double as_number(const char* key, const json& v, const char* doc, const Range& range, const std::string& what) {
    const std::string expect = range.bounded() ? what + " " + range.describe() : what;
    if (!v.is_number()) bad(key, expect, doc, v);
    const double out = v.get<double>();
    if (!std::isfinite(out) || !range.contains(out)) bad(key, expect, doc, v);
    return out;
  }

  void check_unknown(const Frame& frame) const {
    if (!frame.node) return;
    for (auto it = frame.node->begin(); it != frame.node->end(); ++it) {
      if (frame.known.count(it.key())) continue;
      const std::string full = frame.prefix.empty() ? it.key() : frame.prefix + "." + it.key();
      std::string best;
      size_t best_d = 4;
      for (const auto& k : frame.known) {
        size_t d = edit_distance(it.key(), k);
        if (d < best_d) best_d = d, best = k;
      }
      std::string known;
      for (const auto& k : frame.known) known += (known.empty() ? "" : ", ") + k;
      for (const RetiredKey& k : retired_keys())  // a key of an older config: say why it went
        if (k.path == full || (k.path.size() > full.size() &&
                               k.path.compare(k.path.size() - full.size() - 1, std::string::npos, "." + full) == 0))
          fail(doc_.source_of(full), ": '", full, "' was retired: its study (", k.study,
               ") did not adopt it, and its remaining behaviour is now the only one; delete the key");
      fail(doc_.source_of(full), ": unknown key '", full, "'",
           best.empty() ? "" : cat(" (did you mean '", frame.prefix.empty() ? best : frame.prefix + "." + best, "'?)"),
           "; keys allowed ", frame.prefix.empty() ? "at the top level" : "in '" + frame.prefix + "'", ": ", known);
    }
  }

  const ConfigDocument& doc_;
  std::vector<Frame> stack_;
};

// ---------------------------------------------------------------- writing
class JsonWriter final : public ConfigVisitor {
 public:
  JsonWriter() { stack_.push_back(&root_); }
  void field(const char* key, bool& v, const char*) override { (*stack_.back())[key] = v; }
  void field(const char* key, int64_t& v, const char*, Range) override { (*stack_.back())[key] = v; }
  void field(const char* key, double& v, const char*, Range) override { (*stack_.back())[key] = v; }
  void field(const char* key, std::string& v, const char*, std::vector<std::string>) override {
    (*stack_.back())[key] = v;
  }
  void field(const char* key, std::vector<int64_t>& v, const char*, Range) override { (*stack_.back())[key] = v; }
  void field(const char* key, std::vector<double>& v, const char*, Range) override { (*stack_.back())[key] = v; }
  void field(const char* key, std::vector<std::string>& v, const char*) override { (*stack_.back())[key] = v; }
  nlohmann::ordered_json result() const { return root_; }

 protected:
  void enter(const char* key, const char*) override {
    auto& child = (*stack_.back())[key];
    child = nlohmann::ordered_json::object();
    stack_.push_back(&child);
  }
  void leave() override { stack_.pop_back(); }
  int64_t begin_list(const char* key, const char*, int64_t current) override {
    auto& arr = (*stack_.back())[key];
    arr = nlohmann::ordered_json::array();
    lists_.push_back(&arr);
    return current;
  }
  void begin_element(int64_t) override {
    lists_.back()->push_back(nlohmann::ordered_json::object());
    stack_.push_back(&lists_.back()->back());
  }
  void end_element() override { stack_.pop_back(); }
  void end_list() override { lists_.pop_back(); }

 private:
  std::vector<nlohmann::ordered_json*> lists_;
  nlohmann::ordered_json root_ = nlohmann::ordered_json::object();
  std::vector<nlohmann::ordered_json*> stack_;
};

// ---------------------------------------------------------------- documenting
class DocWriter final : public ConfigVisitor {
 public:
  void field(const char* key, bool& v, const char* doc) override { add(key, "bool", v ? "true" : "false", doc); }
  void field(const char* key, int64_t& v, const char* doc, Range r) override {
    add(key, join("int", r.describe()), std::to_string(v), doc);
  }
  void field(const char* key, double& v, const char* doc, Range r) override {
    add(key, join("number", r.describe()), num(v), doc);
  }
  void field(const char* key, std::string& v, const char* doc, std::vector<std::string> choices) override {
    std::string type = "string";
    if (!choices.empty()) {
      type.clear();
      for (const auto& c : choices) type += (type.empty() ? "" : "|") + c;
    }
    add(key, type, "\"" + v + "\"", doc);
  }
  void field(const char* key, std::vector<int64_t>& v, const char* doc, Range r) override {
    add(key, join("[int]", r.describe()), json(v).dump(), doc);
  }
  void field(const char* key, std::vector<double>& v, const char* doc, Range r) override {
    add(key, join("[number]", r.describe()), json(v).dump(), doc);
  }
  void field(const char* key, std::vector<std::string>& v, const char* doc) override {
    add(key, "[string]", json(v).dump(), doc);
  }
  std::string result() const { return out_.str(); }

 protected:
  void enter(const char* key, const char* doc) override {
    prefix_.push_back(key);
    out_ << "\n[" << full("") << "]  " << doc << "\n";
  }
  void leave() override { prefix_.pop_back(); }
  int64_t begin_list(const char* key, const char* doc, int64_t) override {
    prefix_.push_back(std::string(key) + "[]");
    out_ << "\n[" << full("") << "]  (list) " << doc << "\n";
    return 1;  // document one default element
  }
  bool rebuilds_lists() const override { return true; }
  void begin_element(int64_t) override {}
  void end_element() override {}
  void end_list() override { prefix_.pop_back(); }

 private:
  static std::string join(const std::string& a, const std::string& b) { return b.empty() ? a : a + " " + b; }
  std::string full(const std::string& key) const {
    std::string p;
    for (const auto& s : prefix_) p += (p.empty() ? "" : ".") + s;
    if (key.empty()) return p;
    return p.empty() ? key : p + "." + key;
  }
  void add(const char* key, const std::string& type, const std::string& def, const char* doc) {
    out_ << "  " << full(key) << "  (" << type << ", default " << def << ")\n      " << doc << "\n";
  }
  std::vector<std::string> prefix_;
  std::ostringstream out_;
};

}  // namespace

void read_options(const ConfigDocument& doc, const std::function<void(ConfigVisitor&)>& visit) {
  if (!doc.json.is_object()) fail(doc.source_of(""), ": configuration must be a JSON object");
  JsonReader reader(doc);
  visit(reader);
  reader.finish();
}

nlohmann::ordered_json write_options(const std::function<void(ConfigVisitor&)>& visit) {
  JsonWriter writer;
  visit(writer);
  return writer.result();
}

std::string document_options(const std::function<void(ConfigVisitor&)>& visit) {
  DocWriter writer;
  visit(writer);
  return writer.result();
}

}  // namespace isplat
