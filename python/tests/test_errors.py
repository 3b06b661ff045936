"""Bad input raises a Python exception that names the argument; nothing crashes."""
import pytest
import torch

import infinisplat
from conftest import make_scene

INPUTS = ("means", "quats", "scales", "opacities", "colors")


def call(s, **change):
    s = {**s, **change}
    return infinisplat.render(*[s[k] for k in INPUTS + ("K", "T_cw", "width", "height")])


@pytest.mark.parametrize("name", INPUTS + ("K", "T_cw"))
def test_wrong_shape_names_the_argument(scene, name):
    with pytest.raises(ValueError, match=name):
        call(scene, **{name: scene[name][..., :2]})


@pytest.mark.parametrize("name", INPUTS + ("K", "T_cw"))
def test_nan_names_the_argument(scene, name):
    bad = scene[name].clone()
    bad.view(-1)[1] = float("nan")
    with pytest.raises(RuntimeError, match=name):
        call(scene, **{name: bad})


@pytest.mark.parametrize("name", INPUTS + ("K", "T_cw"))
def test_wrong_device_names_the_argument(scene, name):
    with pytest.raises(ValueError, match=name):
        call(scene, **{name: scene[name].to("meta")})


@pytest.mark.parametrize("name", INPUTS)
def test_wrong_type_names_the_argument(scene, name):
    with pytest.raises(TypeError, match=name):
        call(scene, **{name: scene[name].tolist()})
    with pytest.raises(TypeError, match=name):
        call(scene, **{name: scene[name].to(torch.int32)})
    with pytest.raises(TypeError, match=name):  # one dtype for every Gaussian input
        call(scene, **{name: scene[name].float()}, **({"means": scene["means"]} if name != "means" else
                                                     {"quats": scene["quats"].double()}))


def test_bad_options(scene):
    for kw, value in (("width", 0), ("height", -3), ("width", 2.5)):
        with pytest.raises(ValueError, match=kw):
            call(scene, **{kw: value})
    s = [scene[k] for k in INPUTS + ("K", "T_cw", "width", "height")]
    for kw, value in (("background", (1, 2)), ("near_plane", 0.0), ("eps2d", -1.0), ("rasterize_mode", "fast"),
                      ("depth_mode", "mean")):
        with pytest.raises(ValueError, match=kw):
            infinisplat.render(*s, **{kw: value})
    bad_K = scene["K"].clone()
    bad_K[0, 0] = -1
    with pytest.raises(infinisplat.Error, match="focal"):  # a C++ check, surfaced with its message
        call(scene, K=bad_K)
    with pytest.raises(ValueError, match="cameras"):
        call(scene, means=scene["means"].expand(3, -1, -1), quats=scene["quats"].expand(3, -1, -1),
             scales=scene["scales"].expand(3, -1, -1), opacities=scene["opacities"].expand(3, -1),
             colors=scene["colors"].expand(3, -1, -1), K=scene["K"].expand(2, -1, -1),
             T_cw=scene["T_cw"].expand(2, -1, -1))


def test_files_and_predictor_inputs(tmp_path):
    with pytest.raises(infinisplat.Error, match="nothing.safetensors"):
        infinisplat.Predictor(str(tmp_path / "nothing.safetensors"))
    with pytest.raises(TypeError, match="checkpoint"):
        infinisplat.Predictor(3)
    with pytest.raises(infinisplat.Error, match="missing.ply"):
        infinisplat.load_ply(str(tmp_path / "missing.ply"))
    (tmp_path / "broken.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 5\n")
    with pytest.raises(infinisplat.Error, match="broken.ply"):
        infinisplat.load_ply(str(tmp_path / "broken.ply"))
    with pytest.raises(infinisplat.Error, match="image"):
        infinisplat.save_image(str(tmp_path / "x.png"), torch.zeros(2, 4, 4))
