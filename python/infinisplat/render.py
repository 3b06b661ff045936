"""infinisplat.render: checked Python arguments in, the C++ renderer's differentiable maps out."""
import math
from typing import Dict, Optional, Sequence, Union

import torch

from . import _C

_FLOATS = (torch.float32, torch.float64)


def _tensor(name: str, value, dims: Sequence[int], last: Optional[int]) -> torch.Tensor:
    if not isinstance(value, torch.Tensor):
        raise TypeError(f"render: {name} must be a torch.Tensor, got {type(value).__name__}")
    if value.device.type != "cpu":
        raise ValueError(f"render: {name} must be on the CPU, got device {value.device}")
    if value.dtype not in _FLOATS:
        raise TypeError(f"render: {name} must be float32 or float64, got {value.dtype}")
    if value.dim() not in dims or (last is not None and value.shape[-1] != last):
        want = " or ".join(str(d) for d in dims)
        raise ValueError(f"render: {name} must have {want} dimensions" +
                         (f" and {last} in the last" if last is not None else "") + f", got shape {list(value.shape)}")
    return value


def render(
    means: torch.Tensor,
    quats: torch.Tensor,
    scales: torch.Tensor,
    opacities: torch.Tensor,
    colors: torch.Tensor,
    K: torch.Tensor,
    T_cw: torch.Tensor,
    width: int,
    height: int,
    background: Optional[Union[Sequence[float], torch.Tensor]] = None,
    near_plane: float = 0.01,
    eps2d: float = 0.3,
    rasterize_mode: str = "classic",
    depth_mode: str = "center",
    render_depth: bool = True,
    render_normal: bool = True,
) -> Dict[str, Optional[torch.Tensor]]:
    """Renders 3D Gaussians through pinhole cameras on the CPU, differentiably.

    Every Gaussian is splatted as an EWA-projected 2D Gaussian (3-sigma cut-off, alpha = min(0.99, o * G),
    fragments with alpha < 1/255 skipped, compositing front to back by the depth of the mean until the
    transmittance would fall below 1e-4). Gradients flow to means, quats, scales, opacities and colors
    (float32 or float64, all of one dtype); none flow to the cameras. The backward pass is the C++ renderer's
    analytic one (its torch.autograd.Function is the outputs' grad_fn).

    Gaussians are unbatched ([N, ...], N may differ per call) or a batch of B sets ([B, N, ...]); cameras are
    one ([3, 3] / [4, 4]) or a batch of C; a batch of sets needs one camera or C = B (set b through camera b),
    and one set seen by C cameras gives C images. Leading dims of the outputs: none, or [B] / [C].

    Args:
        means: Gaussian centres in world space, metres. [N, 3] or [B, N, 3].
        quats: rotations as quaternions (w, x, y, z), any norm (normalized inside). [N, 4] or [B, N, 4].
        scales: standard deviations along the rotated axes, metres, activated (not log). [N, 3] or [B, N, 3].
        opacities: activated opacities in [0, 1] (not logits). [N] or [B, N].
        colors: RGB per Gaussian (composited as given: linear RGB for the predictor's). [N, 3] or [B, N, 3].
        K: intrinsics [[fx, s, cx], [0, fy, cy], [0, 0, 1]] in pixels, pixel centres at (j + 0.5, i + 0.5).
            [3, 3] or [C, 3, 3].
        T_cw: world-to-camera rigid transforms (gsplat's viewmats), OpenCV axes: x right, y down, z forward.
            [4, 4] or [C, 4, 4].
        width: image width in pixels.
        height: image height in pixels.
        background: RGB behind the Gaussians, rgb += (1 - alpha) * background; 3 values, no gradient.
            Default black.
        near_plane: Gaussians whose camera-space depth is below this are culled. Default 0.01.
        eps2d: added to the diagonal of every 2D covariance, pixels^2 (a low-pass filter). Default 0.3.
        rasterize_mode: "classic" or "antialiased" (opacity compensation for the eps2d dilation, as in
            Mip-Splatting and gsplat). Default "classic".
        depth_mode: "center" (each Gaussian's mean depth, differentiable) or "plane" (where the pixel's ray meets
            the Gaussian's flattest plane; no gradient). Default "center".
        render_depth: composite the depth map. Default True.
        render_normal: composite the normal map (no gradient). Default True.

    Returns:
        A dict of channel-first maps, with the leading batch dim when batched:

        - **rgb**: sum_i w_i c_i + (1 - alpha) * background. [3, H, W] or [B, 3, H, W].
        - **alpha**: sum_i w_i, with w_i = alpha_i * T_i the compositing weights. [1, H, W].
        - **depth**: sum_i w_i z_i, camera-space z, not divided by alpha; None unless render_depth. [1, H, W].
        - **normal**: sum_i w_i n_i with n_i the shortest axis facing the camera, in camera space; no
          gradient; None unless render_normal. [3, H, W].
    """
    means = _tensor("means", means, (2, 3), 3)
    lead = means.shape[:-1]
    for name, value, last in (("quats", quats, 4), ("scales", scales, 3), ("colors", colors, 3)):
        _tensor(name, value, (means.dim(),), last)
        if value.shape[:-1] != lead:
            raise ValueError(f"render: {name} must be {list(lead) + [last]} like means, got {list(value.shape)}")
    _tensor("opacities", opacities, (means.dim() - 1,), None)
    if opacities.shape != lead:
        raise ValueError(f"render: opacities must be {list(lead)} like means, got {list(opacities.shape)}")
    for name, value in (("quats", quats), ("scales", scales), ("opacities", opacities), ("colors", colors)):
        if value.dtype != means.dtype:
            raise TypeError(f"render: {name} is {value.dtype} but means is {means.dtype}; give one dtype")
    _tensor("K", K, (2, 3), 3)
    _tensor("T_cw", T_cw, (2, 3), 4)
    if K.shape[-2] != 3 or T_cw.shape[-2] != 4:
        raise ValueError(f"render: K must be [3, 3] and T_cw [4, 4] (or batched), got {list(K.shape)} and "
                         f"{list(T_cw.shape)}")
    if K.dim() != T_cw.dim() or (K.dim() == 3 and K.shape[0] != T_cw.shape[0]):
        raise ValueError(f"render: K {list(K.shape)} and T_cw {list(T_cw.shape)} must hold the same cameras")
    if means.dim() == 3 and K.dim() == 3 and K.shape[0] != means.shape[0]:
        raise ValueError(f"render: {means.shape[0]} Gaussian sets but {K.shape[0]} cameras (K, T_cw)")
    for name, value in (("width", width), ("height", height)):
        if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
            raise ValueError(f"render: {name} must be a positive int, got {value!r}")
    if background is None:
        background = (0.0, 0.0, 0.0)
    elif isinstance(background, torch.Tensor):
        background = background.detach().reshape(-1).tolist()
    background = [float(b) for b in background]
    if len(background) != 3 or not all(math.isfinite(b) for b in background):
        raise ValueError(f"render: background must be 3 finite values, got {background}")
    if not (near_plane > 0 and math.isfinite(near_plane)):
        raise ValueError(f"render: near_plane must be > 0, got {near_plane}")
    if not (eps2d >= 0 and math.isfinite(eps2d)):
        raise ValueError(f"render: eps2d must be >= 0, got {eps2d}")
    if rasterize_mode not in ("classic", "antialiased"):
        raise ValueError(f"render: rasterize_mode must be 'classic' or 'antialiased', got {rasterize_mode!r}")
    if depth_mode not in ("center", "plane"):
        raise ValueError(f"render: depth_mode must be 'center' or 'plane', got {depth_mode!r}")
    rgb, alpha, depth, normal = _C.render(means, quats, scales, opacities, colors, K, T_cw, width, height, background,
                                          float(near_plane), float(eps2d), rasterize_mode == "antialiased",
                                          depth_mode, bool(render_depth), bool(render_normal))
    return {"rgb": rgb, "alpha": alpha, "depth": depth, "normal": normal}
