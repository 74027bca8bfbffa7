#include "particle_sim/scene/obj_mesh.h"

#include <cstdlib>
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
        mesh.triangles.emplace_back(corners[0], corners[k], corners[k + 1]);
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

core::Status loadObjFile(const std::string& path, ObjMesh& mesh)
{
  std::ifstream in(path);
  if (!in) return core::Status::failure(path + ": cannot open the mesh file");
  std::stringstream text;
  text << in.rdbuf();
  return parseObj(text.str(), path, mesh);
}

}  // namespace scene
}  // namespace particle_sim
