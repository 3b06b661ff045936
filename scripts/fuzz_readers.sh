#!/usr/bin/env bash
# Mutation fuzzing of every reader reachable from the command line: seeded, bounded in time, counts crashes.
#
#   scripts/fuzz_readers.sh [BUILD_DIR] [SECONDS] [SEED]      (defaults: build 300 1)
#
# It generates a tiny dataset, a one-step checkpoint, a PLY and an evaluation with the tools in BUILD_DIR,
# then mutates those valid files (bit flips, overwritten and interesting bytes, truncation; for JSON and
# text: wrong types, huge and deep values, deleted keys, bad tokens) and runs the tool that reads each one.
# A run is fine when it exits 0 or 1 (1: an error message). A crash is a signal, another exit code or a
# timeout; exit-1 messages that name no file ("internal error", "LibTorch error", "out of memory") are
# listed as unnamed errors (unless they say what was being done: "... (while reading X)"). Crashing inputs are kept
# under the work folder, which is then not removed.
#
# Then scripts/fuzz_families.py runs its crafted families (contradictions, degenerate values, colliding outputs,
# full and read-only disks, signals, concurrency) and counts crashes, hangs, silent and unnamed cases. SECONDS = 0
# runs the families alone. The exit status is 1 when either part found anything.
set -uo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "${1:-$root/build}" && pwd)" || { echo "fuzz_readers: no build folder ${1:-build}" >&2; exit 2; }
seconds="${2:-300}"
seed="${3:-1}"
for tool in infinisplat infinisplat-train infinisplat-eval; do
  [ -x "$build/$tool" ] || { echo "fuzz_readers: $build/$tool is missing; build first" >&2; exit 2; }
done
work="$(mktemp -d "${TMPDIR:-/tmp}/fuzz_readers.XXXXXX")"
echo "fuzz_readers: tools from $build, work folder $work, $seconds s, seed $seed"

cd "$root" || exit 2
mutation=0
if [ "$seconds" != 0 ]; then
python3 - "$build" "$work" "$seconds" "$seed" <<'PYTHON'
import json, os, random, re, resource, shutil, subprocess, sys, time

build, work, seconds, seed = sys.argv[1], sys.argv[2], float(sys.argv[3]), int(sys.argv[4])
rng = random.Random(seed)
TIMEOUT = 60                      # a tiny input never takes this long: a hang
MEMORY = 6 * 1024 ** 3            # address space per run: a blind huge allocation fails instead of swapping
tool = lambda name: os.path.join(build, name)

def limit_memory():
    os.nice(10)
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY, MEMORY))

def run(cmd, log):
    """Returns (exit code or 'timeout', last stderr line)."""
    for attempt in range(30):  # a tool being rebuilt is briefly missing or busy: wait for it
        with open(log, "wb") as err:
            try:
                rc = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=err, timeout=TIMEOUT,
                                    preexec_fn=limit_memory).returncode
                break
            except subprocess.TimeoutExpired:
                rc = "timeout"
                break
            except OSError:
                time.sleep(10)
    else:
        sys.exit(f"fuzz_readers: cannot start {cmd[0]}")
    lines = [l for l in open(log, errors="replace").read().splitlines() if l.strip()]
    return rc, (lines[-1] if lines else "")

def setup(cmd, what):
    rc, last = run(cmd, os.path.join(work, "setup.log"))
    if rc != 0:
        sys.exit(f"fuzz_readers: setting up ({what}) failed: {last}")

# ---------------------------------------------------------------- valid inputs, made by the tools
data = os.path.join(work, "data")
setup([tool("infinisplat"), "generate", "--threads", "1"] + sum([["--set", f"generate.{k}={v}"] for k, v in {
    "out": data, "seed": 3, "train_scenes": 1, "val_scenes": 1, "test_scenes": 1, "frames": 8, "width": 64,
    "height": 48, "supersample": 1, "eval_scenes": 1, "eval_frames": 8, "eval_width": 64, "eval_height": 48}.items()], []),
    "generate")
hypersim = os.path.join(data, "hypersim")
colmap = os.path.join(data, "eval", "courtyard_colmap")
nerfstudio = os.path.join(data, "eval", "atrium_nerfstudio")
run_dir = os.path.join(work, "run")
tiny = {"runtime.threads": 1, "data.hypersim.root": hypersim, "data.tuples.width": 48, "data.tuples.height": 32,
        "data.tuples.targets": 1, "data.tuples.window": 4, "data.workers": 0, "data.val_tuples": 1,
        "model.prior.type": "dataset", "model.encoder.vit.size": "custom",
        "model.encoder.vit.embed_dim": 32, "model.encoder.vit.depth": 1, "model.encoder.vit.heads": 2,
        "model.encoder.cnn_branch.width": 4, "loss.perceptual": 0,
        "train.out": run_dir, "train.steps": 1, "train.val_every": 1000, "train.checkpoint_every": 1,
        "train.val_images": 0}
