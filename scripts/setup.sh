#!/usr/bin/env bash
# Installs the Debian bookworm packages Downwash Lab needs, then configures and builds it.
# Idempotent: run it again after a pull. Needs root (or sudo) for apt-get.
#   scripts/setup.sh            install + build everything (build/)
#   DW_SKIP_BUILD=1 scripts/setup.sh   install only
#   DW_BUILD_TARGETS="dw-tests" scripts/setup.sh   build only those targets (scripts/test.sh)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)

packages=(
  build-essential cmake ninja-build pkg-config git
  libfastrtps-dev libfastcdr-dev fastddsgen fastdds-tools libtinyxml2-dev
  libcli11-dev libyaml-cpp-dev nlohmann-json3-dev libeigen3-dev
  libzstd-dev liblz4-dev libisal-dev zlib1g-dev libgpiod-dev libopencv-dev libssl-dev
  libtorch-dev libceres-dev libboost-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  iproute2 procps python3 clang-format
)

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
  "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -q
  "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
else
  echo "setup: all Debian packages present"
fi

if [ "${DW_SKIP_BUILD:-0}" = "1" ]; then exit 0; fi
cmake -S "$here" -B "$here/build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo ${DW_CMAKE_ARGS:-}
start=$SECONDS
cmake --build "$here/build" -j "$(nproc)" --target ${DW_BUILD_TARGETS:-all}
echo "setup: built ${DW_BUILD_TARGETS:-all} in $((SECONDS - start)) s"
