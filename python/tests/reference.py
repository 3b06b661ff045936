"""A plain PyTorch splatting rasterizer for the tests: every pixel against every Gaussian, no tiles, autograd for
gradients. Slow and obvious, written from the rules render() documents, so it checks the C++ renderer's output."""
import torch


def _rotation(q):
    q = q / q.norm(dim=1, keepdim=True)
    w, x, y, z = q.unbind(1)
    return torch.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], 1).view(-1, 3, 3)


def _project(means, quats, scales, opacities, K, T_cw, width, height, eps2d, antialiased):
    """Screen-space means, conics, opacities and camera-space depth of each Gaussian (EWA splatting)."""
    fx, s, cx, fy, cy = K[0, 0], K[0, 1], K[0, 2], K[1, 1], K[1, 2]
    R, t = T_cw[:3, :3], T_cw[:3, 3]
    p = means @ R.T + t
    z = p[:, 2]
    M = _rotation(quats) * scales[:, None, :]
    cov = R @ (M @ M.transpose(1, 2)) @ R.T
    a, b = p[:, 0] / z, p[:, 1] / z
    # The Jacobian is taken at the mean clamped to 1.3x the image (the usual guard for off-screen Gaussians).
    bc = b.clamp((-0.15 * height - cy) / fy, (1.15 * height - cy) / fy)
    uc = (fx * a + s * bc + cx).clamp(-0.15 * width, 1.15 * width)
    ac = (uc - cx - s * bc) / fx
    zero = torch.zeros_like(z)
    J = torch.stack([fx / z, s / z, -(fx * ac + s * bc) / z, zero, fy / z, -fy * bc / z], 1).view(-1, 2, 3)
    c2 = J @ cov @ J.transpose(1, 2)
    sa, sb, sc = c2[:, 0, 0] + eps2d, c2[:, 0, 1], c2[:, 1, 1] + eps2d
    det = sa * sc - sb * sb
    o = opacities
    if antialiased:
        o = o * torch.sqrt(((sa - eps2d) * (sc - eps2d) - sb * sb) / det)
    u, v = fx * a + s * b + cx, fy * b + cy
    return u, v, sc / det, -sb / det, sa / det, o, z, det


def reference_render(means, quats, scales, opacities, colors, K, T_cw, width, height, background=(0.0, 0.0, 0.0),
                     near_plane=0.01, eps2d=0.3, antialiased=False):
    """rgb [3, H, W], alpha [1, H, W], depth [1, H, W] of one set through one camera."""
    K, T_cw = K.to(means.dtype), T_cw.to(means.dtype)
    with torch.no_grad():  # which Gaussians take part: decided without gradients, then recomputed on those only
        *_, o, z, det = _project(means, quats, scales, opacities, K, T_cw, width, height, eps2d, antialiased)
        keep = (z >= near_plane) & (scales > 0).all(1) & (opacities > 0) & (det > 0) & (255 * o > 1)
    idx = keep.nonzero().squeeze(1)
    means, quats, scales, opacities, colors = (x[idx] for x in (means, quats, scales, opacities, colors))
    u, v, A, B, C, o, z, _ = _project(means, quats, scales, opacities, K, T_cw, width, height, eps2d, antialiased)
    order = torch.sort(z.detach(), stable=True).indices  # front to back, ties by index
    u, v, A, B, C, o, z, colors = (x[order] for x in (u, v, A, B, C, o, z, colors))
    n = z.shape[0]
    ys, xs = torch.meshgrid(torch.arange(height, dtype=means.dtype) + 0.5,  # pixel centres at +0.5
                            torch.arange(width, dtype=means.dtype) + 0.5, indexing="ij")
    dx, dy = xs.reshape(-1, 1) - u, ys.reshape(-1, 1) - v  # [P, N]
    power = 0.5 * (A * dx * dx + C * dy * dy) + B * dx * dy
    g = o * torch.exp(-power)
    # 3-sigma-style cut where o * exp(-power) could still reach 1/255, capped at power 4.5; skip alpha < 1/255.
    hit = (power <= torch.log(255 * o.detach()).clamp(max=4.5)) & (g >= 1 / 255)
    alpha = torch.where(hit, g.clamp(max=0.99), torch.zeros_like(g))
    T_after = torch.cumprod(1 - alpha, 1)
    with torch.no_grad():  # stop before the Gaussian that would take T below 1e-4
        live = (torch.cumsum((T_after < 1e-4).long(), 1) == 0).to(means.dtype)
    T_before = torch.cat([torch.ones(dx.shape[0], 1, dtype=means.dtype), T_after[:, : n - 1]], 1)
    w = alpha * T_before * live
    T_final = torch.prod(1 - alpha * live, 1)
    bg = torch.tensor(background, dtype=means.dtype)
    rgb = (w @ colors + T_final[:, None] * bg).T.reshape(3, height, width)
    return rgb, (1 - T_final).reshape(1, height, width), (w @ z).reshape(1, height, width)
