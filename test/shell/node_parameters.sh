#!/usr/bin/env bash
# Shell test: the node refuses unusable private parameters at start, naming the parameter, the value
# as given and the allowed range with its unit (core/limits.h), and exits with status 1.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"
use_devel_space
start_roscore

# Runs the node with the given parameters; it must exit 1 within 30 s and log $1 (a fixed string).
expect_refused() {
  local expected="$1"
  shift
  local status=0
  timeout 30 "$node_binary" __name:=particle_sim "$@" >"$work/node.log" 2>&1 || status=$?
  [ "$status" -eq 1 ] || fail "$* : exit status $status, expected 1"
  grep -qF -- "$expected" "$work/node.log" || fail "$* : no '$expected' in the log"
}
expect_refused "~real_time_factor = -1 is out of range: must be in [0, 1000] -" _real_time_factor:=-1.0
expect_refused "~real_time_factor = 1e+300 is out of range" _real_time_factor:=1.0e+300
expect_refused "~rate = 0 is out of range: must be in [0.1, 1000] Hz" _rate:=0.0
expect_refused "~rate = nan is out of range" _rate:=nan
expect_refused "~max_marker_points = 0 is out of range: must be in [1, 1e+07] points" _max_marker_points:=0 \
  _rate:=50 _real_time_factor:=1.0  # (the private parameters of the runs above stay on the master)
echo "node_parameters: passed"
