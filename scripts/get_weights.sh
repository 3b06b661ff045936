#!/usr/bin/env bash
# Downloads the pretrained weights from their publishers, converts them to safetensors and checks the pinned SHA-256.
# Usage:
#   scripts/get_weights.sh [--dest DIR]   download, convert, verify into DIR (default: the checkout's weights/)
#   scripts/get_weights.sh --from DIR     the same from the published files already in DIR (no network)
#   scripts/get_weights.sh --verify [--bin B]        check the files the programs find (infinisplat weights) against the pins
#   scripts/get_weights.sh --self-test lpips|squeezenet  test the converter on legacy torch.save files (ctest runs both)
# --verify and --self-test lpips exit 77 (ctest's "skipped") when there is nothing to check.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
python=/usr/bin/python3  # Debian's, with python3-torch (not a pyenv or venv python without it)
convert="$root/scripts/convert_weights.py"
sums="$root/weights/SHA256SUMS"
skip=77
work=""  # this run's temporary folder, removed on any exit
trap 'rm -rf "${work:-}"' EXIT

# Publisher, file, URL, SHA-256 of the published file ("" = torchvision's own check: the name's 8-hex prefix).
SOURCES=(
  "squeezenet squeezenet1_1-b8a52dc0.pth https://download.pytorch.org/models/squeezenet1_1-b8a52dc0.pth squeezenet1_1_features.safetensors"
  "lpips squeeze.pth https://raw.githubusercontent.com/richzhang/PerceptualSimilarity/master/lpips/weights/v0.1/squeeze.pth lpips_v0.1_squeeze_lin.safetensors"
  "lpips alex.pth https://raw.githubusercontent.com/richzhang/PerceptualSimilarity/master/lpips/weights/v0.1/alex.pth lpips_v0.1_alex_lin.safetensors"
  "lpips vgg.pth https://raw.githubusercontent.com/richzhang/PerceptualSimilarity/master/lpips/weights/v0.1/vgg.pth lpips_v0.1_vgg_lin.safetensors"
)
# The LPIPS v0.1 heads as their publisher ships them (weights/README.md).
declare -A ORIGINAL_SHA256=(
  [squeeze.pth]=4a5350f23600cb79923ce65bb07cbf57dca461329894153e05a1346bd531cf76
  [alex.pth]=df73285e35b22355a2df87cdb6b70b343713b667eddbda73e1977e0c860835c0
  [vgg.pth]=a78928a0af1e5f0fcb1f3b9e8f8c3a2a5a3de244d830ad5c1feddc79b8432868
)

die() { echo "get_weights.sh: $*" >&2; exit 1; }
need_python_torch() {
  "$python" -c "import torch" 2>/dev/null ||
    die "converting needs Debian's python3-torch: run scripts/setup.sh (or apt-get install python3-torch)"
}
pinned() { awk -v f="$1" '$2 == f { print $1 }' "$sums"; }

# Checks every converted file in $1 against weights/SHA256SUMS; prints one line per file.
verify_folder() {
  local dir=$1 bad=0 file want got
  for entry in "${SOURCES[@]}"; do
    read -r _ _ _ file <<<"$entry"
    want=$(pinned "$file")
    [ -n "$want" ] || die "no pinned SHA-256 for $file in $sums"
    if [ ! -f "$dir/$file" ]; then
      echo "missing  $dir/$file"; bad=1; continue
    fi
    got=$(sha256sum "$dir/$file" | cut -d' ' -f1)
    if [ "$got" = "$want" ]; then echo "ok       $dir/$file"; else echo "MISMATCH $dir/$file ($got, pinned $want)"; bad=1; fi
  done
  return $bad
}

