// rostest: the node's ROS API as a contract (README "The node"): every topic it publishes with
// its type, every service it provides, its parameters, all under its namespace; /clock only when
// ~publish_clock; /use_sim_time never written by the node. Run against the node, the nodelet and
// each instance of launch/multi.launch.
//
// Private parameters of this test: ns (the simulator's namespace, e.g. /particle_sim), node (the
// process that publishes: the node, or the nodelet manager), frame_id (expected in its messages),
// publishes_clock (bool), use_sim_time_set (whether the launch file sets /use_sim_time).

#include <gtest/gtest.h>
#include <ros/master.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>
#include <xmlrpcpp/XmlRpc.h>

#include <map>
#include <set>
#include <string>

#include "sim_probe.h"

using particle_sim_test::waitForWall;

namespace
{
std::string param(const std::string& name, const std::string& fallback)
{
  std::string value;
  return ros::param::get("~" + name, value) ? value : fallback;
}

// The master's graph: who publishes which topic and who provides which service.
struct Graph
{
  std::map<std::string, std::set<std::string>> publishers, services;
  std::map<std::string, std::string> types;
};

Graph graph()
{
  Graph g;
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  EXPECT_TRUE(ros::master::execute("getSystemState", args, result, payload, true));
  auto collect = [](XmlRpc::XmlRpcValue& list, std::map<std::string, std::set<std::string>>& out) {
    for (int i = 0; i < list.size(); ++i)
      for (int j = 0; j < list[i][1].size(); ++j)
        out[static_cast<std::string>(list[i][0])].insert(static_cast<std::string>(list[i][1][j]));
  };
  collect(payload[0], g.publishers);
  collect(payload[2], g.services);
  ros::master::V_TopicInfo topics;
  EXPECT_TRUE(ros::master::getTopics(topics));
  for (const auto& t : topics)
    g.types[t.name] = t.datatype;
  return g;
}
}  // namespace

TEST(ApiContract, TopicsServicesAndParametersUnderTheNamespace)
{
  const std::string ns = param("ns", "/particle_sim");
  const std::string node = param("node", ns);
  bool publishes_clock = true, use_sim_time_set = false;
  ros::param::get("~publishes_clock", publishes_clock);
  ros::param::get("~use_sim_time_set", use_sim_time_set);
  ASSERT_TRUE(ros::service::waitForService(ns + "/set_parameters", ros::Duration(60.0)));
  // dynamic_reconfigure advertises its service before it writes its parameters, and services come
  // before the first tick: wait until the node has done all that.
  ASSERT_TRUE(waitForWall(
      [&] {
        const Graph g = graph();
        return g.publishers.count("/diagnostics") && g.publishers.at("/diagnostics").count(node) &&
               ros::param::has(ns + "/damping");
      },
      30.0));
  const Graph g = graph();

  const std::map<std::string, std::string> topics = {
      {ns + "/markers", "visualization_msgs/MarkerArray"},
      {ns + "/meshes", "particle_sim/ClothMesh"},
      {ns + "/status", "particle_sim/SimStatus"},
      {ns + "/points", "sensor_msgs/PointCloud2"},
      {ns + "/parameter_descriptions", "dynamic_reconfigure/ConfigDescription"},
      {ns + "/parameter_updates", "dynamic_reconfigure/Config"},
      {"/diagnostics", "diagnostic_msgs/DiagnosticArray"},
      {"/tf", "tf2_msgs/TFMessage"},
  };
  for (const auto& [topic, type] : topics)
  {
    EXPECT_EQ(g.publishers.count(topic) ? g.publishers.at(topic).count(node) : 0u, 1u)
        << node << " does not publish " << topic;
    EXPECT_EQ(g.types.count(topic) ? g.types.at(topic) : "", type) << topic;
  }
  const bool clock = g.publishers.count("/clock") && g.publishers.at("/clock").count(node);
  EXPECT_EQ(clock, publishes_clock) << "/clock publisher";
  if (publishes_clock)
  {
    EXPECT_EQ(g.types.at("/clock"), "rosgraph_msgs/Clock");
  }

  // Nothing else of ours outside the namespace (everything relative or private). Only for a node
  // of its own: a nodelet manager publishes for the other nodelets too.
  for (const auto& [topic, nodes] : g.publishers)
  {
    if (node != ns || !nodes.count(node)) continue;
    const bool ours = topic.rfind(ns + "/", 0) == 0 || topic == "/clock" || topic == "/diagnostics" || topic == "/tf" ||
                      topic == "/rosout";
    EXPECT_TRUE(ours) << node << " publishes " << topic << " outside " << ns;
  }

  for (const char* s :
       {"spawn_emitter", "spawn_rope", "spawn_cloth", "spawn_jelly", "remove_body", "reset", "pause_physics",
        "unpause_physics", "step", "pin_particle", "unpin_particle", "set_spring_constants", "set_wind",
        "set_parameters", "grasp", "release", "spawn_collider", "remove_collider"})
  {
    const std::string service = ns + "/" + s;
    EXPECT_EQ(g.services.count(service) ? g.services.at(service).count(node) : 0u, 1u)
        << node << " does not provide " << service;
  }

  // Parameters: dynamic_reconfigure keeps the live ones on the parameter server, under ns.
  for (const char* p : {"rate", "real_time_factor", "gravity_x", "gravity_y", "gravity_z", "global_damping", "wind_x",
                        "wind_y", "wind_z", "integrator", "body", "spring_class", "stiffness", "damping"})
    EXPECT_TRUE(ros::param::has(ns + "/" + p)) << ns << "/" << p;
  double gravity_z = 0.0;
  EXPECT_TRUE(ros::param::get(ns + "/gravity_z", gravity_z));
  EXPECT_DOUBLE_EQ(gravity_z, -9.81);
  // The node never sets /use_sim_time: only a launch file does.
  EXPECT_EQ(ros::param::has("/use_sim_time"), use_sim_time_set);

  // Its messages are in its own frame.
  const std::string frame_id = param("frame_id", "world");
  auto markers = ros::topic::waitForMessage<visualization_msgs::MarkerArray>(ns + "/markers", ros::Duration(30.0));
  ASSERT_TRUE(markers);
  ASSERT_FALSE(markers->markers.empty());
  for (const auto& m : markers->markers)
    EXPECT_EQ(m.header.frame_id, frame_id) << m.ns;
  auto status = ros::topic::waitForMessage<particle_sim::SimStatus>(ns + "/status", ros::Duration(30.0));
  ASSERT_TRUE(status);
  EXPECT_EQ(status->header.frame_id, frame_id);
  EXPECT_FALSE(status->bodies.empty());
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "api_test");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
