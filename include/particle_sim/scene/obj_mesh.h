#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "particle_sim/core/status.h"

namespace particle_sim
{
namespace scene
{
/// A triangle mesh read from a Wavefront OBJ file.
struct ObjMesh
{
  std::vector<Eigen::Vector3d> vertices;   ///< 'v' lines [file units]
  std::vector<Eigen::Vector3i> triangles;  ///< 'f' lines, 0-based; polygons split into fans
  std::vector<Eigen::Vector2d> uvs;        ///< per vertex, from 'vt' via the faces; empty when the file has none
};

/// Parses OBJ text: 'v', 'vt' and 'f' (v, v/vt, v//vn, v/vt/vn; 1-based or negative indices).
/// Other lines are ignored. Errors name the line.
core::Status parseObj(const std::string& text, const std::string& source, ObjMesh& mesh);
core::Status loadObjFile(const std::string& path, ObjMesh& mesh);

}  // namespace scene
}  // namespace particle_sim
