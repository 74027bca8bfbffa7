# The sources of particle_sim_ros_conversions (the node's pure conversions: requests to definitions,
# core state to messages, status and parameters), relative to the package root. One list for the
# catkin library and for the fuzz targets' build (test/fuzz/CMakeLists.txt), so that a conversion
# that comes to depend on another file cannot leave the fuzz build unlinkable unnoticed.
set(PARTICLE_SIM_ROS_CONVERSIONS_SOURCES
  src/ros/marker_builder.cpp
  src/ros/mesh_builder.cpp
  src/ros/point_cloud_builder.cpp
  src/ros/pin_wrench.cpp
  src/ros/grasps.cpp
  src/ros/dragging.cpp
  src/ros/request_conversions.cpp
  src/ros/material_conversions.cpp
  src/ros/status_report.cpp
  src/ros/parameters.cpp
  src/ros/spring_constants.cpp)
