#!/usr/bin/python3
"""Converts published torch.save weight files (legacy or zip format) into the safetensors layout the project reads.

Reading is torch.load of Debian's python3-torch (the same LibTorch 1.13.1 the project links): torch's own reader of
its legacy pickle format. Writing is this file's: safetensors with a compact JSON header in the state dict's order,
padded with spaces to 8 bytes, data in that order, written atomically.

  convert_weights.py squeezenet SRC.pth DST.safetensors   torchvision's squeezenet1_1: the `features.*` tensors,
                                                           renamed without the prefix ("0.weight", "3.squeeze.bias")
  convert_weights.py lpips SRC.pth DST.safetensors        LPIPS v0.1 heads: every tensor, names as published
  convert_weights.py compare A.safetensors B.safetensors  exit 0 when both hold the same names, dtypes, shapes and
                                                           bytes (tensor for tensor), else name the first difference
"""
import json
import os
import struct
import sys
import tempfile

DTYPES = {"torch.float32": "F32", "torch.float64": "F64", "torch.float16": "F16", "torch.bfloat16": "BF16",
          "torch.int64": "I64", "torch.int32": "I32", "torch.uint8": "U8"}


def fail(msg):
    print(f"convert_weights.py: {msg}", file=sys.stderr)
    sys.exit(1)


def load_state_dict(path):
    try:
        import torch
    except ImportError:
        fail("needs Debian's python3-torch (apt-get install python3-torch; scripts/setup.sh installs it)")
    try:
        state = torch.load(path, map_location="cpu")
    except Exception as e:  # a truncated or foreign file: name it
        fail(f"{path}: not a torch.save file ({type(e).__name__}: {e})")
    if hasattr(state, "state_dict"):
        state = state.state_dict()
    if not isinstance(state, dict):
        fail(f"{path}: holds a {type(state).__name__}, not a state dict")
    return state


def select(kind, state, path):
    if kind == "lpips":
        out = dict(state)
    elif kind == "squeezenet":
        out = {k[len("features."):]: v for k, v in state.items() if k.startswith("features.")}
    else:
        fail(f"unknown kind '{kind}' (squeezenet | lpips)")
    if not out:
        fail(f"{path}: no tensors for '{kind}'")
    return out


def write_safetensors(tensors, dst):
    header, blobs, offset = {}, [], 0
    for name, t in tensors.items():
        dtype = DTYPES.get(str(t.dtype))
        if dtype is None:
            fail(f"tensor '{name}' has unsupported dtype {t.dtype}")
        data = t.detach().cpu().contiguous().numpy().tobytes()
        header[name] = {"dtype": dtype, "shape": list(t.shape), "data_offsets": [offset, offset + len(data)]}
        blobs.append(data)
        offset += len(data)
    text = json.dumps(header, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 8)
    folder = os.path.dirname(os.path.abspath(dst))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".convert.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(struct.pack("<Q", len(text)) + text)
            for b in blobs:
                f.write(b)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, dst)
    except BaseException:
        os.unlink(tmp)
        raise


def read_safetensors(path):
    with open(path, "rb") as f:
        raw = f.read()
    if len(raw) < 8:
        fail(f"{path}: too short for a safetensors file")
    (n,) = struct.unpack("<Q", raw[:8])
    if 8 + n > len(raw):
        fail(f"{path}: header length {n} runs past the end")
    header = json.loads(raw[8:8 + n])
    header.pop("__metadata__", None)
    data = raw[8 + n:]
    return {k: (v["dtype"], v["shape"], data[v["data_offsets"][0]:v["data_offsets"][1]]) for k, v in header.items()}


def compare(a, b):
    ta, tb = read_safetensors(a), read_safetensors(b)
    if list(ta) != list(tb):
        fail(f"{a} and {b} hold different tensors: {sorted(set(ta) ^ set(tb)) or 'same names, other order'}")
    for name in ta:
        if ta[name][:2] != tb[name][:2]:
            fail(f"tensor '{name}': {ta[name][:2]} in {a}, {tb[name][:2]} in {b}")
        if ta[name][2] != tb[name][2]:
            fail(f"tensor '{name}': values differ between {a} and {b}")
    print(f"identical: {len(ta)} tensors ({a} = {b})")


def main(argv):
    if len(argv) != 4 or argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if len(argv) == 2 else 2
    kind, src, dst = argv[1], argv[2], argv[3]
    if kind == "compare":
        compare(src, dst)
        return 0
    if not os.path.isfile(src):
        fail(f"{src}: no such file")
    tensors = select(kind, load_state_dict(src), src)
    write_safetensors(tensors, dst)
    print(f"converted {src} -> {dst} ({len(tensors)} tensors)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
