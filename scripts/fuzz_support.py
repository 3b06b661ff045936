"""Helpers of scripts/fuzz_families.py: running a tool under limits, judging its exit and last stderr line, counting,
and the file surgery that makes contradictory inputs out of valid ones."""
import hashlib, json, os, re, resource, signal, struct, subprocess

TIMEOUT = 120                     # a tiny input never takes this long: a hang
MEMORY = 6 * 1024 ** 3            # address space per run: a blind huge allocation fails instead of swapping
GENERIC = re.compile(r"internal error|LibTorch error|out of memory")
counts = {k: 0 for k in ("cases", "crash", "hang", "silent", "unnamed", "refused", "skipped")}
failures = []
work = root = ""


def init(work_dir, root_dir):
    global work, root
    work, root = work_dir, root_dir


def limits():
    # A shell's background job starts with SIGINT ignored, and children inherit that: give the tools the default.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    os.nice(10)
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY, MEMORY))


def start(cmd, log, **kw):
    return subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=open(log, "wb"), preexec_fn=kw.pop("pre", limits),
                            cwd=root or None, **kw)


def finish(proc, log, timeout=TIMEOUT):
    try:
        rc = proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        rc = "timeout"
    lines = [l for l in open(log, errors="replace").read().splitlines() if l.strip()]
    return rc, lines


def run(cmd, log, timeout=TIMEOUT, **kw):
    return finish(start(cmd, log, **kw), log, timeout)


def setup(cmd, what):
    rc, lines = run(cmd, os.path.join(work, "setup.log"))
    if rc != 0:
        sys.exit(f"fuzz_families: setting up ({what}) failed: {lines[-1] if lines else rc}")


def sha(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest() if os.path.isfile(path) else None


def temporaries(folder):
    return [os.path.join(d, f) for d, _, fs in os.walk(folder) for f in fs if ".isplat-tmp" in f]


def record(family, name, verdict, detail, case):
    counts["cases"] += 1
    if verdict != "ok":
        counts[verdict] += 1
        if verdict != "skipped":
            failures.append((family, name, verdict, detail, case))
    print(f"  {verdict:8s} {family:14s} {name}" + (f": {detail[:200]}" if verdict != "ok" else ""), flush=True)


def judge(rc, lines, expect, names, ok_rcs=(0,), sent=()):
    """expect: 'error' (exit 1 naming one of `names`), 'ok' (an exit in ok_rcs), 'either' (ok, or a named error)."""
    last = lines[-1] if lines else ""
    if rc == "timeout":
        return "hang", "no exit"
    if isinstance(rc, int) and rc < 0 and -rc not in sent:
        return "crash", f"signal {-rc}: {last}"
    named = any(n and n in last for n in names) and not (GENERIC.search(last) and "while" not in last)
    if expect == "error":
        if rc == 0:
            return "silent", "exit 0 on contradictory input"
        if rc != 1:
            return "crash", f"exit {rc}: {last}"
        return ("ok", "") if named else ("unnamed", last)
    if rc in ok_rcs or (isinstance(rc, int) and rc < 0 and -rc in sent):
        return "ok", ""
    if expect == "either" and rc == 1:
        return ("ok", "") if named else ("unnamed", last)
    if rc == 1:
        return "refused", last
    return "crash", f"exit {rc}: {last}"


def case_dir(family, name):
    d = os.path.join(work, "cases", family, re.sub(r"[^A-Za-z0-9_.-]+", "_", name))
    os.makedirs(d)
    return d


def check(family, name, cmd, expect, names, ok_rcs=(0,), after=None, timeout=TIMEOUT):
    """Runs one case; `after(case, rc, lines)` returns a complaint ('silent' kind) or None."""
    case = case_dir(family, name)
    cmd = cmd(case) if callable(cmd) else cmd
    rc, lines = run(cmd, os.path.join(case, "stderr.txt"), timeout)
    verdict, detail = judge(rc, lines, expect, names, ok_rcs)
    if verdict == "ok" and after:
        complaint = after(case, rc, lines)
        if complaint:
            verdict, detail = "silent", complaint
    record(family, name, verdict, detail, case)



def write_text(path, text):
    open(path, "w").write(text)
    return path


# ---------------------------------------------------------------- file surgery
def edit_text(path, fn):
    text = fn(open(path).read())
    open(path, "w").write(text)


def colmap_text_only(r):
    sparse = os.path.join(r, "scene_0", "sparse", "0")
    for f in os.listdir(sparse):
        if f.endswith(".bin"):
            os.remove(os.path.join(sparse, f))
    return sparse


def data_lines(text):
    return [i for i, l in enumerate(text.split("\n")) if l and not l.startswith("#")]


def dup_camera_text(r):  # the first camera's line again, with another focal length
    edit_text(os.path.join(colmap_text_only(r), "cameras.txt"),
              lambda t: t.rstrip("\n") + "\n" + re.sub(r"^(\S+ \S+ \S+ \S+) \S+", r"\1 77",
                                                      t.split("\n")[data_lines(t)[0]]) + "\n")


def dup_image_text(r, same_name):
    def change(t):
        lines = t.split("\n")
        first = data_lines(t)[0]
        f = lines[first].split(" ")
        if same_name:
            f[0] = "999"
        else:
            f[9] = "copy_" + f[9]
        return t.rstrip("\n") + "\n" + " ".join(f) + "\n\n"
    edit_text(os.path.join(colmap_text_only(r), "images.txt"), change)


def images_bin_entries(b):
    n = struct.unpack_from("<Q", b, 0)[0]
    pos, out = 8, []
    for _ in range(n):
        start = pos
        pos += 4 + 56 + 4
        pos = b.index(b"\0", pos) + 1
        np_ = struct.unpack_from("<Q", b, pos)[0]
        pos += 8 + 24 * np_
        out.append((start, pos))
    return out


def dup_image_bin(r, what):
    path = os.path.join(r, "scene_0", "sparse", "0", "images.bin")
    b = bytearray(open(path, "rb").read())
    (s0, e0), (s1, _) = images_bin_entries(bytes(b))[:2]
    if what == "id":
        b[s1:s1 + 4] = b[s0:s0 + 4]
    else:  # append a copy of entry 0 with a new id: the same name twice
        entry = bytearray(b[s0:e0])
        entry[0:4] = struct.pack("<I", 999)
        b += entry
        b[0:8] = struct.pack("<Q", struct.unpack_from("<Q", b, 0)[0] + 1)
    open(path, "wb").write(bytes(b))


def ns_edit(r, fn):
    path = os.path.join(r, "scene_0", "transforms.json")
    j = json.load(open(path))
    fn(j)
    json.dump(j, open(path, "w"))


def ply_bytes(n, value, tail=b"", comment=""):
    props = ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1",
             "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"]
    h = "ply\nformat binary_little_endian 1.0\n" + comment + f"element vertex {n}\n"
    h += "".join(f"property float {p}\n" for p in props) + "end_header\n"
    body = b"".join(struct.pack("<17f", *[value(v, k) for k in range(17)]) for v in range(n))
    return h.encode() + body + tail


