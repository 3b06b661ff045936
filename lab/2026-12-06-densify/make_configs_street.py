#!/usr/bin/env python3
"""Writes the configs of the second sitting (2026-12-06): the other-style prior (a depth net trained on generated
streets, out/densify/depth_street/depth_net.safetensors) in today's fit and in the blend, clean and with the kinect
preset, and the clean decisive rows again at 4 pairs per bin.
  configs/dev_street.json:   development scenes, scoring.out out/densify/dev (the reference rows resume from there)
  configs/study_street.json: evaluation sets at 1 pair per bin, kinect, scoring.out out/densify/study (likewise)
  configs/study_seen_street.json: the same kinect rows with the mask from the sensor's depth, out/densify/study_seen
  configs/study16.json:      evaluation sets at 4 pairs per bin (16 per set), clean then kinect, no LPIPS,
                             out/densify/study16 (the clean rows ran first, the kinect rows after them)
  configs/study16_seen.json: the kinect rows at 16 per set with the mask from the sensor's depth, out/densify/study16_seen
The rows' options are those of make_configs.py (far = keep, colour range 1), so the names resume their scores.
Usage: make_configs_street.py   (from this folder)"""
from make_configs import CK, EVAL_SETS, PROTOCOL, SPARSE, method, write

LEARNED = ["prior.sparse.mono=learned", "prior.learned_weights=out/densify/depth_net.safetensors"]
STREET = ["prior.sparse.mono=learned", "prior.learned_weights=out/densify/depth_street/depth_net.safetensors"]
FIT = ["prior.sparse.densify=fit", "prior.sparse.far=keep"]
BLEND = ["prior.sparse.densify=blend", "prior.sparse.color_range=1", "prior.sparse.far=keep"]
PROMPTS = ["prior.sparse.densify=image", "prior.sparse.color_range=1", "prior.sparse.far=keep"]


# Development scenes: dev.json's names (the blend and prompt rows carry the far rule in their names there).
dev_rows = []
for kinect in (False, True):
    dev_rows += [method("dataset", ["prior.type=dataset"], kinect),
                 method("prompts-farkeep", SPARSE + PROMPTS, kinect),
                 method("fit-learned", SPARSE + LEARNED + FIT, kinect),
                 method("blend-learned-farkeep", SPARSE + LEARNED + BLEND, kinect),
                 method("fit-street", SPARSE + STREET + FIT, kinect),
                 method("blend-street-farkeep", SPARSE + STREET + BLEND, kinect)]
write({"datasets": [{"name": "rooms-val", "format": "hypersim", "root": "out/experiments/data/hypersim", "split": "val",
                     "width": 256, "height": 192}],
       "protocol": PROTOCOL, "methods": dev_rows,
       "scoring": {"lpips": ["squeeze"], "weights_dir": "weights", "examples": 0, "reference": "dataset-kinect",
                   "out": "out/densify/dev", "max_per_bin": 3}}, "configs/dev_street.json")

# Evaluation sets, kinect, 1 pair per bin: study.json's names.
study_rows = [method("dataset", ["prior.type=dataset"], True),
              method("prompts", SPARSE + PROMPTS, True),
              method("fit-learned", SPARSE + LEARNED + FIT, True),
              method("blend-learned", SPARSE + LEARNED + BLEND, True),
              method("fit-street", SPARSE + STREET + FIT, True),
              method("blend-street", SPARSE + STREET + BLEND, True)]
write({"datasets": EVAL_SETS, "protocol": PROTOCOL, "methods": study_rows,
       "scoring": {"out": "out/densify/study", "lpips": ["squeeze"], "weights_dir": "weights", "examples": 0,
                   "max_per_bin": 1, "reference": "dataset-kinect"}}, "configs/study_street.json")

write({"datasets": EVAL_SETS, "protocol": PROTOCOL, "methods": study_rows,
       "scoring": {"out": "out/densify/study_seen", "lpips": ["squeeze"], "weights_dir": "weights", "examples": 0,
                   "max_per_bin": 1, "reference": "dataset-kinect", "mask_depth": "seen"}},
      "configs/study_seen_street.json")


# Evaluation sets, 4 pairs per bin; the rows in the order they matter (the evaluator runs them in turn).
def rows16_of(kinect):
    return [method("dataset", ["prior.type=dataset"], kinect),
            method("blend-learned", SPARSE + LEARNED + BLEND, kinect),
            method("fit-learned", SPARSE + LEARNED + FIT, kinect),
            method("prompts", SPARSE + PROMPTS, kinect),
            method("fit-street", SPARSE + STREET + FIT, kinect),
            method("blend-street", SPARSE + STREET + BLEND, kinect)]


rows16 = rows16_of(False)
write({"datasets": EVAL_SETS, "protocol": PROTOCOL, "methods": rows16 + rows16_of(True),
       "scoring": {"out": "out/densify/study16", "lpips": [], "weights_dir": "weights", "examples": 0,
                   "max_per_bin": 4, "reference": "dataset"}}, "configs/study16.json")
write({"datasets": EVAL_SETS, "protocol": PROTOCOL, "methods": rows16_of(True),
       "scoring": {"out": "out/densify/study16_seen", "lpips": [], "weights_dir": "weights", "examples": 0,
                   "max_per_bin": 4, "reference": "dataset-kinect", "mask_depth": "seen"}}, "configs/study16_seen.json")
