// rostest: cloth and jelly through the node's services, checked in ~markers and ~meshes.

#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <tf2_ros/transform_broadcaster.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>

#include "node_listener.h"
#include "particle_sim/ClothMesh.h"
#include "particle_sim/PinParticle.h"
#include "particle_sim/RemoveBody.h"
#include "particle_sim/SetSpringConstants.h"
#include "particle_sim/SetWind.h"
#include "particle_sim/SpawnCloth.h"
#include "particle_sim/SpawnJelly.h"

using particle_sim::ClothMesh;
using particle_sim::PinParticle;
using particle_sim::RemoveBody;
using particle_sim::SetSpringConstants;
using particle_sim::SetWind;
using particle_sim::SpawnCloth;
using particle_sim::SpawnJelly;
using particle_sim_test::call;
using particle_sim_test::Listener;
using visualization_msgs::Marker;

namespace
{
// Keeps the latest ClothMesh of each body.
class MeshListener
{
public:
  explicit MeshListener(ros::NodeHandle& nh)
  {
    sub_ = nh.subscribe("/particle_sim/meshes", 20, &MeshListener::onMesh, this);
  }
  bool has(const std::string& body) const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return latest_.count(body) > 0;
  }
  ClothMesh latest(const std::string& body) const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return latest_.at(body);
  }

private:
  void onMesh(const ClothMesh::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    latest_[msg->body] = *msg;
  }
  mutable std::mutex mutex_;
  std::map<std::string, ClothMesh> latest_;
  ros::Subscriber sub_;  // last: shut down first
};

SpawnCloth::Request clothRequest(const std::string& name, double y)
{
  SpawnCloth::Request req;
  req.name = name;
  req.origin.x = -0.5;
  req.origin.y = y;
  req.origin.z = 2.0;
  req.edge_u.x = 1.0;
  req.edge_v.z = -1.0;
  req.nu = 6;
  req.nv = 5;
  req.mass = 0.1;
  req.stretch_stiffness = 400.0;
  req.stretch_damping = 0.2;
  req.shear_stiffness = 100.0;
  req.shear_damping = 0.1;
  req.bend_stiffness = 1.0;
  req.bend_damping = 0.01;
  req.named_pins = {"corner_00", "corner_10"};
  req.max_strain = 0.1;
  return req;
}

SpawnJelly::Request jellyRequest(const std::string& name)
{
  SpawnJelly::Request req;
  req.name = name;
  req.origin.x = 2.0;
  req.origin.z = 1.0;
  req.size.x = req.size.y = req.size.z = 0.4;
  req.nx = req.ny = req.nz = 4;
  req.mass = 0.5;
  req.stretch_stiffness = 2000.0;
  req.stretch_damping = 1.0;
  req.shear_stiffness = 1000.0;
  req.shear_damping = 0.5;
  req.bend_stiffness = 200.0;
  req.bend_damping = 0.2;
  return req;
}

// The ClothMesh is consistent: indices in range, one unit normal per vertex, one strain per vertex.
void expectConsistent(const ClothMesh& mesh, std::size_t vertices, std::size_t triangles)
{
  EXPECT_EQ(mesh.header.frame_id, "world");
  ASSERT_EQ(mesh.mesh.vertices.size(), vertices);
  ASSERT_EQ(mesh.mesh.triangles.size(), triangles);
  ASSERT_EQ(mesh.normals.size(), vertices);
  ASSERT_EQ(mesh.strain.size(), vertices);
  ASSERT_EQ(mesh.particles.size(), vertices);
  for (const auto& t : mesh.mesh.triangles)
    for (std::uint32_t v : t.vertex_indices)
      EXPECT_LT(v, vertices);
  for (const auto& n : mesh.normals)
    EXPECT_NEAR(std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z), 1.0, 1e-9);
  for (double s : mesh.strain)
    EXPECT_TRUE(std::isfinite(s));
}

