// `infinisplat-eval --config configs/eval_X.json [--pairs-only]`: the paper's evaluation protocol.
#include <iostream>

#include "core/app.h"
#include "core/error.h"
#include "core/log.h"
#include "eval/evaluator.h"

int main(int argc, char** argv) {
  using namespace isplat;
  return run_main("infinisplat-eval", [&] {
    EvalConfig config;
    CommonArgs common;
    bool pairs_only = false;
    ArgParser args("infinisplat-eval",
                   "Draw the baseline-binned pair manifests (512 pairs per dataset) and score every "
                   "configured method on them: masked PSNR, SSIM and LPIPS, timings, reports. "
                   "Re-running resumes where the last run stopped.");
    common.add_to(args);
    args.flag("--pairs-only", pairs_only, "write the manifests and stop");
    args.epilog("example: infinisplat-eval --config configs/eval_synthetic.json --set scoring.max_per_bin=8");
    if (!start_app(args, common, config, argc, argv)) return 0;
    Evaluator(config).run(pairs_only);
    return 0;
  });
}
