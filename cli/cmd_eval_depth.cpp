// `infinisplat eval-depth`: AbsRel and delta < 1.25 of depth priors on datasets with reference depth.
#include "cli/commands.h"
#include "core/app.h"
#include "eval/depth_eval.h"

namespace isplat::cli {

int run_eval_depth(int argc, char** argv) {
  DepthEvalConfig config;
  CommonArgs common;
  ArgParser args("infinisplat eval-depth",
                 "Score depth priors (the learned net in any of its options, a TorchScript model, or the sparse "
                 "LiDAR variant) against the datasets' depth: AbsRel and delta < 1.25, overall and per depth "
                 "range, on evenly spaced frames. Writes report.md, report.csv and report.json.");
  common.add_to(args);
  args.epilog(
      "example: infinisplat eval-depth --config depth_eval.json --set frames=8 (keys: --help-config; "
      "docs/depth-priors.md)");
  if (!start_app(args, common, config, argc, argv, 2)) return 0;
  evaluate_depth_priors(config);
  return 0;
}

}  // namespace isplat::cli
