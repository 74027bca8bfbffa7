# Shared by the shell tests that need a ROS master: sourced, not run. Sets up a private master
# URI on a free port, a scratch folder, and cleanup of every process the test started.
#   PARTICLE_SIM_BUILD   workspace whose devel/setup.bash is sourced (default: the one scripts/common.sh
#                        uses, ../<checkout>_ws)
export PATH="/usr/bin:$PATH"
PARTICLE_SIM_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
PARTICLE_SIM_BUILD="${PARTICLE_SIM_BUILD:-$(dirname "$PARTICLE_SIM_ROOT")/$(basename "$PARTICLE_SIM_ROOT")_ws}"
set +u  # ROS's setup files read unset variables
# shellcheck disable=SC1091
source "$PARTICLE_SIM_BUILD/devel/setup.bash"
set -u

work="$(mktemp -d)"
port="$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"
export ROS_MASTER_URI="http://127.0.0.1:$port" ROS_HOSTNAME=127.0.0.1 ROS_HOME="$work" ROS_LOG_DIR="$work/log"
unset ROS_IP
node_binary="$PARTICLE_SIM_BUILD/devel/lib/particle_sim/particle_sim_node"

started=()  # pids of everything started here, stopped on exit
stop_all() {
  for pid in "${started[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
  for pid in "${started[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
  done
  rm -rf "$work"
}
trap stop_all EXIT

fail() {
  echo "FAIL: $*" >&2
  for log in "$work"/*.log; do [ -f "$log" ] && { echo "--- $log" >&2; tail -n 30 "$log" >&2; }; done
  exit 1
}

# Starts roscore on $port (log: $work/roscore_$1.log) and waits up to 30 s until it answers.
start_roscore() {
  local nodes
  roscore -p "$port" >"$work/roscore_$1.log" 2>&1 &
  roscore_pid=$!
  started+=("$roscore_pid")
  for _ in $(seq 300); do
    nodes="$(timeout 5 rosnode list 2>/dev/null)" || true
    contains "$nodes" '^/rosout$' && return 0
    sleep 0.1
  done
  fail "roscore did not start on port $port"
}

# Stops the roscore started last, and waits until it is gone.
stop_roscore() {
  kill -INT "$roscore_pid"
  for _ in $(seq 100); do kill -0 "$roscore_pid" 2>/dev/null || break; sleep 0.1; done
  kill -KILL "$roscore_pid" 2>/dev/null || true
  wait "$roscore_pid" 2>/dev/null || true
}

# Waits up to $1 seconds until file $2 matches the extended regex $3.
wait_for_log() {
  for _ in $(seq $(($1 * 10))); do grep -Eq "$3" "$2" && return 0; sleep 0.1; done
  return 1
}

# True if text $1 has a line matching the extended regex $2 (no pipe: under pipefail, grep -q
# ending a pipe early fails the writer).
contains() { grep -Eq -- "$2" <<<"$1"; }

# Waits up to $1 seconds until service $2 is registered with the master.
wait_for_service() {
  local services
  for _ in $(seq $(($1 * 5))); do
    services="$(timeout 5 rosservice list 2>/dev/null)" || true
    contains "$services" "^$2\$" && return 0
    sleep 0.2
  done
  return 1
}
