#include "particle_sim/scene/obj_mesh.h"

#include <Eigen/Geometry>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace particle_sim
{
namespace scene
{
namespace
{
// Resolves an OBJ index (1-based, or negative counting back from the last one read) to 0-based.
bool resolveIndex(long long index, std::size_t count, int& out)
{
  const long long resolved = index > 0 ? index - 1 : static_cast<long long>(count) + index;
  if (index == 0 || resolved < 0 || resolved >= static_cast<long long>(count)) return false;
  out = static_cast<int>(resolved);
  return true;
}
}  // namespace

core::Status parseObj(const std::string& text, const std::string& source, ObjMesh& mesh)
{
  mesh = ObjMesh{};
  std::vector<Eigen::Vector2d> texture_coordinates;
  std::vector<int> uv_of_vertex;  // per vertex: index into texture_coordinates, or -1
  std::istringstream lines(text);
  std::string line;
  int number = 0;
  auto fail = [&](const std::string& message) {
    return core::Status::failure(source + ":" + std::to_string(number) + ": " + message);
  };
  while (std::getline(lines, line))
  {
    ++number;
    std::istringstream in(line);
    std::string tag;
    if (!(in >> tag) || tag[0] == '#') continue;
    if (tag == "v")
    {
      Eigen::Vector3d v;
      if (!(in >> v.x() >> v.y() >> v.z()) || !v.allFinite()) return fail("a vertex needs three numbers: v x y z");
      if (mesh.vertices.size() == kMaxObjVertices)
        return fail("more than " + std::to_string(kMaxObjVertices) +
                    " vertices: an OBJ mesh may have at most that many");
      mesh.vertices.push_back(v);
      uv_of_vertex.push_back(-1);
    }
    else if (tag == "vt")
    {
      Eigen::Vector2d uv;
      if (!(in >> uv.x() >> uv.y()) || !uv.allFinite()) return fail("a texture coordinate needs two numbers: vt u v");
      texture_coordinates.push_back(uv);
    }
    else if (tag == "f")
    {
      // Corners "v", "v/vt", "v//vn" or "v/vt/vn"; a polygon becomes a fan of triangles.
      std::vector<int> corners;
      std::string corner;
      while (in >> corner)
      {
        long long v = 0, vt = 0;
        char* end = nullptr;
        v = std::strtoll(corner.c_str(), &end, 10);
        int vertex = 0;
        if (end == corner.c_str() || !resolveIndex(v, mesh.vertices.size(), vertex))
          return fail("face corner '" + corner + "' names no vertex read so far");
        if (*end == '/' && end[1] != '/' && end[1] != '\0')
        {
          vt = std::strtoll(end + 1, nullptr, 10);
          int uv = 0;
          if (!resolveIndex(vt, texture_coordinates.size(), uv))
            return fail("face corner '" + corner + "' names no texture coordinate read so far");
          if (uv_of_vertex[vertex] < 0) uv_of_vertex[vertex] = uv;
        }
        corners.push_back(vertex);
      }
      if (corners.size() < 3) return fail("a face needs at least three corners");
      for (std::size_t k = 1; k + 1 < corners.size(); ++k)
      {
        if (mesh.triangles.size() == kMaxObjTriangles)
          return fail("more than " + std::to_string(kMaxObjTriangles) +
                      " triangles: an OBJ mesh may have at most that many");
        const Eigen::Vector3i t(corners[0], corners[k], corners[k + 1]);
        if (zeroArea(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]))
          return fail("the face has a triangle of zero area (vertices " + std::to_string(t[0] + 1) + ", " +
                      std::to_string(t[1] + 1) + ", " + std::to_string(t[2] + 1) +
                      " are on one line or repeated): it has no normal; remove it from the mesh");
        mesh.triangles.push_back(t);
      }
    }
  }
  if (mesh.vertices.empty() || mesh.triangles.empty())
    return core::Status::failure(source + ": no triangles: an OBJ mesh needs 'v' and 'f' lines");

  // Texture coordinates per vertex, when every vertex used by a face has one.
  bool all_uv = !texture_coordinates.empty();
  for (const Eigen::Vector3i& t : mesh.triangles)
    for (int c = 0; c < 3; ++c)
      all_uv = all_uv && uv_of_vertex[t[c]] >= 0;
  if (all_uv)
  {
    mesh.uvs.assign(mesh.vertices.size(), Eigen::Vector2d::Zero());
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
      if (uv_of_vertex[i] >= 0) mesh.uvs[i] = texture_coordinates[uv_of_vertex[i]];
  }
  return core::Status::success();
}

bool zeroArea(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c)
{
  const Eigen::Vector3d e1 = b - a, e2 = c - a;
  return e1.cross(e2).norm() <= 1e-12 * e1.norm() * e2.norm();
}

core::Status loadObjFile(const std::string& path, ObjMesh& mesh)
{
  // What the path is, before opening it: a device (/dev/zero), a fifo or a folder never ends or
  // is not a mesh.
  std::error_code error;
  const std::filesystem::file_status status = std::filesystem::status(path, error);
  if (error || !std::filesystem::exists(status))
    return core::Status::failure(path + ": cannot open the mesh file (" +
                                 (error ? error.message() : std::string("no such file")) + ")");
  if (!std::filesystem::is_regular_file(status))
    return core::Status::failure(path + ": is not a regular file; a mesh must be an OBJ file");
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  if (error) return core::Status::failure(path + ": cannot read the mesh file's size (" + error.message() + ")");
  if (size > kMaxObjFileBytes)
    return core::Status::failure(path + ": is " + std::to_string(size) + " bytes, over the limit of " +
                                 std::to_string(kMaxObjFileBytes) + " bytes (64 MiB) for an OBJ mesh");

  // Read at most one byte more than the limit, in case the file grew since.
  std::ifstream in(path, std::ios::binary);
  if (!in) return core::Status::failure(path + ": cannot open the mesh file");
  std::string text(static_cast<std::size_t>(size) + 1, '\0');
  in.read(&text[0], static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxObjFileBytes)
    return core::Status::failure(path + ": is over the limit of " + std::to_string(kMaxObjFileBytes) +
                                 " bytes (64 MiB) for an OBJ mesh");
  return parseObj(text, path, mesh);
}

}  // namespace scene
}  // namespace particle_sim
