// Rebuilding a model from a checkpoint: its stored config gives the architecture, then the weights load.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "io/checkpoint.h"
#include "model/infinisplat.h"

namespace isplat {

// The model defaults a checkpoint was trained under, from its metadata's "config_version": 1 (no key, every
// checkpoint written before 2026-12-06) is the paper release's sampler and composer; 2 is area sampling with the lab's
// edge supports and the implicit decoder; 3 is pixel-centre supports with the silhouette supports and the dense head
// (lab/README.md). A key that a stored config lacks takes its version's default.
constexpr int kModelConfigVersion = 3;
int config_version(const Checkpoint& ck, const std::string& source);
ModelOptions model_defaults(int config_version);

// The "model" section of the training config stored in a checkpoint, over its version's defaults, with optional
// overrides ("prior.type=sparse"); unknown keys and bad values fail as for any config.
ModelOptions model_options_from_checkpoint(const Checkpoint& ck, const std::string& source,
                                           const std::vector<std::string>& overrides = {});

// A pipeline (prior + model) with the checkpoint's weights, in eval mode. A learned prior's weights embedded in the
// checkpoint are used unless the overrides set prior.learned_weights, which then wins.
std::unique_ptr<Pipeline> load_pipeline(const std::string& checkpoint_path,
                                        const std::vector<std::string>& overrides = {});
// The same from a checkpoint already in memory; `path` names it in messages.
std::unique_ptr<Pipeline> load_pipeline(const Checkpoint& ck, const std::string& path,
                                        const std::vector<std::string>& overrides = {});

}  // namespace isplat
