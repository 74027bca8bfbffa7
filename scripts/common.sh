# Shared by scripts/demo and scripts/test: installs what is missing and builds into build/.
# Sourced, not run.

PARTICLE_SIM_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PARTICLE_SIM_BUILD="${PARTICLE_SIM_BUILD:-$PARTICLE_SIM_ROOT/build}"  # another build directory: set it before

# Debian packages the package needs to build, run and test (ROS 1 from Debian's own archive).
PARTICLE_SIM_PACKAGES=(
  build-essential cmake catkin ros-core-dev libroscpp-dev libtf2-ros-dev ros-visualization-msgs
  ros-geometry-msgs ros-shape-msgs ros-std-msgs ros-std-srvs libros-rosgraph-msgs-dev ros-message-generation
  libyaml-cpp-dev libeigen3-dev libgtest-dev librostest-dev python3-rostest python3-rospy
  python3-roslaunch python3-rosservice python3-rostopic rosbash
  libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure libdiagnostic-updater-dev
  ros-diagnostic-msgs libnodelet-dev libnodeletlib-dev libnodeletlib-tools libbondcpp-dev pluginlib-dev
  librosbag-dev python3-rosbag python3-rosnode python3-tf2-msgs rviz
)

# ROS tools are Python programs that need Debian's python3, not a pyenv one found first on PATH.
export PATH="/usr/bin:$PATH"

log() { printf '\033[1m[particle_sim]\033[0m %s\n' "$*" >&2; }

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

# Configures (once) and builds the package into build/ with catkin's CMake, devel space in
# build/devel. Extra arguments go to make.
build_package() {
  mkdir -p "$PARTICLE_SIM_BUILD"
  if [ ! -f "$PARTICLE_SIM_BUILD/CMakeCache.txt" ]; then
    log "configuring into build/"
    cmake -S "$PARTICLE_SIM_ROOT" -B "$PARTICLE_SIM_BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 -DCATKIN_DEVEL_PREFIX="$PARTICLE_SIM_BUILD/devel" >/dev/null
  fi
  log "building"
  cmake --build "$PARTICLE_SIM_BUILD" -- -j"$(nproc)" "$@"
}
