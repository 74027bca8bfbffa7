# Helpers for the shell tests of test/shell/ (sourced, never run: scripts/test runs only *.sh).
#
#   source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"
#
# Sourcing it puts /usr/bin first on PATH (Debian's python3 and ROS tools), makes a scratch folder
# $work, and on exit stops everything started with `background` or `start_roscore` (SIGINT, then
# SIGKILL after 5 s) and removes $work. ROS_HOME (unless set) and ROS_LOG_DIR are inside $work;
# ROS_HOSTNAME is 127.0.0.1.
#
#   use_devel_space          sources $PARTICLE_SIM_BUILD/devel/setup.bash (default: the workspace
#                            scripts/common.sh uses, ../<checkout>_ws) and sets $node_binary; for a
#                            test also run by hand (scripts/test has sourced it already)
#   start_roscore [NAME]     a master of its own (log $work/roscore[_NAME].log) on a free port,
#                            ROS_MASTER_URI exported; called again after stop_roscore, the same port
#   stop_roscore             stops the master started last and waits until it is gone
#   background CMD...        runs CMD in the background (pid in $background_pid), stopped on exit
#   "${nodelet_manager[@]}" ARGS...   the command of Debian's nodelet manager (rosrun nodelet nodelet
#                            manager), through rosrun --prefix "$PARTICLE_SIM_MANAGER_PREFIX" when that
#                            is set (scripts/test --sanitize preloads the sanitizer runtime there: the
#                            manager itself is not instrumented); rosrun execs it, so $background_pid
#                            is the manager's pid
#   free_port                prints a TCP port nobody listens on now, below the kernel's ephemeral
#                            range (ip_local_port_range), so that no outgoing connection is given it
#                            before the server that asked binds it
#   wait_for_service NAME [SECONDS]   until the master lists service NAME (default 30 s); 1 if not
#   wait_for_log SECONDS FILE REGEX   until FILE matches the extended REGEX; 1 if not
#   contains TEXT REGEX      true if a line of TEXT matches the extended REGEX
#   running PID              true while process PID exists and is not a zombie
#   fail "message"           prints "FAIL: message" and the last lines of $work/*.log, exits 1

export PATH="/usr/bin:$PATH"
_helpers_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"

work="$(mktemp -d)"
export ROS_HOME="${ROS_HOME:-$work}" ROS_LOG_DIR="$work/log" ROS_HOSTNAME=127.0.0.1
unset ROS_IP

started=()  # pids of everything started here, stopped on exit
_helpers_cleanup() {
  local pid
  for pid in "${started[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
  for pid in "${started[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
  done
  rm -rf "$work"
}
trap _helpers_cleanup EXIT

fail() {
  echo "FAIL: $*" >&2
  local log
  for log in "$work"/*.log; do [ -f "$log" ] && { echo "--- $log" >&2; tail -n 30 "$log" >&2; }; done
  exit 1
}

use_devel_space() {
  local root
  root="$(cd "$_helpers_dir/../.." && pwd)"
  PARTICLE_SIM_ROOT="${PARTICLE_SIM_ROOT:-$root}"
  PARTICLE_SIM_BUILD="${PARTICLE_SIM_BUILD:-$(dirname "$root")/$(basename "$root")_ws}"
  set +u  # ROS's setup files read unset variables
  # shellcheck disable=SC1091
  source "$PARTICLE_SIM_BUILD/devel/setup.bash"
  set -u
  node_binary="$PARTICLE_SIM_BUILD/devel/lib/particle_sim/particle_sim_node"
}

free_port() {
  /usr/bin/python3 "$_helpers_dir/../../scripts/free_port.py"
}

background() {
  "$@" &
  background_pid=$!
  started+=("$background_pid")
}

nodelet_manager=(rosrun nodelet nodelet manager)
[ -z "${PARTICLE_SIM_MANAGER_PREFIX:-}" ] || nodelet_manager=(rosrun --prefix "$PARTICLE_SIM_MANAGER_PREFIX" nodelet nodelet manager)

# Runs the bench program $1 (particle_sim_perf or particle_sim_bullet_peer) on its case $2 with
# --quick, its CSV into the file $3; prints what it printed, and fails the test with that if it fails.
run_quick_case() {
  local out
  out="$(rosrun particle_sim "$1" --only "$2" --quick --out "$3" 2>&1)" || { echo "$out"; fail "$1 --only $2 --quick"; }
  echo "$out"
}

# scripts/performance_report.py on the committed run (docs/performance/performance.csv) without its
# rows of the case $1 (none left out when $1 is empty) and with the rows of the CSV $2 added; the page
# goes to $work/report.md, its plots to $work/plots.
report_with_rows() {
  if [ -n "$1" ]; then
    grep -v "^$1," "$PARTICLE_SIM_ROOT/docs/performance/performance.csv" >"$work/report.csv"
  else
    cp "$PARTICLE_SIM_ROOT/docs/performance/performance.csv" "$work/report.csv"
  fi
  tail -n +2 "$2" >>"$work/report.csv"
  mkdir -p "$work/plots"
  /usr/bin/python3 "$PARTICLE_SIM_ROOT/scripts/performance_report.py" --csv "$work/report.csv" \
    --doc "$work/report.md" --plots "$work/plots" >/dev/null
}

# True if text $1 has a line matching the extended regex $2 (no pipe: under pipefail, grep -q
# ending a pipe early fails the writer).
contains() { grep -Eq -- "$2" <<<"$1"; }

# True while process $1 runs. Its state is read once: a zombie that this shell reaps (on SIGCHLD)
# between a `kill -0` and a `ps` must not pass for a live process.
running() {
  local state
  state="$(ps -o stat= -p "$1" 2>/dev/null || true)"
  [ -n "$state" ] && [ "${state:0:1}" != Z ]
}

start_roscore() {
  local nodes
  roscore_port="${roscore_port:-$(free_port)}"
  export ROS_MASTER_URI="http://127.0.0.1:$roscore_port"
  background roscore -p "$roscore_port" >"$work/roscore${1:+_$1}.log" 2>&1
  roscore_pid=$background_pid
  for _ in $(seq 300); do
    nodes="$(timeout 5 rosnode list 2>/dev/null)" || true
    contains "$nodes" '^/rosout$' && return 0
    sleep 0.1
  done
  fail "roscore did not start on port $roscore_port"
}

stop_roscore() {
  kill -INT "$roscore_pid"
  for _ in $(seq 100); do kill -0 "$roscore_pid" 2>/dev/null || break; sleep 0.1; done
  kill -KILL "$roscore_pid" 2>/dev/null || true
  wait "$roscore_pid" 2>/dev/null || true
}

wait_for_log() {
  for _ in $(seq $(($1 * 10))); do grep -Eq "$3" "$2" && return 0; sleep 0.1; done
  return 1
}

wait_for_service() {
  local services
  for _ in $(seq $((${2:-30} * 5))); do
    services="$(timeout 5 rosservice list 2>/dev/null)" || true
    contains "$services" "^$1\$" && return 0
    sleep 0.2
  done
  return 1
}
