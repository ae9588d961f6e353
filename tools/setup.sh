#!/usr/bin/env bash
# Installs what spall needs, only what is missing: Debian packages (one dpkg query when all are
# present; Slurm and munge for the sweep tests), Node.js when there is none, and tools/js from its lock file (the viewer's three.js and
# esbuild, which the build needs; the glTF validator and playwright-core, which the tests use).
set -euo pipefail
cd "$(dirname "$0")/.."
packages=(
  build-essential cmake ccache pkg-config
  libbullet-dev libopenvdb-dev libboost-dev libboost-iostreams-dev libblosc-dev libtbb-dev
  libeigen3-dev libxsimd-dev libhdf5-dev libgtest-dev libgmock-dev libbenchmark-dev
  libassimp-dev libcli11-dev nlohmann-json3-dev libpng-dev libtinygltf-dev
  python3-openvdb python3-h5py python3-numpy python3-matplotlib python3-pil libopenvdb-tools hdf5-tools
  blender chromium valgrind
  slurm-wlm munge
)
missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "installed" ]] || missing+=("$p")
done
# Any Node.js will do (the machine's own, or Debian's).
command -v node > /dev/null && command -v npm > /dev/null || missing+=(nodejs npm)
if ((${#missing[@]} > 0)); then
  if [[ $(id -u) -ne 0 ]]; then
    echo "spall setup: missing Debian packages: ${missing[*]}" >&2
    echo "spall setup: run as root, or: sudo apt-get install ${missing[*]}" >&2
    exit 1
  fi
  echo "spall setup: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi
# npm ci again whenever the lock file differs from the one last installed.
installed_lock=tools/js/node_modules/.spall-installed-lock.json
if ! cmp -s tools/js/package-lock.json "$installed_lock"; then
  echo "spall setup: installing tools/js (npm ci)" >&2
  npm ci --prefix tools/js --no-audit --no-fund >&2
  cp tools/js/package-lock.json "$installed_lock"
fi
