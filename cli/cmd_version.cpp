// `infinisplat version`: the startup check (LibTorch version, threads, which BLAS is loaded).
#include <iostream>

#include "cli/commands.h"
#include "core/args.h"
#include "core/runtime.h"

namespace isplat::cli {

int run_version(int argc, char** argv) {
  int64_t threads = 0;
  bool no_bench = false;
  ArgParser args("infinisplat version",
                 "Print the project and LibTorch versions, the thread count, the BLAS "
                 "library in use and a measured matmul throughput.");
  args.option("--threads", threads, "intra-op threads (0 = all cores)").range(0, kMaxThreads);
  args.flag("--no-bench", no_bench, "skip the matmul throughput measurement");
  if (!args.parse(argc, argv, 2)) return 0;
  configure_threads(threads);
  std::cout << runtime_report(!no_bench);
  return 0;
}

}  // namespace isplat::cli
