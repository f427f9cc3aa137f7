#!/usr/bin/env bash
# Installs the Debian 12 packages drape builds, tests and runs with, when any is missing.
# Safe to call repeatedly: it only calls apt-get when dpkg reports a package absent.
set -euo pipefail

PACKAGES=(
  cmake g++ make pkg-config
  libeigen3-dev        # dense and sparse linear algebra, fixed-size vectors
  libgmp-dev           # exact rationals: query files with >64-bit numbers, exact CCD references
  libcgal-dev          # exact predicates of the independent penetration check (drape check)
  libcli11-dev         # command-line parsing and --help
  nlohmann-json3-dev   # JSON scenes and --json output
  libtbb-dev           # parallel narrow phase
  libhwy-dev           # Google Highway: the CCD kernels written once for every SIMD instruction set
  libgtest-dev         # the test suite
  libbenchmark-dev     # micro-benchmarks
  libbullet-dev        # btDbvt broad phase (the -float64 libraries)
  libfcl-dev           # peer CCD functions compared against in bench/
  libassimp-dev        # mesh input and output
  libsuitesparse-dev   # CHOLMOD sparse Cholesky
  libopenblas0-serial  # BLAS for CHOLMOD's supernodal factorisation (2x the reference BLAS; serial = deterministic)
  libosmesa6-dev       # off-screen rendering
  libpng-dev           # PNG frames
  ffmpeg               # MP4 encoding
  gnuplot-nox          # the time-against-error plot of drape sweep (PNG)
  openmpi-bin libopenmpi-dev  # drape batch and drape sweep across MPI ranks (mpirun, srun)
  clang libclang-rt-14-dev  # libFuzzer targets (tools/fuzz.sh)
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  echo "install-deps: installing ${missing[*]}" >&2
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
