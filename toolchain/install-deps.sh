#!/usr/bin/env bash
# Installs every build and test dependency of companion from the distribution's packages.
# Idempotent and non-interactive; works on Debian 12 (bookworm) and Ubuntu 22.04 (Jetson, jammy).
# Nothing else is downloaded at build time.
#
#   toolchain/install-deps.sh            build + test dependencies
#   toolchain/install-deps.sh --training also LibTorch for the optional PPO training build
set -euo pipefail

packages=(
  build-essential cmake ninja-build ccache pkg-config git
  libeigen3-dev libspdlog-dev libfmt-dev libserialport-dev libhidapi-dev libsystemd-dev
  libpcap-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang clang-format clang-tidy
  systemd can-utils util-linux python3 python3-matplotlib python3-numpy python3-cvxopt python3-yaml
  tcpdump
)
if [[ "${1:-}" == "--training" ]]; then
  packages+=(libtorch-dev libopenblas0-serial)
fi

# libFuzzer's runtime: its own package on Debian 12 (on Ubuntu 22.04 it comes with clang).
if apt-cache show libclang-rt-14-dev > /dev/null 2>&1; then packages+=(libclang-rt-14-dev); fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
