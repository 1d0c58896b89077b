#!/usr/bin/env bash
# Installs the Debian 12 packages isochor needs, and only those that are missing
# (libopenblas0-pthread replaces the reference BLAS system-wide: CHOLMOD's supernodal
# factorisation of the fine ball is 6 times faster with it):
# a second run installs nothing.
set -euo pipefail
packages=(
  build-essential cmake git pkg-config universal-ctags clang-format
  libeigen3-dev libhdf5-dev libgmsh-dev gmsh libtomlplusplus-dev libcli11-dev libnanoflann-dev libcgal-dev libtinygltf-dev
  libsundials-dev libsuitesparse-dev libmetis-dev libsimbody-dev
  libopenblas0-pthread
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-dev python3-numpy python3-h5py python3-matplotlib python3-meshio
  pybind11-dev python3-pytest python3-venv python3-setuptools python3-wheel
  libopenmpi-dev openmpi-bin libhypre-dev
)
# npm builds the page of `isochor view` (viewer/, its packages pinned in package-lock.json):
# Debian's, unless an npm is on PATH already (a Node.js from elsewhere brings its own).
command -v npm > /dev/null 2>&1 || packages+=(npm)
missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
