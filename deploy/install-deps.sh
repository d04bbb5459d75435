#!/usr/bin/env bash
# Installs every Debian 12 package STAC needs to build and test. Idempotent: packages already
# present are skipped, so a second run costs a few seconds. Run as root (or with sudo).
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  ccache  # keeps compilations across builds (CMakeLists.txt: STAC_CCACHE)
  libeigen3-dev libgeographiclib-dev libpcap-dev libyaml-cpp-dev libtinyxml2-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libusb-1.0-0-dev  # gs_usb / candleLight USB-CAN adapters (drivers/can)
  nlohmann-json3-dev  # tracks and truth JSON lines (stac eval)
  libopencv-dev  # pictures (bird's-eye views, plots) in tools/, never in the per-scan loop
  libpcl-dev  # benchmarks only: PCL Euclidean clustering as the baseline of perception/segmentation
  cyclonedds-dev cyclonedds-tools  # DDS publishing edge (dds/, idl/): C API and idlc
  openssl  # deploy/dds-security.sh: the DDS Security CAs, certificates and signed documents
  libssl-dev  # dds/identity.cpp: a DDS Security private key checked against its certificate
  clang-format clang-tidy  # .ci/check-style (STYLE.md rule 14)
  clang-14 libclang-rt-14-dev  # fuzz/: libFuzzer harnesses with ASan + UBSan (fuzz/run.sh)
  libcpp-httplib-dev  # stac label: the local web page of group induction
  libwebsocketpp-dev libasio-dev  # stac view: the Foxglove WebSocket server (view)
  chromium  # tests/web: stac label's page tested in a real headless browser
  slurm-wlm  # tests/deploy: deploy/slurm-dataset.sh on a one-node cluster the test starts
)
# node and npm run the browser tests (tests/web, puppeteer-core from npm); Debian's nodejs unless
# a node is already installed (e.g. from NodeSource, whose package holds npm too).
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then packages+=(nodejs npm); fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
else
  sudo=""
  if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  echo "install-deps: done"
fi

# The web tests' npm packages (puppeteer-core for stac label's page; @foxglove/ws-protocol,
# @foxglove/schemas and ws for stac view), at the versions tests/web/package-lock.json pins
# (skipped when they are all there already).
web="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/tests/web"
if ! (cd "$web" && node -e 'const deps = require("./package.json").dependencies;
      const ok = Object.entries(deps).every(([name, want]) => {
        try { return require(`${name}/package.json`).version === want; } catch { return false; }
      });
      process.exit(ok ? 0 : 1)' 2>/dev/null); then
  echo "install-deps: npm packages for tests/web"
  (cd "$web" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
fi
