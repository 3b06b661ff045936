"""The predictor gives the C++ CLI's Gaussians on the same photo and checkpoint; PLY and image files round-trip."""
import os
import subprocess

import pytest
import torch

import infinisplat


def cli_predict(tiny, out, *extra):
    # With this process's thread count: the dense head's convolutions (oneDNN) split their sums by threads, so
    # another count differs in the last bit. Debian's torch starts Python with half the cores, the CLI with all.
    subprocess.run([tiny["cli"], "predict", "--checkpoint", tiny["checkpoint"], "--image", tiny["image"], "--depth",
                    tiny["depth"], "--out", out, "--threads", str(infinisplat.num_threads()), *extra], check=True,
                   stdout=subprocess.DEVNULL)
    return infinisplat.load_ply(out)


def same(a, b):  # bit for bit: the same pipeline on the same photo and checkpoint
    for k in ("means", "quats", "scales", "opacities", "colors"):
        assert torch.equal(getattr(a, k), getattr(b, k)), k


def test_predictor_equals_cli(tiny):
    predictor = infinisplat.Predictor(tiny["checkpoint"])
    assert predictor.prior_type == "dataset"
    depth = infinisplat.load_depth(tiny["depth"])
    # The photo by path (as the CLI reads it), at the checkpoint's default field of view.
    g = predictor.predict(tiny["image"], depth=depth)
    assert len(g) > 100 and g.K.shape == (3, 3) and (g.width, g.height) == (48, 32)
    path = os.path.join(tiny["dir"], "ours.ply")
    infinisplat.save_ply(path, g)
    same(infinisplat.load_ply(path), cli_predict(tiny, os.path.join(tiny["dir"], "cli.ply")))
    # The photo as a tensor, with given intrinsics and options.
    g2 = predictor.predict(infinisplat.load_image(tiny["image"]), fx=55.0, depth=depth, seed=2, prune_opacity=0.1)
    infinisplat.save_ply(path, g2)
    cli = cli_predict(tiny, os.path.join(tiny["dir"], "cli2.ply"), "--fx", "55", "--seed", "2", "--prune-opacity",
                      "0.1")
    same(infinisplat.load_ply(path), cli)
    # The prediction renders from its own camera.
    out = infinisplat.render(*g.render_args(), g.K, torch.eye(4), g.width, g.height)
    assert out["alpha"].mean() > 0.5


def test_ply_round_trip(tmp_path, scene):
    g = infinisplat.Gaussians(*(scene[k].float() for k in ("means", "quats", "scales", "opacities", "colors")))
    g.quats = g.quats / g.quats.norm(dim=1, keepdim=True)
    path = str(tmp_path / "g.ply")
    infinisplat.save_ply(path, g)
    back = infinisplat.load_ply(path)
    assert len(back) == len(g)
    for k in ("means", "quats", "scales", "opacities", "colors"):
        torch.testing.assert_close(getattr(back, k), getattr(g, k), atol=1e-5, rtol=1e-4, msg=k)


def test_image_round_trip(tmp_path):
    image = torch.rand(3, 5, 7)
    path = str(tmp_path / "i.png")
    infinisplat.save_image(path, image)
    back = infinisplat.load_image(path)
    assert back.shape == (3, 5, 7) and (back - image).abs().max() <= 0.5 / 255 + 1e-6


def test_predictor_bad_inputs(tiny):
    predictor = infinisplat.Predictor(tiny["checkpoint"])
    depth = infinisplat.load_depth(tiny["depth"])
    image = infinisplat.load_image(tiny["image"])
    nan = image.clone()
    nan[0, 1, 1] = float("nan")
    for kwargs, error, words in (
            (dict(image=image[:2]), ValueError, "image"),
            (dict(image=nan, depth=depth), infinisplat.Error, "image"),
            (dict(image=[1, 2]), TypeError, "image"),
            (dict(image=image, depth=depth[:, :10]), infinisplat.Error, "depth"),
            (dict(image=image, depth=depth.tolist()), TypeError, "depth"),
            (dict(image=image, depth=depth, fx=-3.0), infinisplat.Error, "fx"),
            (dict(image=image, depth=depth, cy=3.0), infinisplat.Error, "give fx too"),
            (dict(image=image, depth=depth, fx=50.0, cx=1000.0), infinisplat.Error, "cx 1000 lies outside the photo"),
            (dict(image=image, depth=depth, width=40, height=32), infinisplat.Error, "width"),
            (dict(image=image, depth=depth, prune_views=3), infinisplat.Error, "prune_views")):
        with pytest.raises(error, match=words) as raised:
            predictor.predict(**kwargs)
        assert "--" not in str(raised.value), str(raised.value)  # Python's keywords, never the CLI's flags
