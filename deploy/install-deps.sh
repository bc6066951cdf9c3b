#!/usr/bin/env bash
# Installs every build, run and test dependency of PickSight from Debian 12's
# own packages. Idempotent: when everything is present it only checks and
# returns, without touching the network.
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake pkg-config git clang clang-format
  # CMake's Ninja generator: quickstart's and CI's build trees (docs/CI.md)
  ninja-build
  # LLVM's linker: quickstart's test trees and CI link with it (docs/CI.md)
  lld
  # libFuzzer and the sanitizer runtimes for clang (fuzz run in CI)
  libclang-rt-14-dev
  # core libraries
  libopencv-dev libtbb-dev libzmq3-dev cppzmq-dev libprotobuf-dev protobuf-compiler
  libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  # camera drivers: GigE/USB3 Vision (and the fake camera used by tests), V4L2
  # (libusb-1.0-0-dev: aravis-0.8.pc requires it, but libaravis-dev does not pull it in)
  libaravis-dev libusb-1.0-0-dev aravis-tools aravis-tools-cli libv4l-dev
  # Python client (python/) and its tests: Debian's /usr/bin/python3 modules
  # (python3-nacl: to open the frames a video server with CURVE seals)
  python3-zmq python3-protobuf python3-numpy python3-nacl python3-pytest
  # picksight-robot's line editing and history (BSD licence)
  libedit-dev
  # network namespaces and veth pairs: the two-host test (deploy/two-hosts) and
  # the fake GigE camera tests (tests/support/run_in_netns.sh)
  iproute2
  # dropping a fake GigE camera's stream packets inside a test's own namespace
  iptables
  # container images without a registry (deploy/containers, opt-in test)
  mmdebstrap podman
  # tests (curl: the package test's HTTPS client)
  catch2 curl
  # services: sd_notify readiness and watchdog
  libsystemd-dev
  # Debian package (CPack: dpkg-shlibdeps, file) and its unit tests (systemd-analyze)
  dpkg-dev file systemd
  # PLC port: Modbus TCP server (libmodbus), and the independent client of its tests
  libmodbus-dev python3-pymodbus
  # web HMI (picksight-web): HTTP(S) server, JPEG encoding, argon2id password hashes;
  # OpenSSL for its TLS settings and the package's certificate (postinst, tests)
  libcpp-httplib-dev libsodium-dev libssl-dev openssl
  libturbojpeg0-dev
  # pymodbus imports its serial client with every client (a Recommends of python3-pymodbus)
  python3-serial-asyncio
  # calibration: Fisher's F distribution for COMPUTE BEST's model test (header-only Boost.Math)
  libboost-math-dev
  # the web HMI page's tests in a real browser: headless Chromium driven by Selenium
  chromium chromium-driver python3-selenium
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi

if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps: missing packages (${missing[*]}); run as root" >&2
  exit 1
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "install-deps: done"
