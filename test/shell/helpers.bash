# Helpers for the shell tests of test/shell/ (sourced, never run: scripts/test runs only *.sh).
#
#   source "$(dirname "$0")/helpers.bash"
#   start_roscore            # a master of its own on a free port; ROS_MASTER_URI exported;
#                            # stopped (with every child) when the script exits
#   fail "message"           # prints "FAIL: message" and exits 1

fail() {
  echo "FAIL: $*" >&2
  exit 1
}

# A TCP port nobody listens on now.
free_port() {
  /usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

_helpers_pids=()
_helpers_cleanup() {
  local pid
  for pid in "${_helpers_pids[@]}"; do
    kill -INT "$pid" 2>/dev/null || true
  done
  for pid in "${_helpers_pids[@]}"; do
    wait "$pid" 2>/dev/null || true
  done
}
trap _helpers_cleanup EXIT

# Runs "$@" in the background and stops it (SIGINT) when the script exits.
background() {
  "$@" &
  _helpers_pids+=("$!")
}

# Starts roscore on a free port with its logs under a temporary ROS_HOME, and waits until it answers.
start_roscore() {
  local port
  port="$(free_port)"
  export ROS_MASTER_URI="http://127.0.0.1:$port"
  export ROS_HOME="${ROS_HOME:-$(mktemp -d)}"
  background roscore -p "$port" >"$ROS_HOME/roscore.out" 2>&1
  local tries=0
  until rosparam get /run_id >/dev/null 2>&1; do
    tries=$((tries + 1))
    [ "$tries" -lt 150 ] || fail "roscore on port $port did not answer within 30 s"
    sleep 0.2
  done
}

# Waits (up to $2 seconds, default 30) until the service $1 is advertised.
wait_for_service() {
  local deadline=$((SECONDS + ${2:-30}))
  until rosservice list 2>/dev/null | grep -qx "$1"; do
    [ "$SECONDS" -lt "$deadline" ] || fail "service $1 did not appear within ${2:-30} s"
    sleep 0.2
  done
}
