#!/usr/bin/env python3
"""Crafted reliability cases beside the mutation fuzzer (issue 74): contradictions, degenerate values, colliding
outputs, full and read-only disks, signals, concurrency. Each case states what must happen and is counted as

  crash    a signal nobody sent, or an exit code other than the expected ones
  hang     no exit within the time limit
  silent   exit 0 where the input is contradictory, or a result that is wrong, half-written or lost
  unnamed  an error whose last line names none of the files, options or keys it comes from
  refused  valid input that fails

  python3 scripts/fuzz_families.py BUILD_DIR [--keep]       (scripts/fuzz_readers.sh runs it after its loop)

Full and read-only disks are a small tmpfs mounted in a private mount namespace (unshare -m), so nothing outside
the run sees it; without that, a full disk is RLIMIT_FSIZE (ulimit -f) and the read-only cases are skipped.
Exit status 1 when any count is not 0."""
import json, os, re, resource, shutil, signal, sys, tempfile, time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fuzz_support import *  # noqa: E402,F403 (run, judge, check, record, the file surgery)
import fuzz_support  # noqa: E402

build = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "build")
keep = "--keep" in sys.argv
root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
work = tempfile.mkdtemp(prefix="fuzz_families.", dir=os.environ.get("TMPDIR", "/tmp"))
tool = lambda name: os.path.join(build, name)
isplat = tool("infinisplat")
fuzz_support.init(work, root)


# ---------------------------------------------------------------- valid inputs, made by the tools
print(f"fuzz_families: tools from {build}, work folder {work}")
data = os.path.join(work, "data")
gen = lambda out, w, h: [isplat, "generate", "--threads", "1"] + sum([["--set", f"generate.{k}={v}"] for k, v in {
    "out": out, "seed": 3, "train_scenes": 1, "val_scenes": 1, "test_scenes": 1, "frames": 8, "width": 64,
    "height": 48, "supersample": 1, "eval_scenes": 1, "eval_frames": 8, "eval_width": w, "eval_height": h}.items()], [])
setup(gen(data, 64, 48), "generate")
square = os.path.join(work, "square")
setup(gen(square, 48, 48), "generate a square evaluation set")
colmap = os.path.join(data, "eval", "courtyard_colmap")
nerfstudio = os.path.join(data, "eval", "atrium_nerfstudio")
run_dir = os.path.join(work, "run")
tiny = {"runtime.threads": 1, "data.hypersim.root": os.path.join(data, "hypersim"), "data.tuples.width": 48,
        "data.tuples.height": 32, "data.tuples.targets": 1, "data.tuples.window": 4, "data.workers": 0,
        "data.val_tuples": 1, "model.prior.type": "dataset",
        "model.encoder.vit.size": "custom", "model.encoder.vit.embed_dim": 32, "model.encoder.vit.depth": 1,
        "model.encoder.vit.heads": 2, "model.encoder.cnn_branch.width": 4,
        "loss.perceptual": 0, "train.out": run_dir, "train.steps": 1, "train.val_every": 1000,
        "train.checkpoint_every": 1, "train.val_images": 0}
train_cmd = lambda sets: [tool("infinisplat-train"), "--config", "configs/quickstart.json"] + sum(
    [["--set", f"{k}={v}"] for k, v in {**tiny, **sets}.items()], [])
setup(train_cmd({}), "one training step")
checkpoint = os.path.join(run_dir, "checkpoints", "last.safetensors")
images = sorted(os.listdir(os.path.join(colmap, "scene_0", "images")))
photo = os.path.join(colmap, "scene_0", "images", images[0])
photo_depth = os.path.join(colmap, "scene_0", "depth", os.path.splitext(images[0])[0] + ".exr")
square_depth = os.path.join(square, "eval", "courtyard_colmap", "scene_0", "depth", os.path.splitext(images[0])[0] + ".exr")
predict = lambda out, *extra, image=photo, depth=photo_depth: [
    isplat, "predict", "--threads", "1", "--checkpoint", checkpoint, "--image", image] + (
    ["--depth", depth] if depth else []) + ["--hfov", "60", "--out", out] + list(extra)
scene_ply = os.path.join(work, "scene.ply")
setup(predict(scene_ply), "predict")
scene_cam = os.path.splitext(scene_ply)[0] + ".camera.json"
render = lambda case, ply, *extra: [isplat, "render", "--threads", "1", "--ply", ply, "--trajectory", "orbit",
                                    "--frames", "2", "--out", os.path.join(case, "frames")] + list(extra)


