# Footprint (largest and middle scale x fx / depth, in pixels) and opacity quantiles of a predicted PLY's Gaussians
# (infinisplat predict writes them in the source camera's frame). Usage: python3 footprint.py FX scene.ply [more.ply]
import struct, sys, math, json
for path in sys.argv[2:]:
    fx = float(sys.argv[1])
    f = open(path, 'rb'); props = []; n = 0
    while True:
        line = f.readline().decode().strip()
        if line.startswith('element vertex'): n = int(line.split()[2])
        if line.startswith('property'): props.append(line.split()[2])
        if line == 'end_header': break
    fmt = '<' + 'f' * len(props); sz = struct.calcsize(fmt); idx = {p: i for i, p in enumerate(props)}
    fp, op, mn = [], [], []
    for k in range(n):
        v = struct.unpack(fmt, f.read(sz))
        s = sorted(math.exp(v[idx['scale_%d' % a]]) for a in range(3))
        z = v[idx['z']]
        if z <= 0: continue  # behind the camera: no footprint
        fp.append(s[2] * fx / max(z, 1e-6)); mn.append(s[1] * fx / max(z, 1e-6))
        op.append(1 / (1 + math.exp(-v[idx['opacity']])))
    q = lambda a, p: sorted(a)[int(p * (len(a) - 1))]
    print(f"{path.split('/')[-1]:14s} n {n}  largest-axis footprint px 10/50/90%: {[round(q(fp,p),2) for p in (.1,.5,.9)]}  middle-axis: {[round(q(mn,p),2) for p in (.1,.5,.9)]}  opacity 10/50/90%: {[round(q(op,p),3) for p in (.1,.5,.9)]}")
