#!/usr/bin/env bash
# Install what the firmware-in-the-loop tests need (tests/firmware/): the Arduino AVR core,
# avr-gcc and avr-libc to compile the sketches, simavr and its headers/parts to run them,
# gcc and libelf to build the harness (firmware/sim/labkit_simavr.c). Debian/Ubuntu only.
# Idempotent: does nothing when everything is present. Called by .ci/run before the tests.
set -euo pipefail
PACKAGES=(arduino-core-avr gcc-avr avr-libc simavr libsimavr-dev libsimavrparts1 libelf-dev gcc)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "firmware toolchain: all installed"
  exit 0
fi
if ! command -v apt-get >/dev/null; then
  echo "firmware toolchain: no apt-get; install ${missing[*]} by hand (the firmware tests skip)" >&2
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null && sudo -n true 2>/dev/null; then SUDO="sudo -n"; else
    echo "firmware toolchain: not root and no sudo; missing ${missing[*]} (the firmware tests skip)" >&2
    exit 0
  fi
fi
echo "firmware toolchain: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
