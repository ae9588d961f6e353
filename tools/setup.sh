#!/usr/bin/env bash
# Installs the Debian packages spall needs, only those missing. Fast (one dpkg query) when all are present.
set -euo pipefail
packages=(
  build-essential cmake ccache pkg-config
  libbullet-dev libopenvdb-dev libboost-dev libboost-iostreams-dev libblosc-dev libtbb-dev
  libeigen3-dev libhdf5-dev libgtest-dev libgmock-dev libbenchmark-dev
  libassimp-dev libcli11-dev nlohmann-json3-dev libpng-dev
  python3-openvdb python3-h5py python3-numpy python3-matplotlib python3-pil libopenvdb-tools hdf5-tools
)
missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "installed" ]] || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  exit 0
fi
if [[ $(id -u) -ne 0 ]]; then
  echo "spall setup: missing Debian packages: ${missing[*]}" >&2
  echo "spall setup: run as root, or: sudo apt-get install ${missing[*]}" >&2
  exit 1
fi
echo "spall setup: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
