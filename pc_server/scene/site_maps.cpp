#include "pc_server/scene/site_maps.hpp"

#include "shared/util/log.hpp"
#include "shared/world/world.hpp"

namespace inspect::server::scene {

void SiteMaps::setDefault(const std::string& path) {
  std::lock_guard lk(mu_);
  default_ = path;
}

void SiteMaps::set(const std::string& robot, const std::string& path) {
  std::lock_guard lk(mu_);
  if (path.empty()) by_robot_.erase(robot);
  else by_robot_[robot] = path;
}

std::shared_ptr<const SiteMap> SiteMaps::load(const std::string& path) {
  if (const auto it = cache_.find(path); it != cache_.end()) return it->second;
  std::shared_ptr<const SiteMap> m;
  try {
    m = std::make_shared<const SiteMap>(siteMapOf(world::loadWorldFile(path)));
  } catch (const std::exception& e) {
    log::warn("scene", "site map ", path, " not drawn: ", e.what());
  }
  cache_[path] = m;
  versions_[path] = next_version_++;
  return m;
}

SiteMaps::Entry SiteMaps::get(const std::string& robot) {
  std::lock_guard lk(mu_);
  const auto it = by_robot_.find(robot);
  const std::string path = it != by_robot_.end() ? it->second : default_;
  if (path.empty()) return {};
  auto m = load(path);
  if (!m) return {};
  return {m, versions_[path]};
}

}  // namespace inspect::server::scene
