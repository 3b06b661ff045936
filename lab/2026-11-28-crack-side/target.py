# Issue 17's target at [2,inf): each row minus pixel_supports and minus dense_decoder (two seeds averaged per pair),
# holes and cracks in points, paired bootstrap 95% (2000 resamples, seed 0), 3 decimals.
# Usage: python3 target.py [eval folder, default out/experiments/crack_side/any] [row=m1+m2 ...]; rows the folder
# did not score are left out.
import json, os, sys
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sides import interval as iv  # one bootstrap for both scripts
root = sys.argv[1] if len(sys.argv) > 1 else 'out/experiments/crack_side/any'
ROWS = [('full', 'full+full_s1'), ('full_edge05', 'full_edge05+full_edge05_s1')]
ROWS += [tuple(a.split('=', 1)) for a in sys.argv[2:]]
def load(s, spec):
    runs = [{r['index']: r for r in map(json.loads, open(f"{root}/{s}/results_{m}.jsonl"))} for m in spec.split('+')]
    return {k: {f: sum(r[k][f] for r in runs) / len(runs) for f in ('hole_rate', 'crack_rate')} | {'bin': runs[0][k]['bin']}
            for k in runs[0] if all(k in r for r in runs)}
print("| set | row | holes − pixel | holes − dense | cracks − pixel | cracks − dense |\n|---|---|---|---|---|---|")
for s in ['rooms-heldout', 'courtyard-colmap', 'atrium-nerfstudio']:
    P = load(s, 'pixel_supports+pixel_supports_s1'); D = load(s, 'dense_decoder+dense_decoder_s1')
    for name, spec in ROWS:
        if not all(os.path.exists(f"{root}/{s}/results_{m}.jsonl") for m in spec.split('+')):
            continue  # a row this folder did not score
        A = load(s, spec); ks = [k for k in A if A[k]['bin'] == 3 and k in P and k in D]
        cells = [iv([100 * (A[k][f] - B[k][f]) for k in ks]) for f in ('hole_rate', 'crack_rate') for B in (P, D)]
        print(f"| {s} ({len(ks)} pairs) | {name} | " + " | ".join(cells) + " |")