def eval_config(path, datasets, out, methods=("identity",)):
    json.dump({"runtime": {"threads": 1}, "datasets": datasets,
               "protocol": {"window": 4, "min_overlap": 0.1, "pairs_per_bin": 2, "per_scene_cap": 8},
               "methods": [{"name": m, "type": m} for m in methods],
               "scoring": {"out": out, "lpips": [], "examples": 0}}, open(path, "w"))
    return path


def eval_on(fmt, source, change):
    """An evaluation (pairs only) of a copy of `source` after change(copy_root)."""
    def cmd(case):
        root_copy = os.path.join(case, "root")
        shutil.copytree(source, root_copy)
        change(root_copy)
        cfg = eval_config(os.path.join(case, "eval.json"), [{"name": f"{fmt}-set", "format": fmt, "root": root_copy}],
                          os.path.join(case, "out"))
        return [tool("infinisplat-eval"), "--config", cfg, "--pairs-only"]
    return cmd


def write_ply_case(case, data_bytes, name="scene.ply"):
    p = os.path.join(case, name)
    open(p, "wb").write(data_bytes)
    shutil.copy(scene_cam, os.path.splitext(p)[0] + ".camera.json")
    return p


def warned(words):
    return lambda case, rc, lines: None if any(all(w in l for w in words) for l in lines) else f"no warning {words}"


def no_output(*paths):
    def after(case, rc, lines):
        left = [p for p in paths if os.path.exists(p)] + temporaries(case)
        return f"left behind: {left}" if left else None
    return after


# ---------------------------------------------------------------- families
def contradictions():
    fam = "contradictions"
    check(fam, "COLMAP text: camera id twice", eval_on("colmap", colmap, dup_camera_text), "error",
          ["cameras.txt"])
    check(fam, "COLMAP text: image id twice", eval_on("colmap", colmap, lambda r: dup_image_text(r, False)), "error",
          ["images.txt"])
    check(fam, "COLMAP text: image name twice", eval_on("colmap", colmap, lambda r: dup_image_text(r, True)), "error",
          ["images.txt"])
    check(fam, "COLMAP binary: image id twice", eval_on("colmap", colmap, lambda r: dup_image_bin(r, "id")), "error",
          ["images.bin"])
    check(fam, "COLMAP binary: image name twice", eval_on("colmap", colmap, lambda r: dup_image_bin(r, "name")),
          "error", ["images.bin"])

    def dup_frame(j):
        f = dict(j["frames"][0])
        f["file_path"] = "./" + f["file_path"]
        j["frames"].append(f)

    def scale_rotation(j):
        for r in range(3):
            j["frames"][1]["transform_matrix"][r][0] *= 2

    def mirror(j):
        for r in range(3):
            j["frames"][1]["transform_matrix"][r][0] *= -1

    for name, fn in [("duplicated frame", dup_frame), ("scaled rotation", scale_rotation), ("mirrored rotation", mirror)]:
        check(fam, f"nerfstudio: {name}", eval_on("nerfstudio", nerfstudio, lambda r, fn=fn: ns_edit(r, fn)), "error",
              ["transforms.json"])
    check(fam, "PLY: zero quaternion", lambda c: render(c, write_ply_case(c, ply_bytes(
        50, lambda v, k: 0.0 if v == 7 and k == 13 else valid(v, k)))), "error", ["scene.ply"])
    check(fam, "PLY: log-scale overflows", lambda c: render(c, write_ply_case(c, ply_bytes(
        50, lambda v, k: 120.0 if v == 3 and k == 10 else valid(v, k)))), "error", ["scene.ply"])
    check(fam, "PLY: data after the vertices", lambda c: render(c, write_ply_case(c, ply_bytes(
        50, valid, tail=b"\0" * 68 * 3))), "ok", ["scene.ply"], after=warned(["scene.ply", "204 bytes", "3 vertices"]))
    check(fam, "predict: depth of another aspect", lambda c: predict(os.path.join(c, "x.ply"), depth=square_depth),
          "error", [square_depth], after=no_output())
    for opt, val in [("--fx", "0"), ("--fx", "-3"), ("--fx", "nan"), ("--hfov", "0"), ("--hfov", "200"),
                     ("--cx", "-1"), ("--threads", "-1"), ("--threads", "5000"), ("--width", "40"),
                     ("--prune-opacity", "1.5")]:
        extra = [opt, val] + (["--fx", "50"] if opt == "--cx" else []) + (["--height", "32"] if opt == "--width" else [])
        check(fam, f"predict {opt} {val}", lambda c, e=extra: predict(os.path.join(c, "x.ply"), *e), "error", [opt])
    check(fam, "predict --cx beyond the photo", lambda c: predict(os.path.join(c, "x.ply"), "--fx", "50", "--cx", "500"),
          "error", ["--cx"], after=no_output())
    check(fam, "predict --width without --height", lambda c: predict(os.path.join(c, "x.ply"), "--width", "64"), "error",
          ["--width"])
    for extra, opt in [(["--width", "70000", "--height", "10"], "--width"), (["--width", "60000", "--height", "60000"],
                                                                              "--width"),
                       (["--frames", "0"], "--frames"), (["--fps", "0"], "--fps"), (["--hfov", "0"], "--hfov"),
                       (["--height", "48"], "--height")]:
        check(fam, f"render {' '.join(extra)}", lambda c, e=extra: render(c, scene_ply, *e), "error", [opt])
    check(fam, "export --fov 0", lambda c: [isplat, "export", "--ply", scene_ply, "--format", "html", "--out",
                                             os.path.join(c, "x.html"), "--fov", "0"], "error", ["--fov"])
    check(fam, "export-onnx --width 40", lambda c: [isplat, "export-onnx", "--checkpoint", checkpoint, "--out",
                                                     os.path.join(c, "x.onnx"), "--width", "40"], "error", ["--width"])


