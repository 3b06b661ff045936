// `infinisplat generate`: writes the procedural datasets (Hypersim layout + COLMAP/nerfstudio eval sets).
#include "cli/commands.h"
#include "core/app.h"
#include "data/synth/generate.h"

namespace isplat::cli {

int run_generate(int argc, char** argv) {
  GenerateConfig config;
  CommonArgs common;
  ArgParser args("infinisplat generate",
                 "Render the embedded synthetic datasets with the built-in CPU ray tracer: training scenes in the "
                 "exact Hypersim release layout, and evaluation scenes of other styles in COLMAP and nerfstudio "
                 "layouts. Deterministic in generate.seed.");
  common.add_to(args);
  args.epilog("example: infinisplat generate --set generate.out=out/data --set generate.train_scenes=2");
  if (!start_app(args, common, config, argc, argv, 2)) return 0;
  generate_datasets(config.generate);
  return 0;
}

}  // namespace isplat::cli
