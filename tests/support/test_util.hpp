#pragma once
// Helpers shared by the tests: paths into the source tree and scratch directories.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace overstep::test {

inline std::string dataDir() { return std::string(OVERSTEP_DATA_DIR); }
inline std::string hrp2Yaml() { return dataDir() + "/robots/hrp2/hrp2.yaml"; }
inline std::string hrp2Urdf() { return dataDir() + "/robots/hrp2/hrp2.urdf"; }
inline std::string twoLinkYaml() { return dataDir() + "/tests/data/two_link.yaml"; }

inline std::string slurp(const std::string& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void writeText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

/// Replaces the first occurrence of `from` (which must exist) in `text`.
inline std::string replaceOnce(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << "fixture edit: '" << from << "' not found";
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

/// A fresh scratch directory, removed at destruction.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            ("overstep_" + std::string(info ? info->name() : "t") + "_" +
             std::to_string(std::random_device{}()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

}  // namespace overstep::test