def degenerate():
    fam = "degenerate"
    check(fam, "PLY: scales that underflow to 0", lambda c: render(c, write_ply_case(c, ply_bytes(
        50, lambda v, k: -200.0 if 10 <= k <= 12 else valid(v, k)))), "either", ["scene.ply"])
    check(fam, "PLY: one vertex", lambda c: render(c, write_ply_case(c, ply_bytes(1, valid))), "either", ["scene.ply"])
    check(fam, "PLY: no vertex", lambda c: render(c, write_ply_case(c, ply_bytes(0, valid))), "error", ["scene.ply"])
    check(fam, "PLY: tiny quaternion", lambda c: render(c, write_ply_case(c, ply_bytes(
        50, lambda v, k: 1e-30 if k == 13 else valid(v, k)))), "error", ["scene.ply"])

    def cam(case, change):
        p = write_ply_case(case, open(scene_ply, "rb").read())
        c = os.path.splitext(p)[0] + ".camera.json"
        j = json.load(open(c))
        change(j)
        json.dump(j, open(c, "w"))
        return render(case, p)
    check(fam, "camera JSON: fx 0", lambda c: cam(c, lambda j: j["K"][0].__setitem__(0, 0)), "error",
          ["camera.json"])
    check(fam, "camera JSON: typical depth 0", lambda c: cam(c, lambda j: j.__setitem__("typical_depth", 0)), "error",
          ["camera.json"])
    check(fam, "nerfstudio: fl_x 0", eval_on("nerfstudio", nerfstudio, lambda r: ns_edit(
        r, lambda j: j.__setitem__("fl_x", 0))), "error", ["transforms.json"])
    check(fam, "nerfstudio: w 0", eval_on("nerfstudio", nerfstudio, lambda r: ns_edit(
        r, lambda j: j.__setitem__("w", 0))), "error", ["transforms.json"])
    check(fam, "COLMAP: focal length 0", eval_on("colmap", colmap, lambda r: edit_text(
        os.path.join(colmap_text_only(r), "cameras.txt"),
        lambda t: re.sub(r"^(\d+ PINHOLE \d+ \d+) \S+", r"\1 0", t, flags=re.M))), "error", ["cameras.txt"])
    for hfov in ("1", "179"):
        check(fam, f"predict --hfov {hfov}", lambda c, h=hfov: predict(os.path.join(c, "x.ply"), "--hfov", h),
              "either", ["predict", "--hfov"])
    check(fam, "predict: prompts at depth 0", lambda c: [
        isplat, "predict", "--threads", "1", "--checkpoint", checkpoint, "--image", photo, "--out",
        os.path.join(c, "x.ply"), "--set", "prior.sparse.mono=none", "--prompts",
        write_text(os.path.join(c, "p.csv"), "u,v,z\n10,10,0\n20,20,0\n30,30,0\n")], "error", ["p.csv"])
    check(fam, "PLY: a comment holding end_header", lambda c: render(c, write_ply_case(c, ply_bytes(
        50, valid, comment="comment written before end_header\ncomment end_header\n"))), "ok", [])
    check(fam, "render: one frame", lambda c: render(c, scene_ply, "--frames", "1"), "ok", [])