def valid(v, k):
    return {0: 0.05 * (v % 20) - 0.5, 1: 0.05 * (v // 20 % 20) - 0.5, 2: 2.0 + 0.001 * v, 9: 2.0, 10: -3.5,
            11: -3.5, 12: -3.5, 13: 1.0}.get(k, 0.0)



# ---------------------------------------------------------------- disks and videos
def namespace_ok():
    probe = os.path.join(work, "probe")
    os.makedirs(probe)
    r = subprocess.run(["unshare", "-m", "--propagation", "private", "sh", "-c",
                        f"mount -t tmpfs -o size=64k tmpfs {probe} && mount -o remount,ro {probe}"],
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return r.returncode == 0


def in_tmpfs(case, cmd, size_kb, readonly=False):
    """`cmd` with {mnt} (a fresh tmpfs of size_kb, read-only on request) run in a private mount namespace; the
    tmpfs's content is copied to case/after for the checks."""
    mnt = os.path.join(case, "mnt")
    after = os.path.join(case, "after")
    os.makedirs(mnt)
    os.makedirs(after)
    script = (f'mount -t tmpfs -o size={size_kb}k tmpfs "{mnt}" || exit 97; mkdir -p "{mnt}/out"; '
              + (f'mount -o remount,ro "{mnt}" || exit 97; ' if readonly else "")
              + '"$@"; rc=$?; cp -a "' + mnt + '/." "' + after + '/" 2>/dev/null; exit $rc')
    return ["unshare", "-m", "--propagation", "private", "sh", "-c", script, "sh"] + [
        a.replace("{mnt}", os.path.join(mnt, "out")) for a in cmd]


def playable(mp4):
    b = open(mp4, "rb").read()
    return b"moov" in b and b"mdat" in b


