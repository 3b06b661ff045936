// `infinisplat-eval --config configs/eval_X.json [--pairs-only]`: the paper's evaluation protocol.
#include <iostream>

#include "core/app.h"
#include "core/error.h"
#include "core/log.h"
#include "core/parse.h"
#include "core/tensor_memory.h"
#include "eval/evaluator.h"

int main(int argc, char** argv) {
  isplat::count_tensor_memory();  // first, before any tensor (core/tensor_memory.h): each pair's work MB
  using namespace isplat;
  return run_main("infinisplat-eval", [&] {
    EvalConfig config;
    CommonArgs common;
    bool pairs_only = false;
    std::string shard;
    int64_t merge = 0;
    ArgParser args("infinisplat-eval",
                   "Draw the baseline-binned pair manifests (512 pairs per dataset) and score every "
                   "configured method on them: masked PSNR, SSIM and LPIPS, timings, reports. "
                   "Re-running resumes where the last run stopped.");
    common.add_to(args);
    args.flag("--pairs-only", pairs_only, "write the manifests and stop");
    args.option("--shard", shard, "score only shard i of n (every n-th pair) into its own results files", "I/N");
    args.option("--merge", merge, "combine the results of N finished shards and write the reports", "N").range(1, 1e6);
    args.epilog(
        "examples:\n  infinisplat-eval --config configs/eval_synthetic.json --set scoring.max_per_bin=8\n"
        "  infinisplat-eval --config X.json --shard 0/3   (and 1/3, 2/3 on any machines), then\n"
        "  infinisplat-eval --config X.json --merge 3");
    if (!start_app(args, common, config, argc, argv)) return 0;
    Evaluator evaluator(config);
    if (merge > 0) {
      ISPLAT_CHECK(shard.empty(), "--merge and --shard cannot be combined");
      evaluator.merge(merge);
      return 0;
    }
    if (!shard.empty()) {
      const auto slash = shard.find('/');
      const auto i = parse_int(shard.substr(0, slash)),
                 n = parse_int(slash == std::string::npos ? "" : shard.substr(slash + 1));
      ISPLAT_CHECK(i && n, "--shard '", shard, "' is not of the form i/n (e.g. 0/3)");
      evaluator.set_shard(*i, *n);
    }
    evaluator.run(pairs_only);
    return 0;
  });
}
