#!/usr/bin/env bash
# Check the system tools the set-up step needs, naming the Debian package of any that is missing.
# Python 3.11, 3.12 (Ubuntu 24.04's) and 3.13: the ROS 2 Jazzy wheels are built for each.
SUPPORTED="3.11 3.12 3.13"
python=${PYTHON:-python3}
missing=()
version=$("$python" -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2> /dev/null)
if [ -z "$version" ]; then
  missing+=("$python (Debian package python3)")
elif [[ " $SUPPORTED " != *" $version "* ]]; then
  missing+=("Python 3.11, 3.12 or 3.13 as $python (it is $version; the ROS 2 Jazzy wheels are built for those): make PYTHON=python3.12")
elif ! "$python" -c 'import venv, ensurepip' 2> /dev/null; then
  missing+=("the venv module (Debian package python$version-venv)")
fi
command -v cmake > /dev/null || missing+=("cmake (Debian package cmake)")
command -v cc > /dev/null || missing+=("a C compiler (Debian package gcc)")
command -v c++ > /dev/null || missing+=("a C++ compiler (Debian package g++)")
command -v make > /dev/null || missing+=("make (Debian package make)")
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] missing system packages; install them (e.g. apt-get install cmake gcc g++) and retry:" >&2
  for item in "${missing[@]}"; do echo "  - $item" >&2; done
  exit 1
fi
echo "[setup] system tools present: python$version, venv, cmake, cc, c++, make"
