// Files a test writes: a fresh directory per test process, removed at exit.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace laser_raycast_test {

struct TempDir {
  TempDir()
      : path(std::filesystem::temp_directory_path() /
             ("laser_raycast_test_" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::filesystem::path path;
};

inline const std::filesystem::path& tempDir() {
  static const TempDir dir;
  return dir.path;
}

// Writes content to name in tempDir(); returns its path.
inline std::string writeFile(const std::string& name, const std::string& content) {
  const std::filesystem::path path = tempDir() / name;
  std::ofstream(path, std::ios::binary) << content;
  return path.string();
}

}  // namespace laser_raycast_test
