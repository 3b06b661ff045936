# Which local axis each Gaussian of a predicted 3DGS PLY (infinisplat predict: source camera frame) is flattest
# along, how flat it is, and how that axis sits to the view ray. Usage: python3 flat_axes.py scene.ply
import struct, sys, math, json
path = sys.argv[1]
f = open(path, 'rb')
props = []; n = 0
while True:
    line = f.readline().decode().strip()
    if line.startswith('element vertex'): n = int(line.split()[2])
    if line.startswith('property'): props.append(line.split()[2])
    if line == 'end_header': break
fmt = '<' + 'f' * len(props)
sz = struct.calcsize(fmt)
idx = {p: i for i, p in enumerate(props)}
ratios = []; zdots = []; flat_axes = [0, 0, 0]
for k in range(n):
    v = struct.unpack(fmt, f.read(sz))
    s = [math.exp(v[idx['scale_%d' % a]]) for a in range(3)]
    q = [v[idx['rot_%d' % a]] for a in range(4)]
    qn = math.sqrt(sum(x * x for x in q)); w, x, y, z = [t / qn for t in q]
    R = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    a = min(range(3), key=lambda i: s[i]); flat_axes[a] += 1
    srt = sorted(s); ratios.append(srt[0] / srt[1])
    col = [R[r][a] for r in range(3)]
    px, py, pz = v[idx['x']], v[idx['y']], v[idx['z']]
    pl = math.sqrt(px * px + py * py + pz * pz)
    zdots.append(abs(col[0] * px + col[1] * py + col[2] * pz) / pl)  # |cos| between flat axis and the view ray
ratios.sort(); zdots.sort()
q = lambda a, p: a[int(p * (len(a) - 1))]
print(f"{n} Gaussians; flattest local axis counts x/y/z {flat_axes}")
print("min/mid scale ratio quantiles 10/50/90%:", [round(q(ratios, p), 3) for p in (0.1, 0.5, 0.9)])
print("|cos(flat axis, view ray)| quantiles 10/50/90%:", [round(q(zdots, p), 3) for p in (0.1, 0.5, 0.9)])
