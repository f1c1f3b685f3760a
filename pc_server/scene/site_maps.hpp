#pragma once
// Which site map (world file) each robot is in, for the 3-D scene: the map of
// the route it was sent on (`inspect` with a route that names one), else the
// server's `site_map` for every robot. Loaded once per file. Thread-safe.
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "pc_server/scene/robot_scene.hpp"

namespace inspect::server::scene {

class SiteMaps {
 public:
  /// The map of every robot without one of its own ("" = none).
  void setDefault(const std::string& path);
  /// The robot's map from now on ("" = back to the default).
  void set(const std::string& robot, const std::string& path);
  /// The robot's map and a version that changes with it (0 = none); a file
  /// that does not load is logged once and treated as none.
  struct Entry {
    std::shared_ptr<const SiteMap> map;
    uint64_t version = 0;
  };
  Entry get(const std::string& robot);

 private:
  std::shared_ptr<const SiteMap> load(const std::string& path);
  std::mutex mu_;
  std::string default_;
  std::map<std::string, std::string> by_robot_;
  std::map<std::string, std::shared_ptr<const SiteMap>> cache_;  // path -> map (null: failed)
  std::map<std::string, uint64_t> versions_;                     // path -> its version
  uint64_t next_version_ = 1;
};

}  // namespace inspect::server::scene
