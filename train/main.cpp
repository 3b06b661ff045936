// `infinisplat-train --config configs/X.json [--set key=value] [--resume auto|PATH]`.
#include <iostream>

#include "core/app.h"
#include "core/error.h"
#include "core/log.h"
#include "train/trainer.h"

int main(int argc, char** argv) {
  using namespace isplat;
  return run_main("infinisplat-train", [&] {
    TrainConfig config;
    CommonArgs common;
    std::string resume;
    ArgParser args("infinisplat-train",
                   "Train the InfiniSplat model (task: gaussians) or the learned depth prior "
                   "(task: depth) from a JSON config. Ctrl-C saves a checkpoint first.");
    common.add_to(args);
    args.option("--resume", resume, "continue from a checkpoint: auto (the run folder's last) or a path", "auto|PATH");
    args.epilog(
        "examples:\n  infinisplat-train --config configs/quickstart.json\n"
        "  infinisplat-train --config configs/quickstart.json --set train.steps=50 --resume auto");
    if (!start_app(args, common, config, argc, argv)) return 0;
    Trainer trainer(config);
    if (!resume.empty()) trainer.resume(resume);
    return trainer.run();
  });
}
