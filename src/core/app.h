// Shared start-up for executables: parse the common options, load and validate the config, apply the
// runtime (threads, seed, logging), and answer --print-config / --help-config.
#pragma once
#include <functional>
#include <iostream>

#include "core/args.h"
#include "core/config.h"
#include "core/runtime.h"

namespace isplat {

// The one failure path of every executable: keeps freed memory for reuse (keep_freed_memory), runs `body`; the
// project's Error, a LibTorch error or any other exception becomes one clean line on stderr ("<program>: error: ...")
// and exit code 1.
int run_main(const char* program, const std::function<int()>& body);

// `Options` is a root config struct with a `RuntimeOptions runtime` member.
// Returns false when the program should exit 0 (help or config printed).
template <class Options>
bool start_app(ArgParser& parser, CommonArgs& common, Options& options, int argc, char** argv, int first = 1) {
  if (!parser.parse(argc, argv, first)) return false;
  if (common.help_config) {
    std::cout << config_reference(options);
    return false;
  }
  options = load_config<Options>(common.config, common.sets);
  if (common.threads >= 0) options.runtime.threads = common.threads;
  if (common.print_config) {
    std::cout << config_to_json(options).dump(2) << "\n";
    return false;
  }
  apply_runtime(options.runtime);
  return true;
}

}  // namespace isplat
