#include "overstep/core/stderr_capture.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <iostream>

namespace overstep::core {
namespace {}  // namespace

StderrCapture::StderrCapture() {
  std::fflush(stderr);
  std::cerr.flush();
  std::error_code ec;
  std::string tmpl = (std::filesystem::temp_directory_path(ec) / "overstep-stderr-XXXXXX").string();
  file_ = ::mkstemp(tmpl.data());
  if (file_ < 0) return;  // nothing captured: the text goes to stderr as before
  ::unlink(tmpl.c_str());
  saved_ = ::dup(STDERR_FILENO);
  if (saved_ < 0 || ::dup2(file_, STDERR_FILENO) < 0) {
    if (saved_ >= 0) ::close(saved_);
    ::close(file_);
    saved_ = file_ = -1;
  }
}

StderrCapture::~StderrCapture() { text(); }

std::string StderrCapture::text() {
  if (saved_ < 0) return text_;
  std::fflush(stderr);
  std::cerr.flush();
  ::dup2(saved_, STDERR_FILENO);
  ::close(saved_);
  saved_ = -1;
  std::string raw;
  if (::lseek(file_, 0, SEEK_SET) == 0) {
    char buf[4096];
    ssize_t n;
    while (raw.size() < (1u << 16) && (n = ::read(file_, buf, sizeof buf)) > 0)
      raw.append(buf, static_cast<std::size_t>(n));
  }
  ::close(file_);
  file_ = -1;
  std::string out, line;
  raw += '\n';
  for (const char c : raw) {
    if (c != '\n') {
      line += c;
      continue;
    }
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
    std::size_t lead = 0;
    while (lead < line.size() && std::isspace(static_cast<unsigned char>(line[lead]))) ++lead;
    if (lead < line.size()) out += (out.empty() ? "" : "; ") + line.substr(lead);
    line.clear();
  }
  text_ = printable(out);
  return text_;
}

std::string printable(const std::string& s) {
  static const char* const hex = "0123456789abcdef";
  std::string out;
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c >= 0x20 && c < 0x7f) {
      out += ch;
    } else {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out;
}

}  // namespace overstep::core
