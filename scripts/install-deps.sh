#!/usr/bin/env bash
# install-deps.sh: every Debian package cenote needs to build, test, benchmark and run its demo.
# Idempotent and non-interactive: packages already present are not fetched again, and
# `apt-get update` runs at most once per invocation (and only when something is missing).
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build ccache pkg-config git
  # pipeline: images, calibration, SIMD, threads
  libopencv-dev libeigen3-dev libhwy-dev libdeflate-dev zlib1g-dev
  # command line, config, logs
  libcli11-dev libyaml-cpp-dev libspdlog-dev libfmt-dev nlohmann-json3-dev
  # mapping: volumetric map (OpenVDB, TBB), OctoMap as peer, reference and file format
  libopenvdb-dev libtbb-dev liboctomap-dev octomap-tools
  # eval: nearest neighbours for cloud metrics; plots (cenote eval --plot runs /usr/bin/python3)
  libnanoflann-dev python3-matplotlib
  # server and clients: gRPC (C++ server, C++ and command-line clients), Python client with
  # stubs generated at build time
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc python3-grpcio python3-grpc-tools
  python3-protobuf
  # server TLS tests make their certificates
  openssl
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
  # the format check (scripts/check-format.sh: clang-format 14, as .clang-format was tuned for)
  clang-format
  # test data scripts
  python3 python3-numpy
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

if [ "$(id -u)" -ne 0 ]; then
  SUDO=sudo
else
  SUDO=
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
