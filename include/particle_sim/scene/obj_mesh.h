#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
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

/// Bounds checked before and while reading, so that no file can exhaust memory: the file size
/// [bytes], the 'v' lines and the triangles (after polygons are split into fans).
constexpr std::uintmax_t kMaxObjFileBytes = 64u * 1024u * 1024u;
constexpr std::size_t kMaxObjVertices = 1000000;
constexpr std::size_t kMaxObjTriangles = 2000000;

/// Parses OBJ text: 'v', 'vt' and 'f' (v, v/vt, v//vn, v/vt/vn; 1-based or negative indices).
/// Other lines are ignored. Refuses more than kMaxObjVertices vertices or kMaxObjTriangles
/// triangles, and triangles of zero area (they have no normal). Errors name the line.
core::Status parseObj(const std::string& text, const std::string& source, ObjMesh& mesh);
/// Reads and parses an OBJ file: only a regular file (or a link to one) of at most
/// kMaxObjFileBytes; its size is checked before anything is read.
core::Status loadObjFile(const std::string& path, ObjMesh& mesh);

/// Whether the triangle (a, b, c) has no area: |(b − a) × (c − a)| <= 1e-12 |b − a| |c − a|
/// (its corners are on one line, up to rounding).
bool zeroArea(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

}  // namespace scene
}  // namespace particle_sim
