#!/usr/bin/env bash
# Installs every build/run/test dependency of overstep from Debian's packages.
# Idempotent: a second run installs nothing (it only checks what is missing).
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev
  libdart-all-dev libdart-external-ikfast-dev
  libnlopt-cxx-dev libfcl-dev liburdfdom-dev
  liblcm-dev liblcm-bin liblcm-java libjchart2d-java libglib2.0-dev
  default-jdk-headless
  libyaml-cpp-dev nlohmann-json3-dev libcli11-dev libspdlog-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  iproute2 python3-matplotlib python3-numpy clang-format
  # `overstep spy` is a Swing window (a full JRE); the monitoring tests use it and the report and
  # the terminal monitor as a person does (issue 21): an X server, a mouse, a browser, a terminal,
  # screenshots.
  openjdk-17-jre fonts-dejavu-core xvfb xdotool chromium tmux imagemagick
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "setup: installing ${#missing[@]} missing packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done"
