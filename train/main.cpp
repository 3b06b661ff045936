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
        "  infinisplat-train --config configs/quickstart.json --set train.steps=50 --resume auto\n"
        "  RANK=0 WORLD_SIZE=2 MASTER_ADDR=127.0.0.1 MASTER_PORT=29500 infinisplat-train --config ... --threads 1\n"
        "  (one rank of a data-parallel group; scripts/train_dist.sh N config.json starts N local ranks)");
    if (!start_app(args, common, config, argc, argv)) return 0;
    apply_dist_environment(config.dist);  // RANK, WORLD_SIZE, MASTER_ADDR, MASTER_PORT (scripts/train_dist.sh)
    Trainer trainer(config);
    if (!resume.empty()) trainer.resume(resume);
    return trainer.run();
  });
}
