#!/usr/bin/env bash
# Check the system tools the set-up step needs, naming the Debian package of any that is missing.
missing=()
command -v "${PYTHON:-python3}" > /dev/null || missing+=("python3 (Debian package python3)")
"${PYTHON:-python3}" -c 'import sys; assert sys.version_info[:2] == (3, 11)' 2> /dev/null ||
  missing+=("Python 3.11 as ${PYTHON:-python3} (the ROS 2 Jazzy wheels are built for it)")
"${PYTHON:-python3}" -c 'import venv, ensurepip' 2> /dev/null ||
  missing+=("the venv module (Debian package python3.11-venv)")
command -v cmake > /dev/null || missing+=("cmake (Debian package cmake)")
command -v cc > /dev/null || missing+=("a C compiler (Debian package gcc)")
command -v c++ > /dev/null || missing+=("a C++ compiler (Debian package g++)")
command -v make > /dev/null || missing+=("make (Debian package make)")
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] missing system packages; install them (e.g. apt-get install cmake gcc g++) and retry:" >&2
  for item in "${missing[@]}"; do echo "  - $item" >&2; done
  exit 1
fi
echo "[setup] system tools present: python3.11, venv, cmake, cc, c++, make"