class ClothTest : public ::testing::Test
{
protected:
  static void SetUpTestSuite()
  {
    for (const char* s :
         {"spawn_cloth", "spawn_jelly", "set_wind", "set_spring_constants", "pin_particle", "remove_body"})
      ASSERT_TRUE(ros::service::waitForService(std::string("/particle_sim/") + s, ros::Duration(30.0))) << s;
  }
  ros::NodeHandle nh_;
  Listener listener_{nh_};
  MeshListener meshes_{nh_};
};
}  // namespace

TEST_F(ClothTest, SpawnedClothIsATriangleListAndAConsistentMesh)
{
  const auto res = call<SpawnCloth>("spawn_cloth", clothRequest("towel", 1.0));
  ASSERT_TRUE(res.success) << res.message;
  ASSERT_TRUE(listener_.waitFor([&] { return listener_.latest("towel", 1).action == Marker::ADD; }));
  const Marker surface = listener_.latest("towel", 1);
  EXPECT_EQ(surface.type, Marker::TRIANGLE_LIST);
  // 5 x 4 cells, 2 triangles each, 3 points each, a colour per point.
  EXPECT_EQ(surface.points.size(), 5u * 4u * 2u * 3u);
  EXPECT_EQ(surface.colors.size(), surface.points.size());
  EXPECT_EQ(listener_.latest("towel", 2).points.size(), 2u);  // the two pinned corners

  ASSERT_TRUE(listener_.waitFor([&] { return meshes_.has("towel"); }));
  const ClothMesh first = meshes_.latest("towel");
  expectConsistent(first, 30u, 40u);
  // The triangles stay the same for the body's life; the vertices move (it falls from flat).
  ros::WallDuration(0.3).sleep();
  const ClothMesh later = meshes_.latest("towel");
  ASSERT_EQ(later.mesh.triangles.size(), first.mesh.triangles.size());
  for (std::size_t k = 0; k < first.mesh.triangles.size(); ++k)
    EXPECT_EQ(later.mesh.triangles[k].vertex_indices, first.mesh.triangles[k].vertex_indices);
  EXPECT_GT(later.header.stamp, first.header.stamp);
}

TEST_F(ClothTest, SpawnedJellyIsAClosedSurfaceInMarkersAndMeshes)
{
  const auto res = call<SpawnJelly>("spawn_jelly", jellyRequest("cube"));
  ASSERT_TRUE(res.success) << res.message;
  ASSERT_TRUE(listener_.waitFor([&] { return meshes_.has("cube"); }));
  // 6 faces of 3 x 3 quads, 2 triangles each, over the 64 - 8 outer particles.
  expectConsistent(meshes_.latest("cube"), 56u, 108u);
  // ~markers is another topic: its first array with the cube may come after the first mesh.
  ASSERT_TRUE(listener_.waitFor([&] { return listener_.latest("cube", 1).action == Marker::ADD; }));
  EXPECT_EQ(listener_.latest("cube", 1).type, Marker::TRIANGLE_LIST);
  // It falls to the ground and rests on it.
  EXPECT_TRUE(listener_.waitFor(
      [&] {
        const ClothMesh mesh = meshes_.latest("cube");
        double lowest = 1e9;
        for (const auto& v : mesh.mesh.vertices)
          lowest = std::min(lowest, v.z);
        return lowest < 0.01;
      },
      10.0));
}

TEST_F(ClothTest, ServicesActOnClothAndRemoveBodyDeletesItsMarkers)
{
  ASSERT_TRUE(call<SpawnCloth>("spawn_cloth", clothRequest("rag", -1.0)).success);
  ASSERT_TRUE(listener_.waitFor([&] { return listener_.latest("rag", 1).action == Marker::ADD; }));

  SetSpringConstants::Request k;
  k.body = "rag";
  k.spring_class = "shear";
  k.stiffness = 50.0;
  k.damping = 0.05;
  const auto set = call<SetSpringConstants>("set_spring_constants", k);
  EXPECT_TRUE(set.success) << set.message;

  PinParticle::Request pin;
  pin.body = "rag";
  pin.index = -1;  // nearest to the free bottom corner
  pin.point.x = 0.5;
  pin.point.y = -1.0;
  pin.point.z = 1.0;
  pin.target = PinParticle::Request::TARGET_CURRENT;
  const auto pinned = call<PinParticle>("pin_particle", pin);
  ASSERT_TRUE(pinned.success) << pinned.message;
  EXPECT_TRUE(listener_.waitFor([&] { return listener_.latest("rag", 2).points.size() == 3u; }));

  RemoveBody::Request remove;
  remove.name = "rag";
  ASSERT_TRUE(call<RemoveBody>("remove_body", remove).success);
  EXPECT_TRUE(listener_.waitFor([&] {
    return listener_.latest("rag", 0).action == Marker::DELETE && listener_.latest("rag", 1).action == Marker::DELETE &&
           listener_.latest("rag", 2).action == Marker::DELETE;
  }));
}

