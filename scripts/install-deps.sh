#!/usr/bin/env bash
# Installs the Debian 12 packages stex needs to build, test and run (only those missing).
# As root: apt-get update + install. Otherwise: prints the exact apt-get line and exits 2.
set -euo pipefail
PKGS=(cmake make g++ pkg-config
      ocl-icd-opencl-dev opencl-headers pocl-opencl-icd libclfft-dev
      mesa-opencl-icd  # rusticl: the second OpenCL implementation make test runs the device tests on (README)
      libfftw3-dev libopenimageio-dev libeigen3-dev
      libassimp-dev libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev nlohmann-json3-dev openimageio-tools
      fonts-dejavu-core  # the captions of make demo's picture (oiiotool --text)
      python3-dev pybind11-dev python3-numpy python3-pytest
      python3-openimageio  # the OIIO plugin's TextureSystem test (ctest oiio_texture_system, docs/oiio-plugin.md)
      clang libclang-rt-14-dev  # clang + libFuzzer/sanitizer runtimes: scripts/fuzz.sh (docs/hardening.md)
      munge slurmctld slurmd slurm-client  # the one-node Slurm cluster of ctest "slurm" (docs/farm.md)
      libcpp-httplib-dev wrk chromium)  # stex serve: HTTP server; its load and headless viewer tests (docs/serve.md)
missing=()
for p in "${PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
line="apt-get install -y --no-install-recommends ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "stex: missing Debian packages: ${missing[*]}" >&2
  echo "stex: run as root:  apt-get update && $line" >&2
  exit 2
fi
echo "stex: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}"
