#!/usr/bin/env bash
# Installs every build/run dependency from Debian packages (idempotent; a second run takes seconds).
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build ccache pkg-config
  libtorch-dev libopencv-dev libeigen3-dev nlohmann-json3-dev
  libopenexr-dev libimath-dev catch2 libhdf5-dev libjpeg62-turbo-dev zlib1g-dev
  libonnx-dev libprotobuf-dev protobuf-compiler
  libbenchmark-dev libopenblas0-pthread clang-format
  libgloo-dev  # Gloo headers for c10d ProcessGroupGloo (data-parallel training)
  chromium  # opens the exported HTML viewer headless in the tests
  python3-torch  # scripts/get_weights.sh converts the published torch.save weights with torch.load
  python3-dev python3-pybind11 python3-pytest python3-venv python3-wheel  # python/: build, tests, pip install
  curl  # scripts/get_weights.sh downloads them
)

need_root() {
  if [ "$(id -u)" -ne 0 ]; then
    echo "setup.sh: missing packages and not root; re-run as root or install: $*" >&2
    exit 1
  fi
}

# Node.js/npm only when absent (a newer nodesource build conflicts with Debian's npm package).
command -v npm >/dev/null 2>&1 || PACKAGES+=(nodejs npm)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -gt 0 ]; then
  need_root "${missing[@]}"
  echo "setup.sh: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
else
  echo "setup.sh: all Debian packages present"
fi

# OpenBLAS must be the selected libblas.so.3: LibTorch's matmuls run ~30x slower on reference BLAS.
arch_dir="/usr/lib/$(dpkg-architecture -qDEB_HOST_MULTIARCH 2>/dev/null || echo x86_64-linux-gnu)"
openblas_blas="$arch_dir/openblas-pthread/libblas.so.3"
openblas_lapack="$arch_dir/openblas-pthread/liblapack.so.3"
current=$(readlink -f "$arch_dir/libblas.so.3" || true)
if [ "$current" != "$(readlink -f "$openblas_blas")" ]; then
  need_root libopenblas0-pthread
  update-alternatives --set "libblas.so.3-$(basename "$arch_dir")" "$openblas_blas" >/dev/null
  [ -e "$openblas_lapack" ] && update-alternatives --set "liblapack.so.3-$(basename "$arch_dir")" "$openblas_lapack" >/dev/null
fi
current=$(readlink -f "$arch_dir/libblas.so.3")
case "$current" in
  *openblas*) echo "setup.sh: libblas.so.3 -> $current" ;;
  *) echo "setup.sh: ERROR libblas.so.3 resolves to $current, not OpenBLAS" >&2; exit 1 ;;
esac

# onnxruntime-node verifies ONNX export; --ignore-scripts because its post-install step tries to download.
ORT_VERSION=1.30.0
root_dir="$(cd "$(dirname "$0")/.." && pwd)"
ort_dir="$root_dir/third_party/onnxruntime-node"
if command -v npm >/dev/null 2>&1; then
  if [ ! -f "$ort_dir/node_modules/onnxruntime-node/package.json" ] ||
     ! grep -q "\"version\": \"$ORT_VERSION\"" "$ort_dir/node_modules/onnxruntime-node/package.json"; then
    mkdir -p "$ort_dir"
    (cd "$ort_dir" && npm install --silent --no-audit --no-fund --ignore-scripts "onnxruntime-node@$ORT_VERSION" >/dev/null) ||
      echo "setup.sh: WARNING npm install onnxruntime-node failed; the ONNX runtime check will be skipped" >&2
  fi
fi
# splat-transform writes the HTML viewer export and, in the tests, reads back the .splat/.spz/PLY files we
# write. 2.7.1 is the newest release that runs on Node 18 (Debian 12's nodejs); 3.x needs Node 22.
SPLAT_TRANSFORM_VERSION=2.7.1
st_dir="$root_dir/third_party/splat-transform"
st_pkg="$st_dir/node_modules/@playcanvas/splat-transform/package.json"
if command -v npm >/dev/null 2>&1; then
  if [ ! -f "$st_pkg" ] || ! grep -q "\"version\": \"$SPLAT_TRANSFORM_VERSION\"" "$st_pkg"; then
    mkdir -p "$st_dir"
    (cd "$st_dir" && npm install --silent --no-audit --no-fund --ignore-scripts \
      "@playcanvas/splat-transform@$SPLAT_TRANSFORM_VERSION" >/dev/null) ||
      echo "setup.sh: WARNING npm install splat-transform failed; html export and its checks will be skipped" >&2
  fi
fi
echo "setup.sh: done"
