"""Fits Gaussians to one image with Adam through infinisplat.render (the image-fitting demo, on the CPU)."""
import argparse
import math

import torch
import torch.nn.functional as F

import infinisplat

p = argparse.ArgumentParser(description=__doc__)
p.add_argument("--image", help="target photo (default: a generated pattern)")
p.add_argument("--size", type=int, default=128, help="render width and height in pixels")
p.add_argument("--gaussians", type=int, default=3000)
p.add_argument("--steps", type=int, default=300)
p.add_argument("--out", default="fit.png")
a = p.parse_args()
torch.manual_seed(0)
if a.image:
    target = F.interpolate(infinisplat.load_image(a.image)[None], (a.size, a.size), mode="area")[0]
else:  # colour bands and a disc
    y, x = torch.meshgrid(torch.linspace(-1, 1, a.size), torch.linspace(-1, 1, a.size), indexing="ij")
    target = torch.stack([(x + 1) / 2, (torch.sin(6 * y) + 1) / 2, ((x * x + y * y) < 0.4).float()])
n, f = a.gaussians, float(a.size)  # camera at the origin looking down +z, 90 degree field of view; scene at z = 1
K = torch.tensor([[f / 2, 0, f / 2], [0, f / 2, f / 2], [0, 0, 1.0]])
means = torch.cat([torch.rand(n, 2) * 2 - 1, 1 + 0.1 * torch.rand(n, 1)], 1).requires_grad_()
log_scales = torch.full((n, 3), -0.5 * math.log(n)).requires_grad_()  # render() takes activated values: exp, sigmoid
quats = torch.randn(n, 4).requires_grad_()
opacity_logits = torch.zeros(n).requires_grad_()
color_logits = torch.zeros(n, 3).requires_grad_()
opt = torch.optim.Adam([means, log_scales, quats, opacity_logits, color_logits], lr=0.03)
for step in range(a.steps + 1):
    out = infinisplat.render(means, quats, log_scales.exp(), opacity_logits.sigmoid(), color_logits.sigmoid(),
                             K, torch.eye(4), a.size, a.size, render_depth=False, render_normal=False)
    loss = F.mse_loss(out["rgb"], target)
    if step % max(1, a.steps // 5) == 0:
        print(f"step {step:4d}  PSNR {-10 * torch.log10(loss).item():.2f} dB")
    opt.zero_grad()
    loss.backward()
    opt.step()
infinisplat.save_image(a.out, out["rgb"])
print(f"wrote {a.out} ({infinisplat.num_threads()} threads, {infinisplat.simd_level()} kernels)")
