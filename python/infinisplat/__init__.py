"""InfiniSplat-C++ from Python: a differentiable CPU Gaussian rasterizer and a one-photo predictor.

    import infinisplat
    out = infinisplat.render(means, quats, scales, opacities, colors, K, T_cw, width, height)
    out["rgb"].mean().backward()

See docs/python.md for the conventions (the same as gsplat's where both have them).
"""
import torch  # loads LibTorch before the extension module that links it

from . import _C
from ._C import Error
from .predict import Gaussians, Predictor, load_depth, load_image, load_ply, save_image, save_ply
from .render import render

__version__ = _C.__version__
__all__ = ["render", "Predictor", "Gaussians", "save_ply", "load_ply", "load_image", "save_image",
           "load_depth", "Error",
           "simd_level", "simd_supported", "set_simd_level", "num_threads", "set_num_threads"]


def simd_level() -> str:
    """The instruction set of the float32 pixel loops and projection: "avx512", "avx2" or "portable".

    float64 always runs the portable loops. Every level gives bit-identical images and gradients.
    """
    return _C.simd_level()


def simd_supported() -> str:
    """The best level this CPU has (the one in use unless set_simd_level lowered it)."""
    return _C.simd_supported()


def set_simd_level(level: str) -> str:
    """Use `level` ("portable", "avx2" or "avx512"), capped at simd_supported(); returns the previous level."""
    return _C.set_simd_level(level)


def num_threads() -> int:
    """Threads the renderer and the predictor use (LibTorch's intra-op count, the same as torch.get_num_threads())."""
    return _C.num_threads()


def set_num_threads(n: int = 0) -> int:
    """Sets the thread count (0 = every core, as the C++ tools do) and returns the count in effect."""
    return _C.set_num_threads(n)
