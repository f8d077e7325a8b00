#!/usr/bin/env bash
# install-deps.sh: every Debian package cenote needs to build, test, benchmark and run its demo.
# Idempotent and non-interactive: packages already present are not fetched again, and
# `apt-get update` runs at most once per invocation (and only when something is missing).
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build ccache pkg-config git
  # pipeline: images, calibration, SIMD, threads
  libopencv-dev libeigen3-dev libhwy-dev libdeflate-dev libisal-dev zlib1g-dev libjpeg-dev
  # ROS 2 recordings: MCAP chunks (zstd; lz4 below), rosbag2 sqlite3 storage; the tests' compressed
  # rosbag2 bags (compression_mode MESSAGE / FILE) are written with python3-zstandard
  libzstd-dev libsqlite3-dev python3-zstandard
  # command line, config, logs
  libcli11-dev libyaml-cpp-dev libspdlog-dev libfmt-dev nlohmann-json3-dev
  # mapping: volumetric map (OpenVDB, TBB), OctoMap as peer, reference and file format
  libopenvdb-dev libtbb-dev liboctomap-dev octomap-tools
  # eval: nearest neighbours for cloud metrics; plots (cenote eval --plot runs /usr/bin/python3)
  libnanoflann-dev python3-matplotlib
  # PCD files and statistical outlier removal through PCL's own code: its runtime libraries (13
  # packages, 6 MB, ~40 MB installed on top of the rest) and, below, libpcl-dev's headers alone.
  # libpcl-dev itself drags VTK, Qt and all of Boost in: 268 packages, 115 MB, 743 MB, 142 s here.
  libpcl-io1.13 libpcl-common1.13 libpcl-filters1.13 libboost-dev
  # server and clients: gRPC (C++ server, C++ and command-line clients), Python client with
  # stubs generated at build time
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc python3-grpcio python3-grpc-tools
  python3-protobuf
  # TLS on the viewer port (Asio's OpenSSL layer); the server TLS tests make their certificates
  libssl-dev openssl
  # ROS 1 bags (io/bag/ros1_bag.cpp): bz2 and lz4-frame chunks; the tests' bags are written by ROS's own
  # rosbag (python3-rosbag) with the message classes of sensor_msgs, geometry_msgs, nav_msgs and tf2_msgs,
  # their images encoded (PNG, JPEG) and rigs rectified (CameraInfo) by OpenCV's Python bindings, which
  # also write the paper's dataset layout (FileStorage) in the tests
  libbz2-dev liblz4-dev python3-rosbag python3-sensor-msgs python3-geometry-msgs python3-nav-msgs python3-tf2-msgs
  python3-opencv
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
  # the format check (scripts/check-format.sh: clang-format 14, as .clang-format was tuned for)
  clang-format
  # test data scripts
  python3 python3-numpy
  # the live viewer's browser test: headless Chromium (driven by npm playwright-core, web/)
  chromium
)
# `make fuzz` (install-deps.sh --fuzz): clang and its libFuzzer runtime; CI's `make test` needs neither.
if [ "${1:-}" = "--fuzz" ]; then
  PACKAGES+=(clang libclang-rt-14-dev)
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ "$(id -u)" -ne 0 ]; then
  SUDO=sudo
else
  SUDO=
fi
export DEBIAN_FRONTEND=noninteractive
updated=0
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
else
  echo "install-deps: installing ${missing[*]}"
  $SUDO apt-get update -qq
  updated=1
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The browser viewer (web/) and the ROS 2 test recordings (tests/io/bag/gen) are made by npm packages:
# node and npm, from Debian unless some other node (with its own npm) is installed already.
if ! command -v node > /dev/null || ! command -v npm > /dev/null; then
  echo "install-deps: installing nodejs npm"
  [ "$updated" -eq 1 ] || $SUDO apt-get update -qq
  updated=1
  $SUDO apt-get install -y -qq --no-install-recommends nodejs npm
fi

# PCL's headers without libpcl-dev's dependencies: the package unpacked (not installed) under
# /opt/cenote/pcl, where CMakeLists.txt looks after /usr/include. A full libpcl-dev also does.
PCL_HEADERS=/opt/cenote/pcl
if [ ! -f /usr/include/pcl-1.13/pcl/io/pcd_io.h ] && [ ! -f "$PCL_HEADERS/usr/include/pcl-1.13/pcl/io/pcd_io.h" ]; then
  echo "install-deps: unpacking libpcl-dev's headers into $PCL_HEADERS"
  [ "$updated" -eq 1 ] || $SUDO apt-get update -qq
  work=$(mktemp -d)
  chmod 777 "$work"  # apt-get download fetches as the _apt user
  (cd "$work" && $SUDO apt-get download -qq libpcl-dev)
  $SUDO mkdir -p "$PCL_HEADERS"
  $SUDO dpkg-deb -x "$work"/libpcl-dev_*.deb "$PCL_HEADERS"
  rm -rf "$work"
fi

# npm for the MCAP test recordings (tests/io/bag/gen, npm ci at build time): Debian's npm, unless the
# installed nodejs already brings its own (NodeSource's does, and conflicts with Debian's npm package).
if ! command -v npm >/dev/null 2>&1; then
  echo "install-deps: installing npm"
  [ "$updated" -eq 1 ] || $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends npm
fi