TEST_F(ClothTest, WindPushesTheHangingSheetAlongItsNormal)
{
  // The scene's sheet hangs in the xz plane (normal along y). A wind along +y pushes it to +y.
  ASSERT_TRUE(listener_.waitFor([&] { return meshes_.has("sheet"); }));
  auto meanY = [&] {
    const ClothMesh mesh = meshes_.latest("sheet");
    double y = 0.0;
    for (const auto& v : mesh.mesh.vertices)
      y += v.y / mesh.mesh.vertices.size();
    return y;
  };
  const double before = meanY();
  SetWind::Request wind;
  wind.wind.y = 8.0;
  const auto res = call<SetWind>("set_wind", wind);
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_TRUE(listener_.waitFor([&] { return meanY() > before + 0.1; })) << "mean y stayed " << meanY();
  wind.wind.y = std::nan("");
  const auto refused = call<SetWind>("set_wind", wind);
  EXPECT_FALSE(refused.success);
  EXPECT_NE(refused.message.find("wind = [0, nan, 0] is not finite"), std::string::npos) << refused.message;
  wind.wind.y = 0.0;
  EXPECT_TRUE(call<SetWind>("set_wind", wind).success);
}

TEST_F(ClothTest, SphereFollowsItsTfFrame)
{
  // The scene's sphere 'ball' follows the tf frame 'ball_frame', broadcast here.
  tf2_ros::TransformBroadcaster broadcaster;
  geometry_msgs::TransformStamped tf;
  tf.header.frame_id = "world";
  tf.child_frame_id = "ball_frame";
  tf.transform.translation.x = -2.0;
  tf.transform.translation.y = 1.5;
  tf.transform.translation.z = 0.75;
  tf.transform.rotation.w = 1.0;
  EXPECT_TRUE(listener_.waitFor([&] {
    tf.header.stamp = ros::Time::now();
    broadcaster.sendTransform(tf);
    const Marker ball = listener_.latest("_colliders", 0);
    return ball.action == Marker::ADD && std::abs(ball.pose.position.x + 2.0) < 1e-9 &&
           std::abs(ball.pose.position.y - 1.5) < 1e-9 && std::abs(ball.pose.position.z - 0.75) < 1e-9;
  })) << "the sphere marker is at "
      << listener_.latest("_colliders", 0).pose.position.x;

  // The frame's publisher stops: after kFramePinTimeout (1 s) the sphere holds still where it was,
  // and the node warns (at most every 5 s) that the frame is not available.
  std::mutex log_mutex;
  std::vector<std::string> warnings;
  ros::NodeHandle nh;
  const ros::Subscriber rosout =
      nh.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::LogConstPtr& m) {
        std::lock_guard<std::mutex> lock(log_mutex);
        if (m->level == rosgraph_msgs::Log::WARN) warnings.push_back(m->msg);
      });
  const auto warned = [&] {
    std::lock_guard<std::mutex> lock(log_mutex);
    return std::any_of(warnings.begin(), warnings.end(), [](const std::string& w) {
      return w.find("sphere 'ball' follows frame 'ball_frame', which is not available: no new transform for") !=
                 std::string::npos &&
             w.find("it holds still") != std::string::npos;
    });
  };
  EXPECT_TRUE(listener_.waitFor(warned, 15.0)) << "no warning that the sphere's frame stopped";
  const Marker held = listener_.latest("_colliders", 0);
  EXPECT_EQ(held.action, Marker::ADD);
  EXPECT_NEAR(held.pose.position.x, -2.0, 1e-9);
  EXPECT_NEAR(held.pose.position.y, 1.5, 1e-9);
  EXPECT_NEAR(held.pose.position.z, 0.75, 1e-9);
}