def colliding():
    fam = "colliding"

    def unchanged(*paths):
        before = {p: sha(p) for p in paths}
        return lambda case, rc, lines: None if all(sha(p) == h for p, h in before.items()) else "an input changed"

    def copy_inputs(case):
        ck, ph = os.path.join(case, "ck.safetensors"), os.path.join(case, "photo.jpg")
        shutil.copy(checkpoint, ck)
        shutil.copy(photo, ph)
        return ck, ph

    for target in ("checkpoint", "image"):
        case = case_dir(fam, f"predict --out = --{target}")
        ck, ph = copy_inputs(case)
        out = ck if target == "checkpoint" else ph
        cmd = [isplat, "predict", "--threads", "1", "--checkpoint", ck, "--image", ph, "--hfov", "60", "--out", out]
        rc, lines = run(cmd, os.path.join(case, "stderr.txt"))
        verdict, detail = judge(rc, lines, "error", [out, "--out"])
        if sha(ck) != sha(checkpoint) or sha(ph) != sha(photo):
            verdict, detail = "silent", "an input was overwritten"
        record(fam, f"predict --out = --{target}", verdict, detail, case)
    case = case_dir(fam, "export --out = --ply")
    p = write_ply_case(case, open(scene_ply, "rb").read())
    h = sha(p)
    rc, lines = run([isplat, "export", "--ply", p, "--format", "ply-sh3", "--out", p], os.path.join(case, "e.txt"))
    verdict, detail = judge(rc, lines, "error", [p, "--out"])
    record(fam, "export --out = --ply", "silent" if sha(p) != h else verdict, detail, case)
    case = case_dir(fam, "render --out holds the PLY as a frame")
    frames = os.path.join(case, "frames")
    os.makedirs(frames)
    p = write_ply_case(case, open(scene_ply, "rb").read(), "frames/frame_0000.png")
    h = sha(p)
    rc, lines = run([isplat, "render", "--ply", p, "--out", frames, "--frames", "2"], os.path.join(case, "e.txt"))
    verdict, detail = judge(rc, lines, "error", ["frame_0000.png", "--out"])
    record(fam, "render --out holds the PLY as a frame", "silent" if sha(p) != h else verdict, detail, case)
    case = case_dir(fam, "train.out is an existing file")
    f = write_text(os.path.join(case, "notes.txt"), "mine")
    rc, lines = run(train_cmd({"train.out": f}), os.path.join(case, "e.txt"))
    verdict, detail = judge(rc, lines, "error", ["notes.txt", "train.out"])
    record(fam, "train.out is an existing file", "silent" if open(f).read() != "mine" else verdict, detail, case)


# ---------------------------------------------------------------- disks
def consistent_predict(case, rc, lines):
    out = os.path.join(case, "after", "out")
    left = temporaries(os.path.join(case, "after"))
    if left:
        return f"temporaries left: {left}"
    ply, cam = os.path.join(out, "x.ply"), os.path.join(out, "x.camera.json")
    if os.path.exists(ply) != os.path.exists(cam):
        return "one of the PLY and its camera JSON without the other"
    return None


