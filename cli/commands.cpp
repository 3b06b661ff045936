// The table of subcommands.
#include "cli/commands.h"

namespace isplat::cli {

std::map<std::string, Command> all_commands() {
  return {
      {"version", {"print versions, threads, BLAS and a matmul speed check", run_version}},
      {"generate", {"render the synthetic datasets (Hypersim layout + COLMAP/nerfstudio eval sets)", run_generate}},
  };
}

}  // namespace isplat::cli
