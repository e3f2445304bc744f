#!/usr/bin/env bash
# Install everything the test suite needs, then run lint, types and tests.
# Works on a fresh Debian machine: a virtualenv in .venv, armfleet with its
# test extra (its compiled fleet path built with the machine's g++), and Debian's
# chromium for the browser tests (never a downloaded one).
set -euo pipefail
cd "$(dirname "$0")/.."

missing=()
command -v chromium >/dev/null 2>&1 || missing+=(chromium)  # the viewer's browser tests
command -v g++ >/dev/null 2>&1 || missing+=(g++)  # armfleet's C++ part (CMake: from PyPI)
command -v strace >/dev/null 2>&1 || missing+=(strace)  # the ROS 2 loopback test traces the world
if [ ${#missing[@]} -gt 0 ]; then
  echo "== installing Debian's ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${missing[@]}" >/dev/null
fi

if [ ! -x .venv/bin/python ]; then
  echo "== creating .venv"
  python3 -m venv .venv
fi
echo "== installing armfleet[test] (every extra; compiles the fleet kernel with g++)"
.venv/bin/python -m pip install -q --disable-pip-version-check -e ".[test]"
echo "== building ROS 2's tf2_msgs and control_msgs (ros_interfaces/README.md; ~3 min on 2 cores)"
.venv/bin/python -m pip install -q --disable-pip-version-check --no-build-isolation \
  ./ros_interfaces/tf2_msgs ./ros_interfaces/control_msgs

echo "== ruff"
.venv/bin/ruff check .
.venv/bin/ruff format --check .
echo "== mypy"
.venv/bin/mypy
echo "== import-linter (the rooms' layers, no import circles, a core free of the extras)"
.venv/bin/lint-imports
echo "== pytest (three workers on two cores, a file per worker: tests also wait on worlds, pages and servers)"
.venv/bin/pytest -n 3 --dist loadfile --durations=30 "$@"
