#!/usr/bin/env python3
"""Writes configs/study.json: every depth-guided row (today's fit, prompt-only, the blend; on the learned, a random
and a warped prior) beside dataset depth, clean and with the kinect preset, on the three evaluation sets; and
configs/study_seen.json: the kinect rows again with the mask from the sensor's depth (scoring.mask_depth = seen).
Usage: make_configs.py FAR   (FAR: the far rule the development scenes chose, README)"""
import json
import sys

CK = "out/experiments/display/runs/full_s0/checkpoints/last.safetensors"
SPARSE = ["variant=lidar", "prior.type=sparse"]
PROTOCOL = {"window": 10, "min_overlap": 0.6, "pairs_per_bin": 16, "per_scene_cap": 12, "seed": 0}
EVAL_SETS = [
    {"name": "rooms-heldout", "format": "hypersim", "root": "out/experiments/data/hypersim", "split": "test",
     "width": 256, "height": 192},
    {"name": "courtyard-colmap", "format": "colmap", "root": "out/experiments/data/eval/courtyard_colmap",
     "width": 384, "height": 256},
    {"name": "atrium-nerfstudio", "format": "nerfstudio", "root": "out/experiments/data/eval/atrium_nerfstudio",
     "width": 384, "height": 256},
]
PRIORS = {
    "learned": ["prior.sparse.mono=learned", "prior.learned_weights=out/densify/depth_net.safetensors"],
    "random": ["prior.sparse.mono=learned", "prior.learned_weights="],
    "warped": ["prior.sparse.mono=dataset", "prior.sparse.mono_warp=0.3"],
}


def method(name, overrides, kinect):
    m = {"name": name + ("-kinect" if kinect else ""), "type": "model", "checkpoint": CK, "overrides": overrides}
    if kinect:
        m["perturb"] = {"sensor": {"preset": "kinect"}}
    return m


def rows(far, kinect):
    out = [method("dataset", ["prior.type=dataset"], kinect)]
    for prior, o in PRIORS.items():
        out.append(method("fit-" + prior, SPARSE + o + ["prior.sparse.densify=fit", "prior.sparse.far=keep"], kinect))
    out.append(method("prompts", SPARSE + ["prior.sparse.densify=image", "prior.sparse.color_range=1", "prior.sparse.far=" + far], kinect))
    for prior, o in PRIORS.items():
        out.append(method("blend-" + prior, SPARSE + o + ["prior.sparse.densify=blend", "prior.sparse.color_range=1", "prior.sparse.far=" + far],
                          kinect))
    return out


def write(config, path):
    with open(path, "w") as f:
        f.write("{\n")
        for i, key in enumerate(config):
            value = config[key]
            if isinstance(value, list):
                f.write(' "%s": [\n' % key + ",\n".join("  " + json.dumps(v) for v in value) + "\n ]")
            else:
                f.write(' "%s": %s' % (key, json.dumps(value)))
            f.write(",\n" if i + 1 < len(config) else "\n")
        f.write("}\n")


if __name__ == "__main__":
    far = sys.argv[1]
    study = {
        "datasets": EVAL_SETS,
        "protocol": PROTOCOL,
        "methods": rows(far, False) + rows(far, True),
        "scoring": {"out": "out/densify/study", "lpips": ["squeeze"], "weights_dir": "weights", "examples": 0,
                    "max_per_bin": 1, "reference": "dataset-kinect"},
    }
    write(study, "configs/study.json")
    seen = dict(study, methods=[m for m in study["methods"] if m["name"].endswith("-kinect")],
                scoring=dict(study["scoring"], out="out/densify/study_seen", mask_depth="seen", max_per_bin=1))
    write(seen, "configs/study_seen.json")