def disks():
    fam = "disks"
    ns = namespace_ok()
    writers = [
        ("predict", lambda: predict("{mnt}/x.ply"), consistent_predict),
        ("render", lambda: [isplat, "render", "--threads", "1", "--ply", scene_ply, "--frames", "4", "--out",
                            "{mnt}/frames"], None),
        ("export spz", lambda: [isplat, "export", "--ply", scene_ply, "--format", "spz", "--out", "{mnt}/x.spz"], None),
        ("export-onnx", lambda: [isplat, "export-onnx", "--checkpoint", checkpoint, "--out", "{mnt}/x.onnx"], None),
        ("eval", lambda: [tool("infinisplat-eval"), "--config", eval_config(
            os.path.join(work, "disk_eval.json"), [{"name": "c", "format": "colmap", "root": colmap}], "{mnt}/ev")],
         None),
        ("train", lambda: train_cmd({"train.out": "{mnt}/run"}), None),
    ]
    for mode in ("full", "read-only"):
        for name, cmd, extra in writers:
            label = f"{mode} disk: {name}"
            case = case_dir(fam, label)
            if ns:
                c = in_tmpfs(case, cmd(), 4 if mode == "full" else 1024, readonly=mode == "read-only")
                if name == "eval":  # the config names the folder: rewrite it for this case
                    cfg = os.path.join(case, "eval.json")
                    j = json.load(open(c[c.index("--config") + 1]))
                    j["scoring"]["out"] = os.path.join(case, "mnt", "out", "ev")
                    json.dump(j, open(cfg, "w"))
                    c[c.index("--config") + 1] = cfg
                pre = limits
            elif mode == "full":
                out = os.path.join(case, "after", "out")
                os.makedirs(out)
                c = [a.replace("{mnt}", out) for a in cmd()]

                def pre():
                    limits()
                    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
                    resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))
            else:
                record(fam, label, "skipped", "no private mount namespace here", case)
                continue
            rc, lines = run(c, os.path.join(case, "stderr.txt"), pre=pre)
            if rc == 97:
                record(fam, label, "skipped", "tmpfs mount failed", case)
                continue
            verdict, detail = judge(rc, lines, "error", [os.path.join(case, "mnt", "out"), os.path.join(case, "after")])
            if verdict == "ok":
                complaint = (extra or (lambda *a: None))(case, rc, lines) or (
                    f"temporaries left: {temporaries(os.path.join(case, 'after'))}"
                    if temporaries(os.path.join(case, "after")) else None)
                if complaint:
                    verdict, detail = "silent", complaint
            record(fam, label, verdict, detail, case)


# ---------------------------------------------------------------- signals
def signals():
    fam = "signals"
    for sig, name, twice in [(signal.SIGINT, "SIGINT", False), (signal.SIGTERM, "SIGTERM", False),
                             (signal.SIGTERM, "SIGTERM twice", True)]:
        case = case_dir(fam, f"render {name}")
        out = os.path.join(case, "frames")
        log = os.path.join(case, "stderr.txt")
        proc = start([isplat, "render", "--threads", "1", "--ply", scene_ply, "--frames", "100000", "--width", "320",
                      "--height", "240", "--out", out], log)
        time.sleep(4)
        proc.send_signal(sig)
        if twice:
            time.sleep(0.05)
            proc.send_signal(sig)
        rc, lines = finish(proc, log)
        verdict, detail = judge(rc, lines, "ok", [], ok_rcs=(128 + sig,), sent=(sig,))
        video = os.path.join(out, "video.mp4")
        if verdict == "ok" and (os.path.exists(video) and not playable(video) or temporaries(case)):
            verdict, detail = "silent", f"video playable: {os.path.exists(video) and playable(video)}, " \
                                        f"temporaries: {temporaries(case)}"
        record(fam, f"render {name}", verdict, detail, case)
    big = os.path.join(work, "big.ply")
    open(big, "wb").write(ply_bytes(200000, valid))
    for delay in (0.2, 0.6, 1.2):
        case = case_dir(fam, f"export SIGTERM after {delay} s")
        out = os.path.join(case, "x.spz")
        log = os.path.join(case, "stderr.txt")
        proc = start([isplat, "export", "--ply", big, "--format", "spz", "--out", out], log)
        time.sleep(delay)
        proc.send_signal(signal.SIGTERM)
        rc, lines = finish(proc, log)
        verdict, detail = judge(rc, lines, "ok", [], ok_rcs=(0, 128 + 15), sent=(signal.SIGTERM,))
        if verdict == "ok" and temporaries(case):
            verdict, detail = "silent", f"temporaries left: {temporaries(case)}"
        record(fam, f"export SIGTERM after {delay} s", verdict, detail, case)
    for delay in (1.0, 3.0):
        case = case_dir(fam, f"predict SIGTERM after {delay} s")
        log = os.path.join(case, "stderr.txt")
        proc = start(predict(os.path.join(case, "x.ply")), log)
        time.sleep(delay)
        proc.send_signal(signal.SIGTERM)
        rc, lines = finish(proc, log)
        verdict, detail = judge(rc, lines, "ok", [], ok_rcs=(0, 128 + 15), sent=(signal.SIGTERM,))
        ply, cam = os.path.join(case, "x.ply"), os.path.join(case, "x.camera.json")
        if verdict == "ok" and (temporaries(case) or os.path.exists(ply) != os.path.exists(cam)):
            verdict, detail = "silent", "half an output or temporaries left"
        record(fam, f"predict SIGTERM after {delay} s", verdict, detail, case)
    case = case_dir(fam, "train SIGINT")
    log = os.path.join(case, "stderr.txt")
    proc = start(train_cmd({"train.out": os.path.join(case, "run"), "train.steps": 100000,
                            "train.checkpoint_every": 100000}), log)
    time.sleep(20)
    proc.send_signal(signal.SIGINT)
    rc, lines = finish(proc, log)
    verdict, detail = judge(rc, lines, "ok", [], ok_rcs=(0, 130), sent=(signal.SIGINT,))
    if verdict == "ok" and (temporaries(case) or not os.path.exists(os.path.join(case, "run", "checkpoints",
                                                                                    "last.safetensors"))):
        verdict, detail = "silent", "no checkpoint written on Ctrl-C, or temporaries left"
    record(fam, "train SIGINT", verdict, detail, case)


