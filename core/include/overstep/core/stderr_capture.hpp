#pragma once
/// \file
/// What libraries print on the process's stderr while we call them (urdfdom and TinyXML on a bad
/// URDF, liblcm on a bus it cannot open), captured so that it can go into our one-line error
/// instead of adding lines of its own (issue 20).

#include <string>

namespace overstep::core {

/// `s` with every byte outside printable ASCII as \xNN (a message quoting it stays one line).
std::string printable(const std::string& s);

/// While alive, what is written to the process's stderr (fd 2, e.g. by liblcm or urdfdom) goes
/// into a temporary file instead; text() ends the capture and returns it. One at a time, from one
/// thread (the descriptor is process-wide).
class StderrCapture {
 public:
  StderrCapture();
  ~StderrCapture();
  StderrCapture(const StderrCapture&) = delete;
  StderrCapture& operator=(const StderrCapture&) = delete;
  /// Ends the capture (idempotent) and returns what was written (the first 64 kB) as one line:
  /// its lines trimmed, empty ones dropped, joined with "; ", other control bytes as \xNN.
  std::string text();

 private:
  int saved_ = -1;
  int file_ = -1;
  std::string text_;
};

}  // namespace overstep::core