train_sets = sum([["--set", f"{k}={v}"] for k, v in tiny.items()], [])
setup([tool("infinisplat-train"), "--config", "configs/quickstart.json"] + train_sets, "one training step")
checkpoint = os.path.join(run_dir, "checkpoints", "last.safetensors")
photo = os.path.join(colmap, "scene_0", "images", sorted(os.listdir(os.path.join(colmap, "scene_0", "images")))[0])
photo_depth = os.path.join(colmap, "scene_0", "depth", os.path.splitext(os.path.basename(photo))[0] + ".exr")
scene_ply = os.path.join(work, "scene.ply")
predict = lambda ck, image, out: [tool("infinisplat"), "predict", "--threads", "1", "--checkpoint", ck, "--image",
                                  image, "--depth", photo_depth, "--hfov", "60", "--out", out]
setup(predict(checkpoint, photo, scene_ply), "predict")
camera_path = os.path.join(work, "path.json")
json.dump({"width": 64, "height": 48, "frames": [
    {"T_cw": [[1, 0, 0, 0.1 * i], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
     "K": [[50, 0, 32], [0, 50, 24], [0, 0, 1]]} for i in range(2)]}, open(camera_path, "w"))

def eval_config(path, datasets, out, methods=("identity",)):
    json.dump({"runtime": {"threads": 1}, "datasets": datasets,
               "protocol": {"window": 4, "min_overlap": 0.1, "pairs_per_bin": 2, "per_scene_cap": 8},
               "methods": [{"name": m, "type": m} for m in methods],
               "scoring": {"out": out, "lpips": [], "examples": 0}}, open(path, "w"))

def dataset(fmt, root):
    return {"name": f"{fmt}-set", "format": fmt, "root": root, **({"split": "test"} if fmt == "hypersim" else {})}

full_eval = os.path.join(work, "eval_full")
eval_config(os.path.join(work, "eval_full.json"),
            [dataset("colmap", colmap), dataset("nerfstudio", nerfstudio), dataset("hypersim", hypersim)], full_eval)
setup([tool("infinisplat-eval"), "--config", os.path.join(work, "eval_full.json")], "evaluation")

# ---------------------------------------------------------------- mutators
INTERESTING = [b"\x00", b"\xff", b"\x7f", b"\x80", b"\xff\xff\xff\xff", b"\x00\x00\x00\x80",
               (1 << 62).to_bytes(8, "little"), (1 << 36).to_bytes(8, "little"), b"\xff" * 8]

def mutate_bytes(b):
    b = bytearray(b)
    if not b:
        return bytes(rng.choice(INTERESTING))
    kind = rng.randrange(6)
    if kind == 0:                                   # flip a few bits
        for _ in range(rng.randint(1, 8)):
            i = rng.randrange(len(b)); b[i] ^= 1 << rng.randrange(8)
    elif kind == 1:                                 # overwrite a run with random bytes
        i = rng.randrange(len(b)); n = rng.randint(1, 64)
        b[i:i + n] = bytes(rng.randrange(256) for _ in range(min(n, len(b) - i)))
    elif kind == 2:                                 # interesting integers (sizes, counts, offsets)
        v = rng.choice(INTERESTING); i = rng.randrange(len(b)); b[i:i + len(v)] = v
    elif kind == 3:                                 # truncate
        del b[rng.randrange(len(b)):]
    elif kind == 4:                                 # duplicate a chunk
        i = rng.randrange(len(b)); n = rng.randint(1, 256); b[i:i] = b[i:i + n]
    else:                                           # zero a range
        i = rng.randrange(len(b)); n = rng.randint(1, 512); b[i:i + n] = bytes(min(n, len(b) - i))
    return bytes(b)

SPECIAL = {"__HUGE__": "1e400", "__BIG__": "1e308", "__DEEP__": "[" * 100000 + "]" * 100000,
           "__I64__": "9223372036854775808"}
JSON_VALUES = [3, "x", -1, 0, None, [], {}, True, 1e9, 100000, "__HUGE__", "__BIG__", "__DEEP__", "__I64__",
               [[1, 2]], "../../outside"]

def json_paths(node, path=()):
    yield path
    if isinstance(node, dict):
        for k, v in node.items():
            yield from json_paths(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node[:8]):
            yield from json_paths(v, path + (i,))

def mutate_json(b):
    try:
        doc = json.loads(b)
    except ValueError:
        return mutate_bytes(b)
    if rng.random() < 0.15:
        return mutate_bytes(b)
    paths = [p for p in json_paths(doc) if p]
    if not paths:
        return mutate_bytes(b)
    p = rng.choice(paths)
    parent = doc
    for k in p[:-1]:
        parent = parent[k]
    if isinstance(parent, dict) and rng.random() < 0.2:
        del parent[p[-1]]
    else:
        parent[p[-1]] = rng.choice(JSON_VALUES)
    text = json.dumps(doc)
    for marker, raw in SPECIAL.items():
        text = text.replace(f'"{marker}"', raw)
    return text.encode()

TOKENS = ["0", "-1", "nan", "inf", "1e400", "99999999999999999999", "x", "", "4611686018427387904"]

def mutate_text(b):
    if rng.random() < 0.3:
        return mutate_bytes(b)
    lines = b.decode(errors="replace").split("\n")
    i = rng.randrange(len(lines))
    words = lines[i].split(" ")
    if rng.random() < 0.2:
        del lines[i]
    else:
        words[rng.randrange(len(words))] = rng.choice(TOKENS)
        lines[i] = " ".join(words)
    return "\n".join(lines).encode()

def mutate(path):
    b = open(path, "rb").read()
    if path.endswith((".json", ".jsonl")) and not path.endswith(".jsonl"):
        out = mutate_json(b)
    elif path.endswith(".jsonl"):
        lines = b.split(b"\n")
        i = rng.randrange(len(lines))
        lines[i] = mutate_json(lines[i]) if lines[i] else mutate_bytes(lines[i])
        out = b"\n".join(lines)
    elif path.endswith((".txt", ".csv")):
        out = mutate_text(b)
    else:
        out = mutate_bytes(b)
    open(path, "wb").write(out)

# ---------------------------------------------------------------- targets: copy, mutate one file, run its reader
def files_under(folder, *exts):
    return sorted(os.path.join(d, f) for d, _, fs in os.walk(folder) for f in fs if f.endswith(exts))

def eval_target(fmt, source, exts, prefer_text=False):
    def run_case(case):
        root = os.path.join(case, "root")
        shutil.copytree(source, root, symlinks=False)
        candidates = files_under(root, *exts)
        victim = rng.choice(candidates)
        if prefer_text and victim.endswith(".txt"):          # COLMAP reads .bin first: make it read the text
            for f in files_under(root, ".bin"):
                os.remove(f)
        mutate(victim)
        cfg = os.path.join(case, "eval.json")
        eval_config(cfg, [dataset(fmt, root)], os.path.join(case, "out"))
        return victim, [tool("infinisplat-eval"), "--config", cfg, "--pairs-only"]
    return run_case

def copy_mutate(src, case, name=None):
    dst = os.path.join(case, name or os.path.basename(src))
    shutil.copy(src, dst)
    mutate(dst)
    return dst

def config_target(exe, src):
    def run_case(case):
        m = copy_mutate(src, case)
        return m, [tool(exe), "--config", m, "--print-config"]
    return run_case

def predict_checkpoint(case):
    m = copy_mutate(checkpoint, case)
    return m, predict(m, photo, os.path.join(case, "x.ply"))

def predict_image(case):
    src = rng.choice([photo, files_under(os.path.join(nerfstudio, "scene_0"), ".png")[0]])
    m = copy_mutate(src, case)
    return m, predict(checkpoint, m, os.path.join(case, "x.ply"))

def predict_depth(case):
    m = copy_mutate(photo_depth, case)
    cmd = predict(checkpoint, photo, os.path.join(case, "x.ply"))
    cmd[cmd.index(photo_depth)] = m
    return m, cmd

def resume_checkpoint(case):
    m = copy_mutate(checkpoint, case)
    out = os.path.join(case, "run")
    sets = sum([["--set", f"{k}={v}"] for k, v in {**tiny, "train.out": out, "train.steps": 2}.items()], [])
    return m, [tool("infinisplat-train"), "--config", "configs/quickstart.json", "--resume", m] + sets

def render_ply(case):
    m = copy_mutate(scene_ply, case, "scene.ply")
    shutil.copy(os.path.splitext(scene_ply)[0] + ".camera.json", os.path.join(case, "scene.camera.json"))
    return m, [tool("infinisplat"), "render", "--threads", "1", "--ply", m, "--trajectory", "orbit",
               "--frames", "1", "--out", os.path.join(case, "frames")]

def render_camera(case):
    m = copy_mutate(os.path.splitext(scene_ply)[0] + ".camera.json", case, "scene.camera.json")
    return m, [tool("infinisplat"), "render", "--threads", "1", "--ply", scene_ply, "--camera", m,
               "--trajectory", "orbit", "--frames", "1", "--out", os.path.join(case, "frames")]

def render_path(case):
    m = copy_mutate(camera_path, case)
    return m, [tool("infinisplat"), "render", "--threads", "1", "--ply", scene_ply, "--trajectory", m,
               "--out", os.path.join(case, "frames")]

def eval_outputs(pattern):
    def run_case(case):
        out = os.path.join(case, "out")
        shutil.copytree(full_eval, out)
        victim = rng.choice([f for f in files_under(out, ".json", ".jsonl") if re.search(pattern, f)])
        mutate(victim)
        cfg = os.path.join(case, "eval.json")
        eval_config(cfg, [dataset("colmap", colmap), dataset("nerfstudio", nerfstudio), dataset("hypersim", hypersim)],
                    out)
        return victim, [tool("infinisplat-eval"), "--config", cfg]
    return run_case

targets = {
    "train config": config_target("infinisplat-train", "configs/quickstart.json"),
    "eval config": config_target("infinisplat-eval", "configs/eval_synthetic.json"),
    "nerfstudio transforms.json": eval_target("nerfstudio", nerfstudio, ("transforms.json",)),
    "nerfstudio 16-bit depth": eval_target("nerfstudio", nerfstudio, (".png",)),
    "COLMAP binary": eval_target("colmap", colmap, (".bin",)),
    "COLMAP text": eval_target("colmap", colmap, (".txt",), prefer_text=True),
    "EXR depth": eval_target("colmap", colmap, (".exr",)),
    "EXR depth (predict)": predict_depth,
    "Hypersim HDF5": eval_target("hypersim", hypersim, (".hdf5",)),
    "Hypersim CSV": eval_target("hypersim", hypersim, (".csv",)),
    "checkpoint (predict)": predict_checkpoint,
    "checkpoint (resume)": resume_checkpoint,
    "image (predict)": predict_image,
    "PLY (render)": render_ply,
    "scene camera JSON": render_camera,
    "camera path JSON": render_path,
    "manifest": eval_outputs(r"manifest\.json$"),
    "results log": eval_outputs(r"results_.*\.jsonl$"),
}

# ---------------------------------------------------------------- the loop
stats = {name: {"runs": 0, "crashes": 0, "unnamed": 0} for name in targets}
crashes, unnamed = [], []
start, n = time.time(), 0
names = list(targets)
while time.time() - start < seconds:
    name = names[n % len(names)]
    case = os.path.join(work, "cases", f"{n:05d}")
    os.makedirs(case)
    victim, cmd = targets[name](case)
    rc, last = run(cmd, os.path.join(case, "stderr.txt"))
    stats[name]["runs"] += 1
    if rc not in (0, 1):
        stats[name]["crashes"] += 1
        crashes.append((name, rc, victim, last))
        open(os.path.join(case, "command.txt"), "w").write(" ".join(cmd) + "\n")
    else:
        if rc == 1 and re.search(r"internal error|LibTorch error|out of memory", last) and "(while " not in last:
            stats[name]["unnamed"] += 1
            unnamed.append((name, victim, last))
            open(os.path.join(case, "command.txt"), "w").write(" ".join(cmd) + "\n")
        else:
            shutil.rmtree(case)
    n += 1

print(f"\n{'reader':30s} {'runs':>5s} {'crashes':>8s} {'unnamed':>8s}")
for name, s in stats.items():
    print(f"{name:30s} {s['runs']:5d} {s['crashes']:8d} {s['unnamed']:8d}")
total = sum(s["runs"] for s in stats.values())
print(f"{'total':30s} {total:5d} {len(crashes):8d} {len(unnamed):8d}")
for name, rc, victim, last in crashes:
    print(f"CRASH  {name}: exit {rc}: {victim}\n       {last[:300]}")
for name, victim, last in unnamed:
    print(f"UNNAMED {name}: {victim}\n       {last[:300]}")
if crashes or unnamed:
    print(f"fuzz_readers: inputs and commands kept in {work}/cases")
else:
    shutil.rmtree(work)
hangs = sum(1 for c in crashes if c[1] == "timeout")
print(f"fuzz_readers: {len(crashes) - hangs} crashes, {hangs} hangs, {len(unnamed)} unnamed errors in {total} runs "
      f"(seed {seed}, {seconds:.0f} s)")
sys.exit(1 if crashes or unnamed else 0)
PYTHON
mutation=$?
else
  rm -rf "$work"
fi
python3 "$root/scripts/fuzz_families.py" "$build"
families=$?
[ "$mutation" = 0 ] && [ "$families" = 0 ]
