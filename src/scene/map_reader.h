#pragma once
// Strict reading of YAML mappings for scene files (private to the scene layer).

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <map>
#include <set>
#include <string>
#include <type_traits>

#include "particle_sim/core/status.h"
#include "particle_sim/core/validation.h"

namespace particle_sim
{
namespace scene
{
using core::Status;

// A scene error carries its own message; thrown only inside the scene layer and turned into a Status
// by parseScene(), so it never crosses the layer.
struct SceneError
{
  std::string message;
};

inline std::string location(const std::string& source, const YAML::Node& node)
{
  const YAML::Mark mark = node.Mark();
  if (mark.line < 0) return source + ": ";
  return source + ":" + std::to_string(mark.line + 1) + ": ";
}

// Reads the keys of one YAML mapping, checking types, and refuses any key it was not asked for.
class MapReader
{
public:
  MapReader(const YAML::Node& node, std::string path, const std::string& source)
      : node_(node), path_(std::move(path)), source_(source)
  {
    if (!node_.IsMap()) fail(node_, path_ + " must be a mapping of key: value");
    // yaml-cpp keeps both entries of a repeated key and lets one win silently: refuse it here.
    std::map<std::string, int> first_line;
    for (const auto& entry : node_)
    {
      const std::string key = entry.first.Scalar();
      const auto [where, inserted] = first_line.emplace(key, entry.first.Mark().line + 1);
      if (!inserted)
        fail(entry.first, field(key) + " is given twice (first on line " + std::to_string(where->second) +
                              "): each key may appear once");
    }
  }

  // Whether `key` is present. Asking makes it an accepted key (listed by finish()).
  bool has(const std::string& key)
  {
    known_.insert(key);
    return static_cast<bool>(node_[key]);
  }

  template <typename T>
  void read(const std::string& key, T& value)
  {
    known_.insert(key);
    const YAML::Node child = node_[key];
    if (!child) return;
    value = convert<T>(child, field(key));
  }

  void read(const std::string& key, Eigen::Vector3d& value)
  {
    known_.insert(key);
    const YAML::Node child = node_[key];
    if (!child) return;
    if (!child.IsSequence() || child.size() != 3)
      fail(child, field(key) + " = " + text(child) + " must be a list of 3 numbers [x, y, z]");
    for (int i = 0; i < 3; ++i)
      value[i] = convert<double>(child[i], field(key) + "[" + std::to_string(i) + "]");
  }

  template <typename T>
  void require(const std::string& key, T& value)
  {
    if (!has(key)) fail(node_, path_ + " needs the key '" + key + "'");
    read(key, value);
  }

  YAML::Node child(const std::string& key)
  {
    known_.insert(key);
    return node_[key];
  }

  // Refuses every key that no read(), child() or has() asked for, listing exactly those: the
  // message and the check come from the same set.
  void finish() const
  {
    for (const auto& entry : node_)
    {
      const std::string key = entry.first.Scalar();
      if (known_.count(key)) continue;
      std::string allowed;
      for (const std::string& k : known_)
        allowed += (allowed.empty() ? "" : ", ") + k;
      fail(entry.first, field(key) + " is not a known key; allowed keys: " + allowed);
    }
  }

  std::string field(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  const YAML::Node& node() const { return node_; }
  [[noreturn]] void fail(const YAML::Node& at, const std::string& message) const
  {
    throw SceneError{location(source_, at) + message};
  }

private:
  static std::string text(const YAML::Node& node)
  {
    if (node.IsScalar()) return core::quoteReceived(node.Scalar());  // cut, valid UTF-8
    YAML::Emitter out;
    out << YAML::Flow << node;
    return out.c_str();
  }

  template <typename T>
  T convert(const YAML::Node& child, const std::string& name) const
  {
    if (!child.IsScalar()) fail(child, name + " = " + text(child) + " must be " + typeName<T>());
    try
    {
      return child.as<T>();
    }
    catch (const YAML::Exception&)
    {
      fail(child, name + " = " + text(child) + " must be " + typeName<T>());
    }
  }

  template <typename T>
  static const char* typeName()
  {
    if constexpr (std::is_same_v<T, bool>)
      return "true or false";
    else if constexpr (std::is_same_v<T, std::string>)
      return "a string";
    else if constexpr (std::is_floating_point_v<T>)
      return "a number";
    else if constexpr (std::is_unsigned_v<T>)
      return "a non-negative integer";
    else
      return "an integer";
  }

  YAML::Node node_;
  std::string path_;
  const std::string& source_;
  std::set<std::string> known_;
};

}  // namespace scene
}  // namespace particle_sim
