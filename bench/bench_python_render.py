#!/usr/bin/env python3
"""The binding's cost: the same Gaussians through infinisplat.render (Python) and through the C++ bench_render.

bench_render writes its case's Gaussians and camera (--save-scene) and times them; this script then times the same
tensors through infinisplat.render the same way (forward with every map; forward without the normal map + an L1 loss
with light depth and alpha terms + backward) and prints both and their ratio.

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/bench_python_render.py --bin-dir build [--case 100k]
"""
import argparse
import json
import os
import struct
import subprocess
import sys
import tempfile
import time

# As the C++ executables start (src/core/startup.cpp): OpenMP's idle workers spin briefly, then sleep. libgomp reads
# this when it loads, so it must be set before torch is imported.
if "OMP_WAIT_POLICY" not in os.environ and "GOMP_SPINCOUNT" not in os.environ:
    os.environ["GOMP_SPINCOUNT"] = "3000"
import torch  # noqa: E402

import infinisplat  # noqa: E402

DTYPES = {"F32": torch.float32, "F64": torch.float64, "I64": torch.int64}


def read_safetensors(path):
    with open(path, "rb") as f:
        data = f.read()
    (n,) = struct.unpack("<Q", data[:8])
    header = json.loads(data[8:8 + n])
    out = {}
    for name, info in header.items():
        if name == "__metadata__":
            continue
        begin, end = info["data_offsets"]
        raw = bytearray(data[8 + n + begin:8 + n + end])
        out[name] = torch.frombuffer(raw, dtype=DTYPES[info["dtype"]]).reshape(info["shape"]).clone()
    return out


def stat(times, use_min):
    times = sorted(times)
    return times[0] if use_min else times[len(times) // 2]


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--bin-dir", default="build", help="the CMake build folder holding bench_render")
    p.add_argument("--case", default="100k", help="bench_render's case (20k, 100k, 100k large splats, ...)")
    p.add_argument("--runs", type=int, default=15, help="timed runs of each kind in Python")
    p.add_argument("--stat", default="min", choices=["min", "median"], help="as bench_render --stat")
    a = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [os.path.join(a.bin_dir, "bench_render"), "--only", a.case, "--stat", a.stat, "--runs-scale", "2",
               "--save-scene", tmp]
        text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        row = next(line for line in text.splitlines() if line.startswith(f"| {a.case} "))
        cells = [c.strip() for c in row.strip("|").split("|")]
        cpp_fwd, cpp_fb = float(cells[6]), float(cells[7])
        s = read_safetensors(os.path.join(tmp, a.case.replace(" ", "_") + ".safetensors"))
    width, height = (int(x) for x in s["size"])
    infinisplat.set_num_threads(0)  # every core, as bench_render
    g = [s[k] for k in ("means", "quats", "scales", "opacities", "colors")]
    params = [t.clone().requires_grad_() for t in g]
    target = torch.full((3, height, width), 0.5)

    def forward():
        t0 = time.perf_counter()
        infinisplat.render(*g, s["K"], s["T_cw"], width, height)
        return (time.perf_counter() - t0) * 1e3

    def forward_backward():
        for t in params:
            t.grad = None
        t0 = time.perf_counter()
        out = infinisplat.render(*params, s["K"], s["T_cw"], width, height, render_normal=False)
        loss = (out["rgb"] - target).abs().mean() + 0.01 * out["depth"].mean() + 0.1 * out["alpha"].mean()
        loss.backward()
        return (time.perf_counter() - t0) * 1e3

    forward(), forward_backward()  # warm-up, as bench_render's first render and first forward+backward
    fwd = [forward() for _ in range(a.runs)]
    fb = [forward_backward() for _ in range(a.runs)]
    py_fwd, py_fb = stat(fwd, a.stat == "min"), stat(fb, a.stat == "min")
    print(f"case {a.case}: {len(g[0])} Gaussians, {width}x{height}, float32, {infinisplat.num_threads()} threads, "
          f"{infinisplat.simd_level()} kernels, {a.stat} of timed runs (ms)")
    print(f"{'':18}{'C++ bench_render':>18}{'Python':>10}{'Python / C++':>14}")
    print(f"{'forward':18}{cpp_fwd:18.1f}{py_fwd:10.1f}{py_fwd / cpp_fwd:14.3f}")
    print(f"{'forward+backward':18}{cpp_fb:18.1f}{py_fb:10.1f}{py_fb / cpp_fb:14.3f}")


if __name__ == "__main__":
    sys.exit(main())
