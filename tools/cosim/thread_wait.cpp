#include "thread_wait.hpp"

#include <cstdlib>

namespace cosim::tool {

std::vector<EnvironmentSetting> thread_wait_settings(
    const std::function<const char*(const char*)>& lookup) {
  if (lookup("OMP_WAIT_POLICY") != nullptr || lookup("GOMP_SPINCOUNT") != nullptr) return {};
  return {{"OMP_WAIT_POLICY", "passive"}, {"GOMP_SPINCOUNT", kBoundedSpinCount}};
}

void set_thread_wait() {
  for (const auto& setting :
       thread_wait_settings([](const char* name) { return std::getenv(name); }))
    setenv(setting.name.c_str(), setting.value.c_str(), 0);
}

}  // namespace cosim::tool
