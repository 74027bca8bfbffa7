#include "particle_sim/ros/mesh_builder.h"

#include <vector>

#include "particle_sim/core/surface.h"

namespace particle_sim
{
namespace ros_interface
{
ClothMesh buildClothMesh(const core::SpringNetworkBody& body, const ros::Time& stamp, const std::string& frame_id)
{
  const core::ParticlePool& p = body.particles();
  const int n = p.size();
  const auto& triangles = body.surfaceTriangles();  // without the triangles a tear cut out
  std::vector<Eigen::Vector3d> normals;
  std::vector<double> strains;
  core::vertexNormals(p.position, n, triangles, normals);
  core::vertexStrains(body, strains);

  // The vertices are the particles some triangle of the current surface uses, in particle order (a
  // jelly's inside particles are left out, and so are particles a tear left in no triangle);
  // `vertex_of` maps a particle to its vertex. Rebuilt every call: a tear changes both.
  std::vector<int> vertex_of(n, -1);
  for (const Eigen::Vector3i& t : triangles)
    for (int c = 0; c < 3; ++c)
      vertex_of[t[c]] = 0;

  ClothMesh msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frame_id;
  msg.body = body.name();
  for (int i = 0; i < n; ++i)
  {
    if (vertex_of[i] < 0) continue;
    vertex_of[i] = static_cast<int>(msg.particles.size());
    msg.particles.push_back(static_cast<std::uint32_t>(i));
    geometry_msgs::Point vertex;
    vertex.x = p.position(0, i);
    vertex.y = p.position(1, i);
    vertex.z = p.position(2, i);
    msg.mesh.vertices.push_back(vertex);
    geometry_msgs::Vector3 normal;
    normal.x = normals[i].x();
    normal.y = normals[i].y();
    normal.z = normals[i].z();
    msg.normals.push_back(normal);
    msg.strain.push_back(strains[i]);
  }
  msg.mesh.triangles.resize(triangles.size());
  for (std::size_t k = 0; k < triangles.size(); ++k)
  {
    for (int c = 0; c < 3; ++c)
      msg.mesh.triangles[k].vertex_indices[c] = static_cast<std::uint32_t>(vertex_of[triangles[k][c]]);
  }
  return msg;
}

}  // namespace ros_interface
}  // namespace particle_sim
