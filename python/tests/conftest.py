"""Shared fixtures: small random scenes, and a tiny checkpoint trained for one step by the C++ tools."""
import json
import math
import os
import shutil
import subprocess
import tempfile

import pytest
import torch

import infinisplat


def make_scene(n=8, width=12, height=10, dtype=torch.float64, seed=0):
    """n Gaussians in front of an identity camera, each well inside the view and at its own depth."""
    g = torch.Generator().manual_seed(seed)
    z = 2.0 + 0.25 * torch.arange(n, dtype=dtype)  # distinct depths: the order never flips under a small step
    xy = (torch.rand(n, 2, generator=g, dtype=dtype) - 0.5) * 0.8 * z[:, None]
    means = torch.cat([xy, z[:, None]], 1)
    quats = torch.randn(n, 4, generator=g, dtype=dtype)
    scales = 0.08 + 0.15 * torch.rand(n, 3, generator=g, dtype=dtype)
    opacities = 0.3 + 0.5 * torch.rand(n, generator=g, dtype=dtype)
    colors = torch.rand(n, 3, generator=g, dtype=dtype)
    f = 0.9 * width
    K = torch.tensor([[f, 0.0, width / 2], [0.0, f, height / 2], [0.0, 0.0, 1.0]], dtype=dtype)
    T_cw = torch.eye(4, dtype=dtype)
    return dict(means=means, quats=quats, scales=scales, opacities=opacities, colors=colors, K=K, T_cw=T_cw,
                width=width, height=height)


@pytest.fixture
def scene():
    return make_scene()


def _tool(name):
    cli = os.environ.get("ISPLAT_CLI")
    if not cli:
        pytest.skip("ISPLAT_CLI (the built `infinisplat`) is not set; ctest sets it")
    return cli if name == "infinisplat" else os.path.join(os.path.dirname(cli), name)


@pytest.fixture(scope="session")
def workdir():
    root = os.environ.get("ISPLAT_TEST_TMP") or tempfile.gettempdir()
    os.makedirs(root, exist_ok=True)
    path = tempfile.mkdtemp(prefix="pytest_", dir=root)
    yield path
    shutil.rmtree(path, ignore_errors=True)


@pytest.fixture(scope="session")
def tiny(workdir):
    """A generated dataset and a checkpoint of a tiny model (dataset-depth prior) after one training step."""
    cli, train = _tool("infinisplat"), _tool("infinisplat-train")
    gen = {"generate": {"out": "data", "seed": 3, "train_scenes": 1, "val_scenes": 1, "test_scenes": 0, "frames": 6,
                        "width": 64, "height": 48, "supersample": 1, "tilt_shift_every": 0,
                        "eval_datasets": ["courtyard_colmap"], "eval_scenes": 1, "eval_frames": 4,
                        "eval_width": 64, "eval_height": 48}}
    cfg = {"runtime": {"seed": 3},
           "data": {"hypersim": {"root": "data/hypersim"}, "workers": 0, "val_tuples": 1,
                    "tuples": {"width": 48, "height": 32, "targets": 1, "window": 4}},
           "model": {"prior": {"type": "dataset"},  # the default model with a tiny ViT
                     "encoder": {"vit": {"size": "custom", "embed_dim": 32, "depth": 1, "heads": 2}}},
           "loss": {"perceptual": 0}, "optim": {"lr": 3e-3, "warmup": 1},
           "train": {"out": "run", "steps": 1, "val_every": 1000, "checkpoint_every": 1000, "val_images": 0}}
    for name, content in (("gen.json", gen), ("train.json", cfg)):
        with open(os.path.join(workdir, name), "w") as f:
            json.dump(content, f)
    for cmd in ([cli, "generate", "--config", "gen.json"], [train, "--config", "train.json"]):
        subprocess.run(cmd, cwd=workdir, check=True, stdout=subprocess.DEVNULL)
    scene = os.path.join(workdir, "data/eval/courtyard_colmap/scene_0")
    return dict(cli=cli, dir=workdir, checkpoint=os.path.join(workdir, "run/checkpoints/last.safetensors"),
                image=os.path.join(scene, "images/IMG_0002.jpg"), depth=os.path.join(scene, "depth/IMG_0002.exr"))
