// `infinisplat weights`: where the pretrained weights are looked for, and which were found.
#include <filesystem>
#include <iostream>

#include "cli/commands.h"
#include "core/args.h"
#include "core/weights.h"

namespace isplat::cli {

int run_weights(int argc, char** argv) {
  bool folder_only = false;
  ArgParser args("infinisplat weights",
                 "List the folders searched for pretrained weights (in order) and the files found. Exits 0 when the "
                 "SqueezeNet features and the LPIPS-squeeze heads are found (the perceptual loss and LPIPS need "
                 "them), 1 otherwise.");
  args.flag("--folder", folder_only, "print only the folder that holds them (nothing when none does)");
  args.epilog(std::string("Get them with ") + kGetWeightsCommand + "; $" + kWeightsEnv +
              " names a folder to use first.");
  if (!args.parse(argc, argv, 2)) return 0;
  const std::string folder = find_weights_folder({kSqueezeNetFeatures, kLpipsSqueezeHeads});
  if (folder_only) {
    if (!folder.empty()) std::cout << folder << "\n";
    return folder.empty() ? 1 : 0;
  }
  std::cout << "searched, in order:\n";
  const auto path = weights_search_path();
  if (path.empty()) std::cout << "  (no folder exists)\n";
  for (const auto& dir : path) std::cout << "  " << dir << "\n";
  for (const char* file : kKnownWeights) {
    const std::string found = find_weights_file(file);
    std::cout << (found.empty() ? "  missing  " : "  found    ") << (found.empty() ? file : found) << "\n";
  }
  if (folder.empty()) {
    std::cout << "the perceptual loss and LPIPS are off: " << missing_weights_hint() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace isplat::cli
