// Dragging a particle with rviz's mouse (ros/dragging.h), without rviz: the click picks the nearest
// free particle, the pin follows the marker's displacement, mouse up lets go with its velocity.

#include "particle_sim/ros/dragging.h"

#include <gtest/gtest.h>

using namespace particle_sim;
using ros_interface::DragEvent;
using ros_interface::Dragging;

namespace
{
core::World makeWorld()
{
  core::WorldDef def;
  def.ground.enabled = false;
  def.dt = 0.01;
  core::World world{def};
  core::RopeDef rope;
  rope.name = "line";
  rope.particles = 11;
  rope.start = {0.0, 0.0, 2.0};
  rope.end = {1.0, 0.0, 2.0};
  rope.stretch_stiffness = 500.0;
  rope.pins = {0, -1};
  EXPECT_TRUE(world.addRope(rope).ok);
  return world;
}

DragEvent event(DragEvent::Type type, const std::string& body, const Eigen::Vector3d& marker,
                const Eigen::Vector3d& mouse = Eigen::Vector3d::Zero(), bool has_mouse = false)
{
  DragEvent e;
  e.type = type;
  e.body = body;
  e.marker_position = marker;
  e.mouse_point = mouse;
  e.has_mouse_point = has_mouse;
  return e;
}
}  // namespace

TEST(Dragging, ClickPinsTheNearestFreeParticleThatThenFollowsTheMarkerUntilMouseUp)
{
  core::World world = makeWorld();
  const core::SpringNetworkBody& rope = *world.findSpringBody("line");
  Dragging drag;
  // A click 3 cm from particle 4 (at x = 0.4): it is pinned where it is.
  const Eigen::Vector3d x4 = rope.particles().position.col(4);
  EXPECT_EQ(drag.apply(world, event(DragEvent::Type::Down, "line", Eigen::Vector3d::Zero(),
                                    x4 + Eigen::Vector3d(0.03, 0.0, 0.0), true)),
            "dragging particle 4 of 'line'");
  ASSERT_TRUE(drag.active());
  EXPECT_EQ(drag.index(), 4);
  EXPECT_TRUE(rope.isPinned(4));
  EXPECT_EQ(rope.pinnedCount(), 3);

  // The marker moves by d: the particle is at x4 + d by the end of the next step.
  const Eigen::Vector3d d(0.1, 0.2, 0.3);
  EXPECT_EQ(drag.apply(world, event(DragEvent::Type::Move, "line", d)), "");
  EXPECT_EQ(drag.apply(world, event(DragEvent::Type::Move, "other", 5.0 * d)), "") << "another body's marker";
  world.step();
  EXPECT_LT((rope.particles().position.col(4) - (x4 + d)).norm(), 1e-9);

  // Mouse up: free again, moving on.
  EXPECT_EQ(drag.apply(world, event(DragEvent::Type::Up, "line", d)), "let go of particle 4 of 'line'");
  EXPECT_FALSE(drag.active());
  EXPECT_FALSE(rope.isPinned(4));
  EXPECT_EQ(rope.pinnedCount(), 2);
  EXPECT_EQ(drag.apply(world, event(DragEvent::Type::Up, "line", d)), "") << "nothing dragged";
}

TEST(Dragging, PinnedParticlesAreNotPickedAndUnknownBodiesDoNothing)
{
  core::World world = makeWorld();
  Dragging drag;
  // A click on the pinned end (particle 0): the nearest free particle, 1, is picked.
  const Eigen::Vector3d x0 = world.findSpringBody("line")->particles().position.col(0);
  drag.apply(world, event(DragEvent::Type::Down, "line", Eigen::Vector3d::Zero(), x0, true));
  EXPECT_EQ(drag.index(), 1);
  // A second down ends the first drag.
  drag.apply(world, event(DragEvent::Type::Down, "line", Eigen::Vector3d::Zero(), x0, true));
  EXPECT_EQ(drag.index(), 1);
  EXPECT_EQ(world.findSpringBody("line")->pinnedCount(), 3);
  EXPECT_EQ(drag.apply(world, event(DragEvent::Type::Down, "nobody", Eigen::Vector3d::Zero())), "");
  EXPECT_FALSE(drag.active()) << "a down on an unknown body ends the drag and starts none";
  EXPECT_EQ(world.findSpringBody("line")->pinnedCount(), 2);
  // A body removed while dragged: forgotten.
  drag.apply(world, event(DragEvent::Type::Down, "line", Eigen::Vector3d::Zero(), x0, true));
  ASSERT_TRUE(world.removeBody("line").ok);
  drag.forget("line");
  EXPECT_FALSE(drag.active());
}
