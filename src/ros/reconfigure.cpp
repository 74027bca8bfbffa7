#include "particle_sim/ros/reconfigure.h"

#include <utility>

#include "particle_sim/ros/material_conversions.h"
#include "particle_sim/ros/message_text.h"
#include "particle_sim/ros/spring_constants.h"

namespace particle_sim
{
namespace ros_interface
{
ReconfigureHandler::ReconfigureHandler(const ros::NodeHandle& private_node, core::World& world, NodeSettings& settings,
                                       core::IntegratorDef& default_integrator, std::function<void()> on_rate_changed)
    : world_(world),
      settings_(settings),
      default_integrator_(default_integrator),
      on_rate_changed_(std::move(on_rate_changed))
{
  // dynamic_reconfigure starts from the world as built (the scene's gravity, wind, ...) and the
  // parameters read at start: the config is pushed before the callback is set, so that the
  // callback's first call applies what is already there.
  server_ = std::make_unique<dynamic_reconfigure::Server<SimConfig>>(mutex_, private_node);
  config_ = currentConfig();
  server_->updateConfig(config_);
  server_->setCallback([this](SimConfig& config, std::uint32_t level) { reconfigure(config, level); });
}

void ReconfigureHandler::showWorld()
{
  config_ = currentConfig();
  server_->updateConfig(config_);
}

void ReconfigureHandler::showSpringConstants(const std::string& body, const std::string& spring_class, double stiffness,
                                             double damping)
{
  config_.body = body;
  config_.spring_class = spring_class;
  config_.stiffness = stiffness;
  config_.damping = damping;
  server_->updateConfig(config_);
}

void ReconfigureHandler::forgetBody(const std::string& body)
{
  if (config_.body != body) return;
  config_.body.clear();
  showWorld();
}

SimConfig ReconfigureHandler::currentConfig() const
{
  SimConfig config = config_;
  const core::Environment& env = world_.environment();
  config.gravity_x = env.gravity.x();
  config.gravity_y = env.gravity.y();
  config.gravity_z = env.gravity.z();
  config.global_damping = env.damping;
  config.wind_x = env.air.wind.x();
  config.wind_y = env.air.wind.y();
  config.wind_z = env.air.wind.z();
  config.real_time_factor = settings_.real_time_factor;
  config.rate = settings_.rate;
  config.integrator = core::toString(default_integrator_.type);
  config.rope_material = settings_.rope_material;
  config.cloth_material = settings_.cloth_material;
  // Show the first spring body, if there is one, so that rqt has something to edit.
  if (config.body.empty() || !world_.findSpringBody(config.body))
  {
    config.body.clear();
    for (const auto& body : world_.bodies())
    {
      if (body->kind() != core::BodyKind::SpringNetwork) continue;
      config.body = body->name();
      break;
    }
  }
  if (config.spring_class.empty()) config.spring_class = "stretch";
  if (!readSpringConstants(world_, config.body, config.spring_class, config.stiffness, config.damping) &&
      !readSpringConstants(world_, config.body, "all", config.stiffness, config.damping))
  {
    config.stiffness = 0.0;
    config.damping = 0.0;
  }
  return config;
}

void ReconfigureHandler::reconfigure(SimConfig& config, std::uint32_t level)
{
  // Runs in run()'s callAvailable(), between two steps. A value the world refuses is put back, so
  // rqt always shows what the simulation uses.
  auto refuse = [](const std::string& what, const core::Status& status) {
    ROS_WARN_NAMED("reconfigure", "%s refused: %s", what.c_str(), toMessageText(status.message).c_str());
  };
  if (level & 1u)
  {
    if (core::Status s = world_.setGravity({config.gravity_x, config.gravity_y, config.gravity_z}); !s)
    {
      refuse("gravity", s);
      config.gravity_x = config_.gravity_x, config.gravity_y = config_.gravity_y, config.gravity_z = config_.gravity_z;
    }
    if (core::Status s = world_.setGlobalDamping(config.global_damping); !s)
    {
      refuse("global_damping", s);
      config.global_damping = config_.global_damping;
    }
    if (core::Status s = world_.setWind({config.wind_x, config.wind_y, config.wind_z}); !s)
    {
      refuse("wind", s);
      config.wind_x = config_.wind_x, config.wind_y = config_.wind_y, config.wind_z = config_.wind_z;
    }
  }
  if (level & 2u)
  {
    settings_.real_time_factor = config.real_time_factor;
    if (config.rate != settings_.rate)
    {
      settings_.rate = config.rate;
      on_rate_changed_();
    }
  }
  if (level & 4u)
  {
    core::IntegratorType type;
    if (core::parseIntegratorType(config.integrator, type))
      default_integrator_.type = type;
    else
    {
      refuse("integrator", core::Status::failure("integrator = " + quoteName(config.integrator) +
                                                 " is not an integrator; allowed: " + core::integratorTypeNames()));
      config.integrator = config_.integrator;
    }
  }
  if (level & 8u)
  {
    // New constants are applied to the body shown; choosing another body or class (constants
    // unchanged) shows that one's constants.
    const bool constants_changed = config.stiffness != config_.stiffness || config.damping != config_.damping;
    const bool selection_changed = config.body != config_.body || config.spring_class != config_.spring_class;
    if (constants_changed && !config.body.empty())
    {
      const core::Status s =
          applySpringConstants(world_, config.body, config.spring_class, config.stiffness, config.damping);
      if (s)
        ROS_INFO_NAMED("reconfigure", "%s", s.message.c_str());
      else
      {
        refuse("spring constants", s);
        config.body = config_.body, config.spring_class = config_.spring_class;
        config.stiffness = config_.stiffness, config.damping = config_.damping;
      }
    }
    else if (selection_changed && !config.body.empty())
    {
      if (!readSpringConstants(world_, config.body, config.spring_class, config.stiffness, config.damping))
      {
        refuse("body", core::Status::failure("body = " + quoteName(config.body) + " has no " + config.spring_class +
                                             " springs (or is not a rope, cloth, jelly or spring network)"));
        config.body = config_.body, config.spring_class = config_.spring_class;
      }
    }
  }
  if (level & 16u)
  {
    // Default materials of spawned ropes and cloth: a preset's name or empty.
    if (core::Status s = checkRopePresetName("rope_material", config.rope_material); s)
      settings_.rope_material = config.rope_material;
    else
    {
      refuse("rope_material", s);
      config.rope_material = config_.rope_material;
    }
    if (core::Status s = checkClothPresetName("cloth_material", config.cloth_material); s)
      settings_.cloth_material = config.cloth_material;
    else
    {
      refuse("cloth_material", s);
      config.cloth_material = config_.cloth_material;
    }
  }
  config_ = config;
}

}  // namespace ros_interface
}  // namespace particle_sim
