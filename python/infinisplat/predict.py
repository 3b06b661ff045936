"""One photo -> Gaussians with a trained checkpoint (as `infinisplat predict` makes them), and PLY files."""
from dataclasses import dataclass
from typing import Optional, Sequence, Union

import torch

from . import _C


@dataclass
class Gaussians:
    """A set of N Gaussians, activated values as render() takes them (gsplat's conventions).

    means [N, 3] metres; quats [N, 4] (w, x, y, z); scales [N, 3] metres (not log); opacities [N] in [0, 1]
    (not logits); colors [N, 3] RGB in [0, 1], linear when `linear_rgb` (else sRGB). A prediction also holds the
    source camera, in which the photo was seen: K [3, 3] at width x height (the working size), T_cw = identity.
    """
    means: torch.Tensor
    quats: torch.Tensor
    scales: torch.Tensor
    opacities: torch.Tensor
    colors: torch.Tensor
    linear_rgb: bool = True
    K: Optional[torch.Tensor] = None
    width: int = 0
    height: int = 0

    def __len__(self) -> int:
        return self.means.shape[0]

    def render_args(self) -> tuple:
        """(means, quats, scales, opacities, colors): the first five arguments of render()."""
        return self.means, self.quats, self.scales, self.opacities, self.colors


class Predictor:
    """A trained checkpoint (.safetensors) loaded once, ready to turn photos into Gaussians.

    Args:
        checkpoint: path of the checkpoint.
        overrides: model config keys to change, as the CLI's --set ("prior.type=dataset").
    """

    def __init__(self, checkpoint: str, overrides: Sequence[str] = ()):
        if not isinstance(checkpoint, str):
            raise TypeError(f"Predictor: checkpoint must be a path (str), got {type(checkpoint).__name__}")
        self._p = _C.Predictor(checkpoint, list(overrides))

    @property
    def prior_type(self) -> str:
        """The depth prior the model was trained with: "dataset" (needs `depth`), "learned", ..."""
        return self._p.prior_type

    def predict(
        self,
        image: Union[str, torch.Tensor],
        fx: Optional[float] = None,
        fy: Optional[float] = None,
        cx: Optional[float] = None,
        cy: Optional[float] = None,
        hfov: Optional[float] = None,
        depth: Optional[torch.Tensor] = None,
        width: int = 0,
        height: int = 0,
        seed: int = 0,
        view_floor: Optional[float] = None,
        prune_opacity: Optional[float] = None,
        prune_contribution: Optional[float] = None,
        prune_views: Optional[int] = None,
        keep_outside: bool = False,
    ) -> Gaussians:
        """Predicts the Gaussians of one photo, in its camera's frame (OpenCV axes, metres).

        The defaults are `infinisplat predict`'s, which gives the same Gaussians on the same photo at the same thread
        count (set_num_threads; the dense head's convolutions differ in the last bit across counts); None takes them
        from the C++ side, where the CLI's are defined (`infinisplat predict --help` lists them).

        Args:
            image: the photo: a path (PNG/JPG/..., its EXIF may give the focal length) or sRGB in [0, 1] as a float
                tensor [3, H, W] (as load_image returns it).
            fx, fy, cx, cy: intrinsics in photo pixels (fy = fx, principal point at the centre by default). Without
                fx: the EXIF 35 mm focal length, else `hfov`, else the checkpoint's prior.hfov_deg.
            hfov: horizontal field of view in degrees, when neither fx nor EXIF gives it.
            depth: metric planar depth in metres [H', W'] of the photo's view (any size of its aspect; 0 = none),
                for a checkpoint whose prior reads it (prior_type "dataset").
            width, height: working size, multiples of 16 (default: the training resolution's area at the photo's
                aspect).
            seed: the sampler's seed.
            view_floor: no Gaussian narrower than this many working-size pixels (0 = the checkpoint's own floor).
            prune_opacity: drop Gaussians below this opacity.
            prune_contribution: drop Gaussians whose largest rendered weight in the source and `prune_views` nearby
                views stays below this (0 = off).
            prune_views: 0, 2, 4 or 6 nearby views for prune_contribution.
            keep_outside: keep Gaussians whose centre leaves the source view.

        Returns:
            Gaussians with K, width and height of the working size (T_cw is the identity).
        """
        if not isinstance(image, (str, torch.Tensor)):
            raise TypeError(f"predict: image must be a path or a tensor [3, H, W], got {type(image).__name__}")
        if isinstance(image, torch.Tensor) and (image.dim() != 3 or image.shape[0] != 3):
            raise ValueError(f"predict: image must be [3, H, W], got {list(image.shape)}")
        if depth is not None and not isinstance(depth, torch.Tensor):
            raise TypeError(f"predict: depth must be a tensor [H, W], got {type(depth).__name__}")
        means, quats, scales, opacities, colors, K, w, h = self._p.predict(
            image, fx, fy, cx, cy, hfov, depth, width, height, seed, view_floor, prune_opacity, prune_contribution,
            prune_views, keep_outside)
        return Gaussians(means, quats, scales, opacities, colors, self._p.linear_rgb, K, w, h)


def save_ply(path: str, gaussians: Gaussians, sh_degree: int = 0) -> None:
    """Writes the standard 3DGS PLY that viewers read (log scales, logit opacities, SH DC of sRGB colours).

    sh_degree > 0 adds the f_rest_* properties as zeros (some viewers open only degree-3 files).
    """
    g = gaussians
    _C.write_ply(path, g.means, g.quats, g.scales, g.opacities, g.colors, g.linear_rgb, sh_degree)


def load_ply(path: str, linear_rgb: bool = True) -> Gaussians:
    """Reads a 3DGS PLY as activated values, colours in linear RGB (or sRGB when linear_rgb is False)."""
    means, quats, scales, opacities, colors = _C.read_ply(path, linear_rgb)
    return Gaussians(means, quats, scales, opacities, colors, linear_rgb)


def load_image(path: str) -> torch.Tensor:
    """Reads an 8/16-bit grey, RGB or RGBA image as float32 sRGB in [0, 1], [3, H, W]."""
    return _C.read_image(path)


def load_depth(path: str) -> torch.Tensor:
    """Reads a depth EXR (channel Z, else Y, R or the only one) as float32 [H, W], 0 where invalid."""
    return _C.read_depth(path)


def save_image(path: str, image: torch.Tensor) -> None:
    """Writes float sRGB [3, H, W] (clamped to [0, 1]) as PNG or JPG, by the path's extension."""
    if not isinstance(image, torch.Tensor):
        raise TypeError(f"save_image: image must be a tensor [3, H, W], got {type(image).__name__}")
    _C.write_image(path, image.detach())
