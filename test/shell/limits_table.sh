#!/usr/bin/env bash
# README.md's limits table ("Limits") is what scripts/limits_table.py generates from the headers that
# define the bounds: a changed bound without a regenerated table fails here, with the difference.
# Run by scripts/test (see its header for the environment it gives).
set -euo pipefail
: "${PARTICLE_SIM_ROOT:?run me through scripts/test}"
/usr/bin/python3 "$PARTICLE_SIM_ROOT/scripts/limits_table.py" --check
