// The stamp beside each method's results (<results>.method.json): what they were scored with.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "eval/eval_config.h"

namespace isplat {

// Refuses results scored with other method options (or another crack or display definition) than the config gives
// now, with other weights, or on other data. `dataset`: the manifest's dataset fingerprint (null for manifests
// written before it). Writes the stamp when there was none or an older one adopted new defaults.
void check_method_stamp(const std::string& results, const MethodOptions& mo, const ScoringOptions& scoring,
                        const nlohmann::json& dataset);

}  // namespace isplat
