// `infinisplat-experiment --config configs/recipe/ablation.json [--stage all|train|eval|report] [--rows a,b]
// [--variants a,b]`.
#include <sstream>

#include "core/app.h"
#include "core/error.h"
#include "core/parse.h"
#include "core/tensor_memory.h"
#include "experiment/experiment.h"

int main(int argc, char** argv) {
  isplat::count_tensor_memory();  // first, before any tensor (core/tensor_memory.h): each pair's work MB
  using namespace isplat;
  return run_main("infinisplat-experiment", [&] {
    ExperimentConfig config;
    CommonArgs common;
    std::string stage = "all", rows, seeds, variants;
    ArgParser args("infinisplat-experiment",
                   "Train every row of an ablation table from one recipe, score them all on the same pairs (RGB "
                   "prior, dataset depth and LiDAR variants) and write one report with paired bootstrap "
                   "intervals and training curves. Resumable: finished runs and scored pairs are skipped.");
    common.add_to(args);
    args.option("--stage", stage, "all | train | eval | report", "STAGE");
    args.option("--rows", rows, "comma-separated rows to train and score now (default: all)", "A,B");
    args.option("--variants", variants, "comma-separated variants to score now (default: all)", "A,B");
    args.option("--seeds", seeds, "comma-separated seeds to train now (default: every seed of a row)", "0,1");
    args.epilog(
        "examples:\n  infinisplat-experiment --config configs/recipe/ablation.json\n"
        "  infinisplat-experiment --config configs/recipe/ablation.json --rows full,pixel_supports --stage train");
    if (!start_app(args, common, config, argc, argv)) return 0;
    ISPLAT_CHECK(stage == "all" || stage == "train" || stage == "eval" || stage == "report", "--stage '", stage,
                 "' is not one of all, train, eval, report");
    const auto list = [](const std::string& csv) {
      std::vector<std::string> out;
      std::stringstream ss(csv);
      for (std::string r; std::getline(ss, r, ',');)
        if (!r.empty()) out.push_back(r);
      return out;
    };
    const std::vector<std::string> only = list(rows), only_variants = list(variants);
    std::vector<int64_t> seed_list;
    for (const std::string& x : list(seeds)) {
      const auto v = parse_int(x);
      ISPLAT_CHECK(v && *v >= 0, "--seeds: '", x, "' is not a non-negative integer");
      seed_list.push_back(*v);
    }
    Experiment experiment(config);
    if ((stage == "all" || stage == "train") && !experiment.train(only, seed_list)) return 130;
    if (stage == "all" || stage == "eval") experiment.evaluate(only, only_variants);
    if (stage == "all" || stage == "eval" || stage == "report") experiment.report();
    return 0;
  });
}
