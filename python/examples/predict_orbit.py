"""Predicts a scene from one photo with a trained checkpoint and renders a small orbit around the photo's camera."""
import argparse
import math
import os

import torch
import torch.nn.functional as F

import infinisplat

p = argparse.ArgumentParser(description=__doc__)
p.add_argument("--checkpoint", required=True, help="trained checkpoint (.safetensors)")
p.add_argument("--image", required=True, help="the photo")
p.add_argument("--depth", help="metric depth EXR of the photo, for a checkpoint with the dataset prior")
p.add_argument("--frames", type=int, default=24)
p.add_argument("--radius", type=float, default=0.1, help="orbit radius as a fraction of the scene's median depth")
p.add_argument("--scale", type=float, default=2.0, help="frame size as a multiple of the working size")
p.add_argument("--out", default="orbit", help="folder for the PLY and the frames")
a = p.parse_args()

predictor = infinisplat.Predictor(a.checkpoint)
g = predictor.predict(a.image, depth=infinisplat.load_depth(a.depth) if a.depth else None)
os.makedirs(a.out, exist_ok=True)
infinisplat.save_ply(os.path.join(a.out, "scene.ply"), g)
print(f"{len(g)} Gaussians at working size {g.width}x{g.height}")

W, H = round(g.width * a.scale), round(g.height * a.scale)
K = g.K.clone()
K[:2] *= a.scale  # the same field of view at the larger size
z = g.means[:, 2].median()
target = torch.tensor([0.0, 0.0, z.item()])  # the photo's camera frame: x right, y down, z forward (OpenCV)
for i in range(a.frames):
    t = 2 * math.pi * i / a.frames
    centre = a.radius * z * torch.tensor([math.cos(t), math.sin(t), 0.0])
    forward = F.normalize(target - centre, dim=0)
    right = F.normalize(torch.linalg.cross(torch.tensor([0.0, 1.0, 0.0]), forward), dim=0)
    R_wc = torch.stack([right, torch.linalg.cross(forward, right), forward], 1)  # camera axes as columns
    T_cw = torch.eye(4)
    T_cw[:3, :3], T_cw[:3, 3] = R_wc.T, -R_wc.T @ centre
    with torch.no_grad():
        rgb = infinisplat.render(*g.render_args(), K, T_cw, W, H, background=(1, 1, 1))["rgb"]
    if g.linear_rgb:  # linear colours -> sRGB for the PNG
        rgb = torch.where(rgb <= 0.0031308, 12.92 * rgb, 1.055 * rgb.clamp(min=1e-8) ** (1 / 2.4) - 0.055)
    infinisplat.save_image(os.path.join(a.out, f"frame_{i:03d}.png"), rgb)
print(f"wrote {a.out}/scene.ply and {a.frames} frames of {W}x{H}")
