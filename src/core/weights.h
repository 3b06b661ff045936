// Where pretrained weights are found: one lookup for the trainer, the evaluator, predict, export and the tests.
#pragma once
#include <string>
#include <vector>

namespace isplat {

// The environment variable naming a folder of converted weights (CI and the team's machines set it).
constexpr const char* kWeightsEnv = "INFINISPLAT_WEIGHTS";
// The command that fetches, converts and verifies them; every message about missing weights names it.
constexpr const char* kGetWeightsCommand = "scripts/get_weights.sh";
// The converted SqueezeNet-1.1 features (torchvision names), the perceptual net's and LPIPS's backbone.
constexpr const char* kSqueezeNetFeatures = "squeezenet1_1_features.safetensors";
// The LPIPS v0.1 linear heads for SqueezeNet ("LPIPS (squeeze)", the evaluator's default).
constexpr const char* kLpipsSqueezeHeads = "lpips_v0.1_squeeze_lin.safetensors";
// Every file scripts/get_weights.sh writes (weights/README.md says what each is).
constexpr const char* kKnownWeights[] = {kSqueezeNetFeatures, kLpipsSqueezeHeads, "lpips_v0.1_alex_lin.safetensors",
                                         "lpips_v0.1_vgg_lin.safetensors"};

// The folders searched, in order: $INFINISPLAT_WEIGHTS; the checkout's weights/ (found from the working
// directory, then from the running executable's folder and its parents); ~/.cache/infinisplat/weights.
// Folders that do not exist are left out.
std::vector<std::string> weights_search_path();

// A weights file from a config value or flag. A value with a folder in it ("/data/w.safetensors",
// "my/w.safetensors") is an explicit path and is returned as given, found or not; a bare file name
// ("squeezenet1_1_features.safetensors") is looked up in weights_search_path(). The old shipped form
// "weights/<name>" is a bare name when no such file exists relative to the working directory.
// Returns "" when a bare name is found nowhere.
std::string find_weights_file(const std::string& name_or_path);

// The first folder of weights_search_path() that holds every one of `files`, or "" when none does.
std::string find_weights_folder(const std::vector<std::string>& files);

// One sentence for messages: where the lookup searched and the command that gets the weights.
std::string missing_weights_hint();

}  // namespace isplat
