// A small command-line parser: typed options with help text, repeatable options and positionals.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace isplat {

class ArgParser {
 public:
  ArgParser(std::string program, std::string summary);

  ArgParser& option(const std::string& name, std::string& target, const std::string& help,
                    const std::string& metavar = "VALUE");
  ArgParser& option(const std::string& name, int64_t& target, const std::string& help,
                    const std::string& metavar = "N");
  ArgParser& option(const std::string& name, double& target, const std::string& help, const std::string& metavar = "X");
  // Bounds of the numeric option added last: a given value outside [lo, hi] (or not finite) is an error naming the
  // option and its range. `why` says what the range protects ("degrees", "photo pixels"); defaults are not checked.
  ArgParser& range(double lo, double hi, const std::string& why = "");
  void flag(const std::string& name, bool& target, const std::string& help);
  void repeated(const std::string& name, std::vector<std::string>& target, const std::string& help,
                const std::string& metavar = "VALUE");
  void positional(const std::string& name, std::string& target, const std::string& help, bool required = true);
  void epilog(const std::string& text) { epilog_ = text; }

  // Parses argv[first..argc). Returns false when --help was printed (the caller should exit 0).
  // Unknown options, missing values and bad numbers throw Error.
  bool parse(int argc, char** argv, int first = 1);
  std::string help() const;

 private:
  struct Spec {
    std::string name, help, metavar;
    bool takes_value = true;
    std::function<void(const std::string&)> set;
    bool bounded = false;
    double lo = 0, hi = 0;
    std::string why{};  // what the range protects, for the message
  };
  struct Positional {
    std::string name, help;
    std::string* target;
    bool required;
  };
  const Spec* find(const std::string& name) const;

  std::string program_, summary_, epilog_;
  std::vector<Spec> specs_;
  std::vector<Positional> positionals_;
};

// Options every executable shares: a config file, overrides, printing, threads.
struct CommonArgs {
  std::string config;
  std::vector<std::string> sets;
  bool print_config = false;
  bool help_config = false;
  int64_t threads = -1;  // -1: take the config's runtime.threads
  void add_to(ArgParser& parser, bool with_config = true);
};

}  // namespace isplat