# Converts the published files in $1 into $2 and verifies the results.
convert_folder() {
  local from=$1 dest=$2 kind name file want got
  need_python_torch
  mkdir -p "$dest"
  for entry in "${SOURCES[@]}"; do
    read -r kind name _ file <<<"$entry"
    [ -f "$from/$name" ] || die "$from/$name: missing (the published $kind file)"
    got=$(sha256sum "$from/$name" | cut -d' ' -f1)
    want=${ORIGINAL_SHA256[$name]:-}
    if [ -n "$want" ] && [ "$got" != "$want" ]; then die "$from/$name: SHA-256 $got, the publisher's is $want"; fi
    if [ -z "$want" ]; then  # torchvision names its files <name>-<first 8 hex digits of the SHA-256>.pth
      prefix=${name##*-}; prefix=${prefix%.pth}
      [ "${got:0:8}" = "$prefix" ] || die "$from/$name: SHA-256 $got does not start with $prefix"
    fi
    "$python" "$convert" "$kind" "$from/$name" "$dest/$file"
  done
  verify_folder "$dest" || die "converted files in $dest do not match the pins in $sums"
  echo "get_weights.sh: weights ready in $dest"
}

download() {
  local dest=$1 kind name url
  local tmp
  tmp=$(mktemp -d)
  work=$tmp
  for entry in "${SOURCES[@]}"; do
    read -r kind name url _ <<<"$entry"
    echo "get_weights.sh: downloading $url"
    curl -fsSL --connect-timeout 10 -o "$tmp/$name" "$url" ||
      die "cannot download $url (offline?). On a machine without internet, put the four published files" \
        "(squeezenet1_1-b8a52dc0.pth, squeeze.pth, alex.pth, vgg.pth) in a folder and run:" \
        "scripts/get_weights.sh --from <folder>; or set INFINISPLAT_WEIGHTS to a folder of converted weights"
  done
  convert_folder "$tmp" "$dest"
}

# Converter test on the published LPIPS heads ($INFINISPLAT_WEIGHTS/original, the team's copy): they must convert to
# tensor-identical copies of the converted files beside them, with the pinned SHA-256. Skipped (77) without them.
self_test_lpips() {
  local shared="${INFINISPLAT_WEIGHTS:-}" n out
  if [ -z "$shared" ] || [ ! -d "$shared/original" ]; then
    echo "self-test: no \$INFINISPLAT_WEIGHTS/original (the published LPIPS heads); skipped"
    exit $skip
  fi
  need_python_torch
  local tmp
  tmp=$(mktemp -d)
  work=$tmp
  for n in squeeze alex vgg; do
    out="$tmp/lpips_v0.1_${n}_lin.safetensors"
    "$python" "$convert" lpips "$shared/original/$n.pth" "$out"
    "$python" "$convert" compare "$out" "$shared/lpips_v0.1_${n}_lin.safetensors"
    [ "$(sha256sum "$out" | cut -d' ' -f1)" = "$(pinned "lpips_v0.1_${n}_lin.safetensors")" ] ||
      die "converted $n.pth does not match its pinned SHA-256"
  done
  echo "get_weights.sh: LPIPS converter self-test passed"
}

# Converter test on torchvision's SqueezeNet layout (features.* and classifier.*) saved in the legacy format with
# _use_new_zipfile_serialization=False: every features tensor must come out identical. Its values are the converted
# features' when the lookup finds them (then the output must also match the pin), else random.
self_test_squeezenet() {
  local ref=""
  need_python_torch
  local tmp
  tmp=$(mktemp -d)
  work=$tmp
  [ -n "${INFINISPLAT_WEIGHTS:-}" ] && [ -f "$INFINISPLAT_WEIGHTS/squeezenet1_1_features.safetensors" ] &&
    ref="$INFINISPLAT_WEIGHTS/squeezenet1_1_features.safetensors"
  "$python" - "$tmp" "$ref" <<'PY'
import collections, json, os, struct, sys, torch
tmp, ref = sys.argv[1], sys.argv[2]
shapes = [("0", (64, 3, 3, 3))]
fires = {3: (64, 16, 64), 4: (128, 16, 64), 6: (128, 32, 128), 7: (256, 32, 128),
         9: (256, 48, 192), 10: (384, 48, 192), 11: (384, 64, 256), 12: (512, 64, 256)}
for i, (cin, s, e) in fires.items():
    shapes += [(f"{i}.squeeze", (s, cin, 1, 1)), (f"{i}.expand1x1", (e, s, 1, 1)), (f"{i}.expand3x3", (e, s, 3, 3))]
torch.manual_seed(0)
known = {}
if ref:
    raw = open(ref, "rb").read(); n = struct.unpack("<Q", raw[:8])[0]
    for k, v in json.loads(raw[8:8 + n]).items():
        a, b = v["data_offsets"]
        known[k] = torch.frombuffer(bytearray(raw[8 + n + a:8 + n + b]), dtype=torch.float32).reshape(v["shape"])
state = collections.OrderedDict()
for name, shape in shapes:
    state[f"features.{name}.weight"] = known.get(f"{name}.weight", torch.randn(shape))
    state[f"features.{name}.bias"] = known.get(f"{name}.bias", torch.randn(shape[0]))
state["classifier.1.weight"] = torch.randn(1000, 512, 1, 1)
state["classifier.1.bias"] = torch.randn(1000)
torch.save(state, f"{tmp}/squeezenet1_1-legacy.pth", _use_new_zipfile_serialization=False)
assert open(f"{tmp}/squeezenet1_1-legacy.pth", "rb").read(2) == b"\x80\x02", "not the legacy format"
expected = collections.OrderedDict((k[len("features."):], v) for k, v in state.items() if k.startswith("features."))
torch.save(expected, f"{tmp}/expected.pt")
print("self-test: a legacy SqueezeNet file with", "the converted features' values" if known else "random values")
PY
  "$python" "$convert" squeezenet "$tmp/squeezenet1_1-legacy.pth" "$tmp/squeezenet1_1_features.safetensors"
  "$python" - "$tmp" <<'PY'
import json, struct, sys, torch
tmp = sys.argv[1]
expected = torch.load(f"{tmp}/expected.pt")
raw = open(f"{tmp}/squeezenet1_1_features.safetensors", "rb").read(); n = struct.unpack("<Q", raw[:8])[0]
h = json.loads(raw[8:8 + n])
assert list(h) == list(expected), f"names or order differ: {list(h)[:3]} vs {list(expected)[:3]}"
for k, t in expected.items():
    v = h[k]; a, b = v["data_offsets"]
    assert v["dtype"] == "F32" and v["shape"] == list(t.shape), f"{k}: {v['dtype']} {v['shape']} vs {list(t.shape)}"
    got = torch.frombuffer(bytearray(raw[8 + n + a:8 + n + b]), dtype=torch.float32).reshape(t.shape)
    assert torch.equal(got, t), f"{k}: values differ"
print(f"self-test: SqueezeNet legacy -> safetensors, {len(h)} tensors identical")
PY
  if [ -n "$ref" ]; then
    "$python" "$convert" compare "$tmp/squeezenet1_1_features.safetensors" "$ref"
    [ "$(sha256sum "$tmp/squeezenet1_1_features.safetensors" | cut -d' ' -f1)" = "$(pinned squeezenet1_1_features.safetensors)" ] ||
      die "the SqueezeNet round trip does not match its pinned SHA-256"
  fi
  echo "get_weights.sh: SqueezeNet converter self-test passed"
}

dest="$root/weights"
mode=download
from=""
bin="${BUILD_DIR:-$root/build}/infinisplat"
while [ $# -gt 0 ]; do
  case "$1" in
    --dest) dest=${2:?--dest needs a folder}; shift 2 ;;
    --from) mode=from; from=${2:?--from needs a folder}; shift 2 ;;
    --verify) mode=verify; shift ;;
    --self-test) mode=self-test-${2:?--self-test needs lpips or squeezenet}; shift 2 ;;
    --bin) bin=${2:?--bin needs the infinisplat executable}; shift 2 ;;
    -h|--help) sed -n '2,8p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done

case "$mode" in
  download) download "$dest" ;;
  from) convert_folder "$from" "$dest" ;;
  verify)
    [ -x "$bin" ] || die "$bin: not built (scripts/build.sh)"
    folder=$("$bin" weights --folder) || { echo "get_weights.sh: no weights found; nothing to verify"; exit $skip; }
    verify_folder "$folder" || die "weights in $folder do not match the pins in $sums; run scripts/get_weights.sh"
    ;;
  self-test-lpips) self_test_lpips ;;
  self-test-squeezenet) self_test_squeezenet ;;
  *) die "unknown self-test '${mode#self-test-}' (lpips | squeezenet)" ;;
esac
