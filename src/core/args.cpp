// Command-line parsing with typed options and generated help.
#include "core/args.h"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "core/error.h"
#include "core/parse.h"
#include "core/runtime.h"

namespace isplat {

ArgParser::ArgParser(std::string program, std::string summary)
    : program_(std::move(program)), summary_(std::move(summary)) {}

ArgParser& ArgParser::option(const std::string& name, std::string& target, const std::string& help,
                             const std::string& metavar) {
  specs_.push_back({name, help, metavar, true, [&target](const std::string& v) { target = v; }});
  return *this;
}

ArgParser& ArgParser::option(const std::string& name, int64_t& target, const std::string& help,
                             const std::string& metavar) {
  specs_.push_back({name, help, metavar, true, [&target, name](const std::string& v) {
                      const auto parsed = parse_int(v);
                      if (!parsed) fail(name, ": expected an integer, got '", v, "'");
                      target = *parsed;
                    }});
  return *this;
}

ArgParser& ArgParser::option(const std::string& name, double& target, const std::string& help,
                             const std::string& metavar) {
  specs_.push_back({name, help, metavar, true, [&target, name](const std::string& v) {
                      const auto parsed = parse_double(v);
                      if (!parsed) fail(name, ": expected a number, got '", v, "'");
                      target = *parsed;
                    }});
  return *this;
}

ArgParser& ArgParser::range(double lo, double hi, const std::string& why) {
  ISPLAT_CHECK(!specs_.empty() && specs_.back().takes_value, program_, ": range() follows a numeric option");
  Spec& s = specs_.back();
  s.bounded = true;
  s.lo = lo, s.hi = hi, s.why = why;
  return *this;
}

void ArgParser::flag(const std::string& name, bool& target, const std::string& help) {
  specs_.push_back({name, help, "", false, [&target](const std::string&) { target = true; }});
}

void ArgParser::repeated(const std::string& name, std::vector<std::string>& target, const std::string& help,
                         const std::string& metavar) {
  specs_.push_back(
      {name, help + " (repeatable)", metavar, true, [&target](const std::string& v) { target.push_back(v); }});
}

void ArgParser::positional(const std::string& name, std::string& target, const std::string& help, bool required) {
  positionals_.push_back({name, help, &target, required});
}

const ArgParser::Spec* ArgParser::find(const std::string& name) const {
  for (const auto& s : specs_)
    if (s.name == name) return &s;
  return nullptr;
}

bool ArgParser::parse(int argc, char** argv, int first) {
  size_t next_positional = 0;
  for (int i = first; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << help();
      return false;
    }
    if (arg.rfind("--", 0) == 0 && arg.size() > 2) {
      std::string name = arg, value;
      bool inline_value = false;
      auto eq = arg.find('=');
      if (eq != std::string::npos) {
        name = arg.substr(0, eq);
        value = arg.substr(eq + 1);
        inline_value = true;
      }
      const Spec* spec = find(name);
      if (!spec) fail(program_, ": unknown option '", name, "' (see --help)");
      if (spec->takes_value) {
        if (!inline_value) {
          if (i + 1 >= argc) fail(program_, ": option ", name, " needs a value ", spec->metavar);
          value = argv[++i];
        }
      } else if (inline_value) {
        fail(program_, ": option ", name, " takes no value");
      }
      spec->set(value);
      if (spec->bounded) {  // the value as given: "nan" or "1e999" is out of every range
        const auto x = parse_double(value);
        if (!x || !std::isfinite(*x) || *x < spec->lo || *x > spec->hi)
          fail(program_, ": ", name, " ", value, " is outside its range [", spec->lo, ", ", spec->hi, "]",
               spec->why.empty() ? "" : " (" + spec->why + ")");
      }
      continue;
    }
    if (next_positional >= positionals_.size()) fail(program_, ": unexpected argument '", arg, "' (see --help)");
    *positionals_[next_positional++].target = arg;
  }
  for (size_t p = next_positional; p < positionals_.size(); ++p)
    if (positionals_[p].required) fail(program_, ": missing argument <", positionals_[p].name, "> (see --help)");
  return true;
}

std::string ArgParser::help() const {
  std::ostringstream os;
  os << "usage: " << program_;
  for (const auto& p : positionals_) os << (p.required ? " <" : " [") << p.name << (p.required ? ">" : "]");
  os << " [options]\n\n" << summary_ << "\n";
  if (!positionals_.empty()) {
    os << "\narguments:\n";
    for (const auto& p : positionals_) os << "  " << std::left << std::setw(28) << p.name << p.help << "\n";
  }
  os << "\noptions:\n";
  for (const auto& s : specs_) {
    std::string left = s.name + (s.takes_value ? " " + s.metavar : "");
    os << "  " << std::left << std::setw(28) << left;
    if (left.size() >= 28) os << "\n  " << std::string(28, ' ');
    os << s.help;
    if (s.bounded) os << " [" << s.lo << ", " << s.hi << "]";
    os << "\n";
  }
  os << "  " << std::left << std::setw(28) << "--help"
     << "show this help\n";
  if (!epilog_.empty()) os << "\n" << epilog_ << "\n";
  return os.str();
}

void CommonArgs::add_to(ArgParser& parser, bool with_config) {
  if (with_config) parser.option("--config", config, "JSON config file (keys not given take their defaults)", "FILE");
  parser.repeated("--set", sets,
                  "override a config key, e.g. --set model.sampler.budget=50000 (training) or --set "
                  "scoring.max_per_bin=8 (evaluation)",
                  "KEY=VALUE");
  parser.flag("--print-config", print_config, "print the merged configuration as JSON and exit");
  parser.flag("--help-config", help_config, "list every config key with its type, default and meaning, and exit");
  parser.option("--threads", threads, "intra-op threads (0 = all cores; default: config runtime.threads)")
      .range(0, kMaxThreads, "0 = all cores");
}

}  // namespace isplat
