// Where the tests find the real third-party scene of ../shared/data (beside the clone), and what
// they do without it: skip, unless LASER_RAYCAST_REQUIRE_SHARED_DATA=1 (CI) makes its absence a
// failure. The including target defines LASER_RAYCAST_SOURCE_DIR (the package's source directory).
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace laser_raycast_test {

// The tb3_world_data directory: under $LASER_RAYCAST_SHARED_DATA if set, else ../shared/data.
inline std::string tb3WorldData() {
  const char* env = std::getenv("LASER_RAYCAST_SHARED_DATA");
  const std::string root =
      env && *env ? std::string(env) : std::string(LASER_RAYCAST_SOURCE_DIR) + "/../shared/data";
  return root + "/tb3_world_data";
}

inline bool sharedDataRequired() {
  const char* env = std::getenv("LASER_RAYCAST_REQUIRE_SHARED_DATA");
  return env && std::string(env) == "1";
}

}  // namespace laser_raycast_test

// At the top of a test that needs the data.
#define REQUIRE_SHARED_DATA()                                                                  \
  do {                                                                                         \
    const std::string data_dir_ = laser_raycast_test::tb3WorldData();                          \
    if (!std::filesystem::exists(data_dir_ + "/urdf/turtlebot3_world.urdf")) {                 \
      if (laser_raycast_test::sharedDataRequired())                                            \
        FAIL() << "shared data missing at " << data_dir_;                                      \
      GTEST_SKIP() << "no shared data at " << data_dir_ << " (set LASER_RAYCAST_SHARED_DATA)"; \
    }                                                                                          \
  } while (0)