# ---------------------------------------------------------------- concurrency
def concurrency():
    fam = "concurrency"
    case = case_dir(fam, "two predicts into one output")
    out = os.path.join(case, "x.ply")
    procs = [start(predict(out), os.path.join(case, f"p{i}.txt")) for i in range(2)]
    results = [finish(p, os.path.join(case, f"p{i}.txt")) for i, p in enumerate(procs)]
    verdicts = [judge(rc, lines, "either", [out, "x.ply"]) for rc, lines in results]
    bad = [v for v in verdicts if v[0] != "ok"]
    verdict, detail = bad[0] if bad else ("ok", "")
    if verdict == "ok" and (temporaries(case) or not (os.path.exists(out) and os.path.exists(
            os.path.join(case, "x.camera.json")))):
        verdict, detail = "silent", "no complete output after two writers"
    record(fam, "two predicts into one output", verdict, detail, case)

    case = case_dir(fam, "two evaluations into one scoring.out")
    cfg = eval_config(os.path.join(case, "eval.json"), [{"name": "c", "format": "colmap", "root": colmap}],
                      os.path.join(case, "out"))
    procs = [start([tool("infinisplat-eval"), "--config", cfg], os.path.join(case, f"e{i}.txt")) for i in range(2)]
    results = [finish(p, os.path.join(case, f"e{i}.txt")) for i, p in enumerate(procs)]
    verdicts = [judge(rc, lines, "either", [os.path.join(case, "out")]) for rc, lines in results]
    bad = [v for v in verdicts if v[0] != "ok"]
    verdict, detail = bad[0] if bad else ("ok", "")
    if verdict == "ok":
        logs = [os.path.join(d, f) for d, _, fs in os.walk(os.path.join(case, "out")) for f in fs
                if f.startswith("results") and f.endswith(".jsonl")]
        for path in logs:
            keys = [l for l in open(path).read().splitlines() if l.strip()]
            if len(keys) != len(set(keys)):
                verdict, detail = "silent", f"duplicate lines in {path}"
    record(fam, "two evaluations into one scoring.out", verdict, detail, case)

    case = case_dir(fam, "two trainings into one train.out")
    sets = {"train.out": os.path.join(case, "run"), "train.steps": 3}
    procs = [start(train_cmd(sets), os.path.join(case, f"t{i}.txt")) for i in range(2)]
    results = [finish(p, os.path.join(case, f"t{i}.txt")) for i, p in enumerate(procs)]
    verdicts = [judge(rc, lines, "either", [os.path.join(case, "run")]) for rc, lines in results]
    bad = [v for v in verdicts if v[0] != "ok"]
    verdict, detail = bad[0] if bad else ("ok", "")
    record(fam, "two trainings into one train.out", verdict, detail, case)


families = {"contradictions": contradictions, "degenerate": degenerate, "colliding": colliding, "disks": disks,
            "signals": signals, "concurrency": concurrency}
only = [a for a in sys.argv[2:] if a in families] or list(families)
for name in only:
    print(f"{name}:", flush=True)
    families[name]()

print(f"\nfuzz_families: {counts['cases']} cases: {counts['crash']} crashes, {counts['hang']} hangs, "
      f"{counts['silent']} silent, {counts['unnamed']} unnamed, {counts['refused']} refused valid input, "
      f"{counts['skipped']} skipped")
for family, name, verdict, detail, case in failures:
    print(f"{verdict.upper():8s} {family}: {name}: {detail[:300]}\n         {case}")
bad = sum(counts[k] for k in ("crash", "hang", "silent", "unnamed", "refused"))
if bad or keep:
    print(f"fuzz_families: cases kept in {work}/cases")
else:
    shutil.rmtree(work)
sys.exit(1 if bad else 0)
