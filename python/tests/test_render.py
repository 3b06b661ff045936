"""render() against a plain PyTorch reference, gradcheck in float64 for every input, and batching."""
import pytest
import torch

import infinisplat
from conftest import make_scene
from reference import reference_render

INPUTS = ("means", "quats", "scales", "opacities", "colors")


def args(s):
    return [s[k] for k in INPUTS + ("K", "T_cw", "width", "height")]


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
@pytest.mark.parametrize("mode", ["classic", "antialiased"])
def test_matches_reference(dtype, mode):
    s = make_scene(n=24, width=20, height=16, dtype=dtype, seed=1)
    bg = (0.2, 0.5, 0.9)
    out = infinisplat.render(*args(s), background=bg, rasterize_mode=mode)
    rgb, alpha, depth = reference_render(*args(s), background=bg, antialiased=mode == "antialiased")
    assert out["rgb"].shape == (3, 16, 20) and out["alpha"].shape == (1, 16, 20)
    assert out["rgb"].dtype == dtype and out["normal"].shape == (3, 16, 20)
    assert alpha.max() > 0.5  # the scene covers the view: the comparison is not of empty images
    for got, want in ((out["rgb"], rgb), (out["alpha"], alpha), (out["depth"], depth)):
        torch.testing.assert_close(got, want, atol=1e-5, rtol=1e-5)


def test_gradients_match_reference():
    s = make_scene(n=16, width=14, height=12, seed=2)
    ours = {k: s[k].clone().requires_grad_() for k in INPUTS}
    ref = {k: s[k].clone().requires_grad_() for k in INPUTS}
    rest = [s[k] for k in ("K", "T_cw", "width", "height")]
    w = torch.rand(3, 12, 14, dtype=torch.float64)
    out = infinisplat.render(*[ours[k] for k in INPUTS], *rest)
    ((out["rgb"] * w).sum() + out["alpha"].sum() + 0.1 * out["depth"].sum()).backward()
    rgb, alpha, depth = reference_render(*[ref[k] for k in INPUTS], *rest)
    ((rgb * w).sum() + alpha.sum() + 0.1 * depth.sum()).backward()
    for k in INPUTS:
        torch.testing.assert_close(ours[k].grad, ref[k].grad, atol=1e-5, rtol=1e-5, msg=k)


@pytest.mark.parametrize("name", INPUTS)
def test_gradcheck(name):
    s = make_scene(n=6, width=10, height=8, seed=3)
    x = s[name].clone().requires_grad_()

    def f(x):
        out = infinisplat.render(*args({**s, name: x}))
        return out["rgb"], out["alpha"], out["depth"]

    assert torch.autograd.gradcheck(f, (x,), eps=1e-6, atol=1e-5, rtol=1e-3)


def test_gradcheck_antialiased_batched():
    s = make_scene(n=4, width=8, height=6, seed=4)
    xs = [torch.stack([s[k], s[k] * 1.01]).requires_grad_() for k in INPUTS]

    def f(*xs):
        out = infinisplat.render(*xs, s["K"], s["T_cw"], 8, 6, rasterize_mode="antialiased", render_normal=False)
        return out["rgb"], out["alpha"], out["depth"]

    assert torch.autograd.gradcheck(f, tuple(xs), eps=1e-6, atol=1e-5, rtol=1e-3)


def test_batched_as_one_at_a_time():
    a, b = make_scene(seed=5), make_scene(seed=6)
    K = torch.stack([a["K"], 1.1 * b["K"]])
    K[1, 2, 2] = 1
    T = torch.stack([a["T_cw"], b["T_cw"]])
    T[1, 0, 3] = 0.1
    sets = [torch.stack([a[k], b[k]]) for k in INPUTS]
    out = infinisplat.render(*sets, K, T, 12, 10)  # set b through camera b
    assert out["rgb"].shape == (2, 3, 10, 12)
    for i, s in enumerate((a, b)):
        one = infinisplat.render(*[s[k] for k in INPUTS], K[i], T[i], 12, 10)
        for key in ("rgb", "alpha", "depth", "normal"):
            assert torch.equal(out[key][i], one[key]), key
    many = infinisplat.render(*[a[k] for k in INPUTS], K, T, 12, 10)  # one set, two cameras
    assert torch.equal(many["rgb"][1], infinisplat.render(*[a[k] for k in INPUTS], K[1], T[1], 12, 10)["rgb"])


def test_maps_left_out_and_modes(scene):
    full = infinisplat.render(*args(scene))
    lean = infinisplat.render(*args(scene), render_depth=False, render_normal=False)
    assert lean["depth"] is None and lean["normal"] is None
    assert torch.equal(full["rgb"], lean["rgb"]) and torch.equal(full["alpha"], lean["alpha"])
    plane = infinisplat.render(*args(scene), depth_mode="plane")
    assert plane["depth"].shape == full["depth"].shape and torch.equal(plane["rgb"], full["rgb"])
    far = infinisplat.render(*args(scene), near_plane=10.0)  # every Gaussian is nearer than 10 m: culled
    assert far["alpha"].abs().max() == 0


def test_simd_levels_and_threads_agree():
    s = make_scene(n=40, width=33, height=17, dtype=torch.float32, seed=7)
    assert infinisplat.simd_level() in ("portable", "avx2", "avx512")
    assert infinisplat.simd_supported() in ("portable", "avx2", "avx512")
    best = infinisplat.render(*args(s))["rgb"]
    previous = infinisplat.set_simd_level("portable")
    threads = infinisplat.num_threads()
    try:
        assert infinisplat.simd_level() == "portable"
        assert torch.equal(infinisplat.render(*args(s))["rgb"], best)
        assert infinisplat.set_num_threads(1) == 1 and infinisplat.num_threads() == 1
        assert torch.equal(infinisplat.render(*args(s))["rgb"], best)
    finally:
        infinisplat.set_simd_level(previous)
        infinisplat.set_num_threads(threads)
    assert infinisplat.simd_level() == previous
