// particle_sim_run, run as a program: `--integrator NAME` reaches every spring body of the scene
// (rope, spring network, grid cloth, mesh cloth, jelly), whatever integrator the scene gives each.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

namespace
{
// Runs `command` and returns what it wrote on stdout; `exit_code` gets its exit status.
std::string run(const std::string& command, int& exit_code)
{
  std::string output;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return output;
  std::array<char, 4096> buffer;
  while (std::fgets(buffer.data(), buffer.size(), pipe))
    output += buffer.data();
  const int status = pclose(pipe);
  exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return output;
}
}  // namespace

TEST(SceneRunTool, IntegratorOptionReachesEverySpringBody)
{
  // Every spring body sets its own integrator, unlike the world's default: the option must replace
  // each of them, not only the default.
  const std::string scene = ::testing::TempDir() + "scene_run_tool_test_" + std::to_string(getpid()) + ".yaml";
  std::ofstream(scene) << "world: {integrator: implicit_euler}\n"
                          "bodies:\n"
                          "  - {name: f, kind: emitter, type: fountain}\n"
                          "  - {name: r, kind: rope, integrator: symplectic_euler}\n"
                          "  - {name: n, kind: spring_network, integrator: rk4,\n"
                          "     particles: [{position: [0, 0, 1]}, {position: [1, 0, 1]}],\n"
                          "     springs: [{particles: [0, 1], stiffness: 10}]}\n"
                          "  - {name: g, kind: cloth, integrator: verlet}\n"
                          "  - {name: m, kind: cloth, integrator: symplectic_euler,\n"
                          "     vertices: [[0, 0, 1], [1, 0, 1], [0, 1, 1]], triangles: [[0, 1, 2]]}\n"
                          "  - {name: j, kind: jelly, integrator: rk4}\n";
  int exit_code = -1;
  const std::string output =
      run(std::string(PARTICLE_SIM_RUN) + " " + scene + " --duration 0.002 --integrator auto", exit_code);
  std::remove(scene.c_str());
  EXPECT_EQ(exit_code, 0) << output;
  // `auto` reports its choice for each body that runs it, and only for those.
  for (const char* body : {"r", "n", "g", "m", "j"})
    EXPECT_NE(output.find(std::string("body '") + body + "' auto: "), std::string::npos) << body << "\n" << output;
  EXPECT_EQ(output.find("body 'f' auto"), std::string::npos) << output;
}

TEST(SceneRunTool, SummaryShowsCollisionCountsOnlyForBodiesThatEnableSelfCollision)
{
  // Two cloths that collide with themselves and each other, 5 mm apart (closer than their thickness),
  // and a rope and a cloth that do not.
  const std::string scene =
      ::testing::TempDir() + "scene_run_tool_self_collision_test_" + std::to_string(getpid()) + ".yaml";
  std::ofstream(scene)
      << "world: {ground: {enabled: false}}\n"
         "bodies:\n"
         "  - {name: lower, kind: cloth, resolution: [5, 5], origin: [0, 0, 1], edge_u: [0.2, 0, 0],\n"
         "     edge_v: [0, 0.2, 0], self_collision: {enabled: true, thickness: 0.01}}\n"
         "  - {name: plain, kind: rope}\n"
         "  - {name: sheet, kind: cloth, resolution: [3, 3], origin: [2, 0, 1]}\n"
         "  - {name: upper, kind: cloth, resolution: [5, 5], origin: [0, 0, 1.005], edge_u: [0.2, 0, 0],\n"
         "     edge_v: [0, 0.2, 0], self_collision: {enabled: true, thickness: 0.01}}\n";
  int exit_code = -1;
  const std::string output = run(std::string(PARTICLE_SIM_RUN) + " " + scene + " --duration 0.003", exit_code);
  std::remove(scene.c_str());
  EXPECT_EQ(exit_code, 0) << output;
  // The summary line of each body that says what its collision passes found, or empty.
  auto contactLine = [&output](const std::string& body) {
    std::istringstream lines(output);
    for (std::string line; std::getline(lines, line);)
      if (line.rfind("body '" + body + "': ", 0) == 0 && line.find(" contacts, ") != std::string::npos) return line;
    return std::string();
  };
  for (const char* body : {"lower", "upper"})
  {
    const std::string line = contactLine(body);
    EXPECT_NE(line.find(" collisions, "), std::string::npos) << body << "\n" << output;
    EXPECT_NE(line.find(" impact-zone particles over 3 steps (self_collision, thickness 0.01 m)"), std::string::npos)
        << body << "\n"
        << output;
  }
  EXPECT_NE(output.find("\nself_collision: "), std::string::npos) << output;
  EXPECT_EQ(contactLine("plain"), "") << output;
  EXPECT_EQ(contactLine("sheet"), "") << output;
}
