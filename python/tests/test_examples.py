"""The two examples run end to end at tiny sizes."""
import os
import re
import subprocess
import sys

EXAMPLES = os.path.join(os.path.dirname(__file__), "..", "examples")


def run(script, *args):
    return subprocess.run([sys.executable, os.path.join(EXAMPLES, script), *args], check=True, capture_output=True,
                          text=True).stdout


def test_fit_image(tmp_path):
    out = run("fit_image.py", "--size", "24", "--gaussians", "150", "--steps", "40", "--out", str(tmp_path / "f.png"))
    psnr = [float(x) for x in re.findall(r"PSNR (-?[\d.]+) dB", out)]
    assert len(psnr) >= 2 and psnr[-1] > psnr[0] + 3, out  # the fit improves
    assert (tmp_path / "f.png").is_file()


def test_predict_orbit(tiny, tmp_path):
    out = run("predict_orbit.py", "--checkpoint", tiny["checkpoint"], "--image", tiny["image"], "--depth",
              tiny["depth"], "--frames", "3", "--scale", "1", "--out", str(tmp_path / "orbit"))
    assert "3 frames" in out
    assert sorted(os.listdir(tmp_path / "orbit")) == ["frame_000.png", "frame_001.png", "frame_002.png", "scene.ply"]
