# Shared by the Quick start scripts: install what is missing, build in a catkin workspace inside the
# clone (.ws/, ignored by git), and set up the environment. Sourced, not run.

# The pyenv python3 some machines put first on PATH lacks catkin's Python modules.
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH

REPO_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
WS_DIR=${LASER_RAYCAST_WS:-$REPO_DIR/.ws}
JOBS=${LASER_RAYCAST_JOBS:-$(nproc)}

# Everything the package needs to build, test (clang: the fuzz harnesses; PCL: reading the point
# layouts as SLAM packages do), run the demo and benchmark, from Debian 12's archive.
APT_PACKAGES=(
  build-essential cmake catkin python3-catkin-pkg
  libeigen3-dev libassimp-dev liburdfdom-dev liburdfdom-headers-dev liborocos-kdl-dev
  libboost-program-options-dev libpng-dev pybind11-dev python3-dev python3-numpy python3-pytest
  libroscpp-dev libroslib-dev libtf2-ros-dev libtf2-eigen-dev libtf2-geometry-msgs-dev
  libsensor-msgs-dev libgeometry-msgs-dev libnav-msgs-dev libstd-msgs-dev ros-std-msgs
  ros-geometry-msgs python3-rosservice
  ros-message-generation ros-message-runtime libnodeletlib-dev libnodeletlib-tools libtopic-tools-dev
  libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure libdiagnostic-updater-dev
  libdiagnostic-msgs-dev librosbag-storage-dev libtf2-msgs-dev libyaml-cpp-dev python3-rosbag
  librostest-dev libgtest-dev python3-rostest python3-roslaunch python3-rosmaster python3-rostopic
  python3-rospy python3-tf2-ros python3-sensor-msgs python3-geometry-msgs python3-std-msgs
  rosbash ros-robot-state-publisher
  libembree-dev libbullet-dev python3-matplotlib catkin-lint libpcl-dev
  clang libclang-rt-dev
)

log() { echo "[laser_raycast] $*" >&2; }

install_missing() {
  local missing=()
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  if [ "$(id -u)" -ne 0 ]; then
    log "missing packages: ${missing[*]}; run as root (or install them with sudo apt-get install)"
    return 1
  fi
  log "installing ${#missing[@]} packages with apt-get: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q >&2 && apt-get install -y -q --no-install-recommends "${missing[@]}" >&2
}

# The build type and further CMake options (test.sh --sanitize changes them).
BUILD_TYPE=Release
CMAKE_OPTIONS=()

build_workspace() {  # extra arguments go to catkin_make (e.g. a target)
  mkdir -p "$WS_DIR/src"
  [ -e "$WS_DIR/src/laser_raycast" ] || ln -s "$REPO_DIR" "$WS_DIR/src/laser_raycast"
  log "building in $WS_DIR"
  (cd "$WS_DIR" &&
    catkin_make -j"$JOBS" -DCMAKE_BUILD_TYPE="$BUILD_TYPE" ${CMAKE_OPTIONS[@]+"${CMAKE_OPTIONS[@]}"} \
      "$@" >&2)
}

source_workspace() {
  # setup.bash reads unset variables; relax nounset around it.
  set +u
  # shellcheck disable=SC1091
  source "$WS_DIR/devel/setup.bash"
  set -u
}
