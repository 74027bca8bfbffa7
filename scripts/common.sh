# Shared by scripts/demo, test, bench, screenshots: installs what is missing and builds the package
# into a catkin workspace outside its source folder. Sourced, not run.
#
# The workspace is PARTICLE_SIM_BUILD (default: ../particle_sim_ws beside this checkout, i.e.
# "$(dirname ROOT)/$(basename ROOT)_ws"): <ws>/build is the CMake build folder, <ws>/devel the
# devel space (source <ws>/devel/setup.bash, or scripts/env.sh), <ws>/install the install space.
# It lies outside the package because rosrun never looks below a package's own build/ folder.

PARTICLE_SIM_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

# Sets the workspace folder and the folders inside it.
use_workspace() {
  PARTICLE_SIM_BUILD="$(realpath -m "$1")"
  PARTICLE_SIM_CMAKE_BUILD="$PARTICLE_SIM_BUILD/build"
  PARTICLE_SIM_DEVEL="$PARTICLE_SIM_BUILD/devel"
  PARTICLE_SIM_INSTALL="$PARTICLE_SIM_BUILD/install"
}
use_workspace "${PARTICLE_SIM_BUILD:-$(dirname "$PARTICLE_SIM_ROOT")/$(basename "$PARTICLE_SIM_ROOT")_ws}"

# Extra CMake arguments of the first configure of a workspace (scripts/test --sanitize sets them).
PARTICLE_SIM_CMAKE_ARGS=()

# Debian packages the package needs to build, run and test (ROS 1 from Debian's own archive).
PARTICLE_SIM_PACKAGES=(
  build-essential cmake catkin ros-core-dev libroscpp-dev libtf2-ros-dev ros-visualization-msgs
  ros-geometry-msgs ros-shape-msgs ros-std-msgs ros-std-srvs ros-sensor-msgs libsensor-msgs-dev libros-rosgraph-msgs-dev ros-message-generation
  libyaml-cpp-dev libeigen3-dev libgtest-dev librostest-dev python3-rostest python3-rospy
  python3-roslaunch python3-rosservice python3-rostopic rosbash
  libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure libdiagnostic-updater-dev
  ros-diagnostic-msgs libnodelet-dev libnodeletlib-dev libnodeletlib-tools libbondcpp-dev pluginlib-dev
  libinteractive-markers-dev
  librosbag-dev python3-rosbag python3-rosnode python3-tf2-msgs rviz
  python3-std-msgs python3-std-srvs python3-geometry-msgs python3-shape-msgs python3-visualization-msgs
  python3-rosgraph-msgs python3-diagnostic-msgs python3-sensor-msgs
  libbullet-dev  # the peer of scripts/bench --performance (particle_sim_bullet_peer), Bullet 3.24
)

# Only for scripts/fuzz (libFuzzer comes with clang; the package build and scripts/test use gcc).
PARTICLE_SIM_FUZZ_PACKAGES=(clang-14 libclang-rt-14-dev)

# Only for the reports of scripts/bench (docs/accuracy.md, docs/validation.md): the plots.
PARTICLE_SIM_REPORT_PACKAGES=(gnuplot-nox)

# ROS tools are Python programs that need Debian's python3, not a pyenv one found first on PATH.
export PATH="/usr/bin:$PATH"

log() { printf '\033[1m[particle_sim %s]\033[0m %s\n' "$(date -u +%H:%M:%S)" "$*" >&2; }

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

# Installs the packages in "$@" that are not installed yet (idempotent; apt-get update once).
ensure_packages() {
  local missing=()
  for pkg in "$@"; do
    dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q 'install ok installed' || missing+=("$pkg")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  log "installing Debian packages: ${missing[*]}"
  as_root apt-get update -qq
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

# Configures (once) and builds the package with catkin's CMake into the workspace: CMake build
# folder <ws>/build, devel space <ws>/devel, install prefix <ws>/install. Extra arguments go to make.
# PARTICLE_SIM_CMAKE_ARGS (the sanitizer build's flags) are applied to a workspace configured before
# too, so that it builds with the flags of this checkout.
build_package() {
  mkdir -p "$PARTICLE_SIM_CMAKE_BUILD"
  if [ -f "$PARTICLE_SIM_CMAKE_BUILD/CMakeCache.txt" ] && [ ${#PARTICLE_SIM_CMAKE_ARGS[@]} -gt 0 ]; then
    cmake -B "$PARTICLE_SIM_CMAKE_BUILD" "${PARTICLE_SIM_CMAKE_ARGS[@]}" >/dev/null
  elif [ ! -f "$PARTICLE_SIM_CMAKE_BUILD/CMakeCache.txt" ]; then
    log "configuring into $PARTICLE_SIM_BUILD"
    cmake -S "$PARTICLE_SIM_ROOT" -B "$PARTICLE_SIM_CMAKE_BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 \
      -DCATKIN_DEVEL_PREFIX="$PARTICLE_SIM_DEVEL" -DCMAKE_INSTALL_PREFIX="$PARTICLE_SIM_INSTALL" \
      "${PARTICLE_SIM_CMAKE_ARGS[@]}" >/dev/null
  fi
  log "building in $PARTICLE_SIM_BUILD"
  cmake --build "$PARTICLE_SIM_CMAKE_BUILD" -- -j"$(nproc)" "$@"
}
