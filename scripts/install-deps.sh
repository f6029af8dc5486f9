#!/usr/bin/env bash
# Installs, from Debian's packages, everything magbake needs to build, test and benchmark.
# Idempotent: prints nothing and changes nothing when every package is already there.
# Works on a minimal Debian bookworm that has only git (runs apt-get as root, or with sudo).
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config git ca-certificates
  # core libraries
  libeigen3-dev libtbb-dev
  # simulation, scene, io, render
  libbullet-dev libbullet-extras-dev libyaml-cpp-dev libassimp-dev
  libhdf5-dev hdf5-tools libopenvdb-dev libboost-iostreams-dev libopenvdb-tools
  libosmesa6-dev libpng-dev
  # command line and logging
  libcli11-dev libspdlog-dev libfmt-dev nlohmann-json3-dev libssl-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
  # independent readers and plots used by tests and bench scripts (Debian's /usr/bin/python3)
  python3 python3-numpy python3-h5py python3-openvdb python3-matplotlib
  # a venv under the build folder for PyPI's usd-core (tests/usd)
  python3-venv
  # disk-full test (loop-mounted ext2 image)
  e2fsprogs util-linux
  # fuzzing (libFuzzer comes with Debian's clang) and the sanitizer build
  clang libclang-rt-dev
  # the same binary baked on emulated Intel and AMD CPUs (Bake.SameCacheOnEmulatedIntelAndAmdCpus)
  qemu-user binutils
  # a single-node Slurm cluster for the farm tests (scripts/slurm-local.sh)
  slurm-wlm munge
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q '^install ok installed$'; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo="sudo"
fi
echo "install-deps: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq >/dev/null
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