TEST_F(ClothTest, BaraffWitkinClothSpawnsPublishesAndTakesItsConstants)
{
  SpawnCloth::Request req = clothRequest("bw", -2.0);
  req.model = "baraff_witkin";
  req.stretch_stiffness = 2000.0;  // per unit area [N/m]
  req.shear_stiffness = 100.0;
  req.bend_stiffness = 0.005;  // [N·m]
  req.bend_damping = 5e-5;
  req.max_strain = 0.0;
  const auto res = call<SpawnCloth>("spawn_cloth", req);
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_NE(res.message.find("baraff_witkin"), std::string::npos) << res.message;
  ASSERT_TRUE(listener_.waitFor([&] { return meshes_.has("bw"); }));
  expectConsistent(meshes_.latest("bw"), 30u, 40u);
  ASSERT_TRUE(listener_.waitFor([&] { return listener_.latest("bw", 1).action == Marker::ADD; }));
  EXPECT_EQ(listener_.latest("bw", 1).type, Marker::TRIANGLE_LIST);

  SetSpringConstants::Request k;
  k.body = "bw";
  k.spring_class = "shear";
  k.stiffness = 50.0;
  k.damping = 0.1;
  const auto set = call<SetSpringConstants>("set_spring_constants", k);
  EXPECT_TRUE(set.success) << set.message;
  EXPECT_NE(set.message.find("omega_max"), std::string::npos) << set.message;

  req.name = "bw_bad";
  req.model = "finite_elements";
  const auto refused = call<SpawnCloth>("spawn_cloth", req);
  EXPECT_FALSE(refused.success);
  EXPECT_NE(refused.message.find("model = 'finite_elements' is not a cloth model"), std::string::npos)
      << refused.message;
}

TEST_F(ClothTest, BadClothAndJellyRequestsAreRefusedNamingTheField)
{
  std::vector<std::pair<std::string, SpawnCloth::Request>> cloth(5, {"", clothRequest("bad", 3.0)});
  cloth[0].first = "nu = 1 is out of range";
  cloth[0].second.nu = 1;
  cloth[1].first = "must be non-zero and not parallel";
  cloth[1].second.edge_v = cloth[1].second.edge_u;
  cloth[2].first = "pins[0] = 'middle' is not a pin name";
  cloth[2].second.named_pins = {"middle"};
  cloth[3].first = "shear_stiffness = -3 is out of range";
  cloth[3].second.shear_stiffness = -3.0;
  cloth[4].first = "name = 'sheet' is already taken";
  cloth[4].second.name = "sheet";
  for (const auto& [expected, req] : cloth)
  {
    const auto res = call<SpawnCloth>("spawn_cloth", req);
    EXPECT_FALSE(res.success) << expected;
    EXPECT_NE(res.message.find(expected), std::string::npos) << "message: " << res.message;
  }
  std::vector<std::pair<std::string, SpawnJelly::Request>> jelly(3, {"", jellyRequest("bad_jelly")});
  jelly[0].first = "size[2] = 0 is out of range";
  jelly[0].second.size.z = 0.0;
  jelly[1].first = "velocity = [nan, 0, 0] is not finite";
  jelly[1].second.velocity.x = std::nan("");
  jelly[2].first = "integrator = 'leapfrog' is not an integrator";
  jelly[2].second.integrator = "leapfrog";
  for (const auto& [expected, req] : jelly)
  {
    const auto res = call<SpawnJelly>("spawn_jelly", req);
    EXPECT_FALSE(res.success) << expected;
    EXPECT_NE(res.message.find(expected), std::string::npos) << "message: " << res.message;
  }
  EXPECT_EQ(listener_.latest("bad", 1).action, -1);
}

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "particle_sim_cloth_test");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
