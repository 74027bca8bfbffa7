# Puts the built particle_sim on the ROS path of this shell:
#   source scripts/env.sh
# after which roslaunch particle_sim ..., rosrun particle_sim ... and rosservice call ... work.
_particle_sim_root="$(cd "$(dirname "${BASH_SOURCE[0]:-$0}")/.." && pwd)"
export PATH="/usr/bin:$PATH"
if [ -f "$_particle_sim_root/build/devel/setup.bash" ]; then
  # shellcheck disable=SC1091
  source "$_particle_sim_root/build/devel/setup.bash"
else
  echo "particle_sim: not built yet; run scripts/test or scripts/demo first" >&2
fi
unset _particle_sim_root
