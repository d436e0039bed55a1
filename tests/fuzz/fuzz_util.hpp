#pragma once
// Shared by the fuzz targets: the input as a file (the readers under test take paths), and the
// one rule of every target: input errors are expected, anything else escapes and is a finding.
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace overstep::fuzz {

/// A scratch folder of this process, created once (removed at exit).
inline const std::filesystem::path& scratch() {
  static const std::filesystem::path dir = [] {
    std::string t = (std::filesystem::temp_directory_path() / "overstep-fuzz-XXXXXX").string();
    if (!::mkdtemp(t.data())) std::abort();
    return std::filesystem::path(t);
  }();
  static const struct Cleanup {
    ~Cleanup() {
      std::error_code ec;
      std::filesystem::remove_all(dir, ec);
    }
  } cleanup;
  return dir;
}

/// Writes `size` bytes to scratch()/name and returns its path.
inline std::string asFile(const std::uint8_t* data, std::size_t size, const std::string& name) {
  const std::filesystem::path p = scratch() / name;
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  return p.string();
}

inline void copyFile(const std::string& from, const std::string& name) {
  std::filesystem::copy_file(from, scratch() / name,
                             std::filesystem::copy_options::overwrite_existing);
}

}  // namespace overstep::fuzz
