# Puts the built particle_sim on the ROS path of this shell:
#   source scripts/env.sh
# after which roslaunch particle_sim ..., rosrun particle_sim ... and rosservice call ... work.
# It sources the devel space of the package's catkin workspace (PARTICLE_SIM_BUILD, default
# ../particle_sim_ws beside the checkout; see scripts/common.sh) and prints the workspace's path.
_particle_sim_root="$(cd "$(dirname "${BASH_SOURCE[0]:-$0}")/.." && pwd)"
_particle_sim_ws="$(realpath -m "${PARTICLE_SIM_BUILD:-$(dirname "$_particle_sim_root")/$(basename "$_particle_sim_root")_ws}")"
export PATH="/usr/bin:$PATH"
if [ -f "$_particle_sim_ws/devel/setup.bash" ]; then
  # shellcheck disable=SC1091
  source "$_particle_sim_ws/devel/setup.bash"
  echo "particle_sim: workspace $_particle_sim_ws (devel space sourced)" >&2
else
  echo "particle_sim: not built yet in $_particle_sim_ws; run scripts/test or scripts/demo first" >&2
fi
unset _particle_sim_root _particle_sim_ws
